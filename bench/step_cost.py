"""What a step costs beyond the tool's nodes: the ends (striker, contact, medium), the energy audit
and the records, and what a run costs before its first step, per preset.

    .venv/bin/python bench/step_cost.py [--repeats 10] [--cells 5 64 512]

Each preset runs on the explicit scheme at Courant number 1 (the default accuracy's grids), a
summary's outputs only, over its duration and a quarter of it (fig5, fig6 and the pile, whose
durations are long) or five times it (the others): the difference over the difference in steps is
the cost of a step, the rest the run's fixed cost. Where a step costs more in one part of the run
than another (the pile's helmet while it is pressed), the step's cost is that of the longer run's
last part and the fixed cost means nothing: it is not printed. On 5 cells a step is almost all ends; the interior's share
grows with the cells (about 1.3 ns a node on this machine, `bench/kernel.py`). Least of the
repeats.
"""

from __future__ import annotations

import argparse
import time

from percussim.solver.case import parse_case
from percussim.solver.controller import simulate_rod, warm_up
from percussim.solver.grid import explicit_numerics, fewest_cells
from percussim.solver.presets import preset_json
from percussim.testing import merge

PRESETS = ("fig3", "fig5", "fig9", "rock_drill", "pile")
# the pile's parts: what its helmet and its shaft cost a step
PARTS = {"pile without its shaft": ("pile", "shaft"), "pile without its helmet": ("pile", "anvil")}
LONG = ("fig5", "fig6", "pile")  # their durations are long already: a quarter of it is the short run


def least_time(case, numerics, repeats: int) -> float:
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        simulate_rod(case, numerics=numerics)
        best = min(best, time.perf_counter() - start)
    return best


def cost(name: str, cells: int, repeats: int) -> tuple[int, float, float]:
    """(cells, ns a step, ms a run before its steps) of preset `name` (or one of `PARTS`) on
    `cells` cells (or the fewest its striker takes)."""
    preset, left_out = PARTS.get(name, (name, None))
    data = {k: v for k, v in preset_json(preset).items() if k != left_out}
    base = parse_case(merge(data, {"numerics": {"cells": None, "time_step": None, "gamma": None}}))
    cells = max(cells, fewest_cells(base))
    factors = (0.25, 1.0) if preset in LONG else (1.0, 5.0)
    found = []
    for factor in factors:
        case = base.model_copy(
            update={"numerics": base.numerics.model_copy(update={"duration": base.numerics.duration * factor})}
        )
        numerics = explicit_numerics(case, cells)
        case = case.summary_only()
        found.append((numerics.steps, least_time(case, numerics, repeats)))
    (short_steps, short), (long_steps, long) = found
    per_step = (long - short) / (long_steps - short_steps)
    return cells, per_step * 1e9, (long - per_step * long_steps) * 1e3


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeats", type=int, default=10)
    parser.add_argument("--cells", type=int, nargs="+", default=[5, 64, 512])
    args = parser.parse_args()
    warm_up()
    print(f"{'preset':24s} {'cells':>6s} {'a step':>10s} {'a run, fixed':>14s}")
    for name in PRESETS + tuple(PARTS):
        for cells in args.cells:
            used, step, fixed = cost(name, cells, args.repeats)
            shown = f"{fixed:11.3f} ms" if fixed >= 0.0 else f"{'—':>14s}"
            print(f"{name:24s} {used:6d} {step:8.0f} ns {shown}")


if __name__ == "__main__":
    main()
