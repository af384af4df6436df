"""Every preset at the default accuracy (1%): the least time of several runs after compilation,
against the goal of 5 ms for a single blow, with its grids and what bounds them.

    .venv/bin/python bench/preset_speed.py [--repeats 20] [--set MIN_STEP=2 ...]

For each preset: the time (`percussim.simulate`, one process), the grids of its ladder, the work
(node-steps over all of them) and the share of it on the finest grid, its estimated error, whether
it met the tolerance, and what a step costs on its finest grid. A preset of many blows or cycles
is timed all the same, marked as such: its goal is its own issue's. `bench/matrix.py` gives the
paper's presets' true errors beside their times; `bench/step_cost.py` what a step costs.

`--set NAME=VALUE` runs the presets under a setting of the ladder or its estimate, one constant of
`solver.accuracy`, `solver.adaptive` or `solver.grid` changed as `bench/ladder_trade.py` changes it
on the matrix: what the setting costs where a preset's ladder ends.
"""

from __future__ import annotations

import argparse
import math
import time

from ladder_trade import apply

from percussim.solver.controller import warm_up
from percussim.solver.presets import preset_names
from percussim.solver.simulate import simulate
from percussim.testing import at_default_accuracy

GOAL_MS = 5.0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeats", type=int, default=20)
    parser.add_argument("--set", action="append", default=[], metavar="NAME=VALUE", help="a ladder constant")
    args = parser.parse_args()
    settings = dict(item.split("=", 1) for item in args.set)
    apply({name: float(value) for name, value in settings.items()})
    if settings:
        print("setting:", ", ".join(args.set))
    warm_up()
    print(
        f"{'preset':18s} {'time':>9s} {'/ 5 ms':>7s} {'node-steps':>11s} {'finest':>7s} {'per step':>9s} "
        f"{'estimate':>9s}  grids"
    )
    for name in preset_names():
        case = at_default_accuracy(name)
        summary = simulate(case).summary
        best = math.inf
        for _ in range(args.repeats):
            start = time.perf_counter()
            simulate(case)
            best = min(best, time.perf_counter() - start)
        runs = summary["runs"]
        work = [(r["cells"] + 1) * (r["steps"] + 1) for r in runs]
        many = case.get("blows") or case.get("cycles")
        met = "" if not any("not met" in w for w in summary["warnings"]) else " not met"
        print(
            f"{name:18s} {best * 1e3:7.2f}ms {best * 1e3 / GOAL_MS:6.1f}× {sum(work):11.3g} "
            f"{work[-1] / sum(work):6.0%} {best / sum(r['steps'] for r in runs) * 1e9:7.0f}ns "
            f"{summary['error_estimate']['worst']:9.1e}  {', '.join(str(r['cells']) for r in runs)}"
            f"{met}{'  (many blows or cycles)' if many else ''}"
        )


if __name__ == "__main__":
    main()
