"""A hammer at work's cost: the `rock_drill_cycle` preset at the default accuracy (1%) with 10 and
100 cycles, on one core, its result streamed to HDF5 as a queued job's is.

    .venv/bin/python bench/cycle_speed.py [--counts 10,100] [--parts] [--truth]

Each count runs in a fresh process, the kernel compiled beforehand: its wall time, the grids of its
ladder, and its peak resident set size (`ru_maxrss`), which stays flat as the cycles grow when
the run's memory is O(cells) (the records go to the file as they are made). The goal: 100 cycles
in 1 s or less.

--parts: each of the ladder's runs of the 100 cycles on its own, in memory, least of 3: its time
and what of it the kernel's `advance` took (the rest is Python around the blows and flights).
--truth: the 10 cycles' quantities on each grid of the ladder against a run on 13,312 cells.
"""

from __future__ import annotations

import argparse
import json
import math
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

GOAL_SECONDS = 1.0


def one(count: int) -> dict:
    """The preset with `count` cycles, solved and streamed here (run in a child process)."""
    from percussim.solver.case import parse_case
    from percussim.solver.controller import warm_up
    from percussim.solver.presets import preset_json
    from percussim.solver.simulate import simulate

    warm_up()
    case = parse_case(preset_json("rock_drill_cycle") | {"cycles": {"count": count}})
    with tempfile.TemporaryDirectory() as folder:
        start = time.perf_counter()
        summary = simulate(case, result_path=Path(folder) / "result.h5").summary
        seconds = time.perf_counter() - start
        size = (Path(folder) / "result.h5").stat().st_size
    return {
        "count": count,
        "seconds": seconds,
        "grids": [run["cells"] for run in summary["runs"]],
        "worst": summary["error_estimate"]["worst"],
        "warnings": summary["warnings"],
        "file_mb": size / 1e6,
        "peak_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
    }


def preset_cycles(count: int):
    """The preset at the default accuracy with `count` cycles."""
    from percussim.solver.case import parse_case
    from percussim.testing import at_default_accuracy

    return parse_case(at_default_accuracy("rock_drill_cycle") | {"cycles": {"count": count}})


LADDER = (26, 52, 104, 208, 416, 832)  # the preset's grids at the default accuracy
QUANTITIES = (
    "max_compressive_stress",
    "max_tensile_stress",
    "peak_contact_force",
    "set",
    "cycle.impact_velocity",
    "cycle.impact_energy",
    "cycle.frequency",
    "cycle.efficiency",
)


def parts() -> None:
    from percussim.solver import kernel as K
    from percussim.solver.controller import simulate_rod, warm_up
    from percussim.solver.grid import explicit_numerics

    warm_up()
    case = preset_cycles(100)
    spent = [0.0]
    advance = K.advance

    def timed(*args):
        start = time.perf_counter()
        out = advance(*args)
        spent[0] += time.perf_counter() - start
        return out

    K.advance = timed
    for cells in LADDER:
        # as the ladder runs them: only the result records its long outputs (`adaptive.records_long_outputs`)
        run_case = case if cells == LADDER[-1] else case.summary_only()
        numerics = explicit_numerics(run_case, cells)
        best = (math.inf, 0.0)
        for _ in range(3):
            spent[0] = 0.0
            start = time.perf_counter()
            simulate_rod(run_case, numerics=numerics)
            best = min(best, (time.perf_counter() - start, spent[0]))
        print(
            f"{cells:5d} cells, {numerics.steps} steps: {best[0] * 1e3:6.1f} ms, the kernel {best[1] * 1e3:6.1f} ms "
            f"({best[1] / numerics.steps * 1e9:.0f} ns a step)"
        )


def truth() -> None:
    from percussim.solver.controller import simulate_rod, warm_up
    from percussim.solver.grid import explicit_numerics

    warm_up()
    case = preset_cycles(10).summary_only()

    def value(summary: dict, name: str) -> float:
        for key in name.split("."):
            summary = summary[key]
        summary = summary["value"] if isinstance(summary, dict) else summary
        return summary[-1] if isinstance(summary, list) else summary

    fine = simulate_rod(case, numerics=explicit_numerics(case, 13_312)).summary
    print("cells  " + "  ".join(f"{q.split('.')[-1][:14]:>14}" for q in QUANTITIES))
    for cells in LADDER:
        summary = simulate_rod(case, numerics=explicit_numerics(case, cells)).summary
        errors = [value(summary, q) / value(fine, q) - 1 for q in QUANTITIES]
        print(f"{cells:5d}  " + "  ".join(f"{e:+14.1e}" for e in errors))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--counts", default="10,100")
    parser.add_argument("--child", type=int, help=argparse.SUPPRESS)
    parser.add_argument("--parts", action="store_true", help="each grid's run of the 100 cycles, timed apart")
    parser.add_argument("--truth", action="store_true", help="each grid's error against 13,312 cells")
    args = parser.parse_args()
    if args.parts or args.truth:
        parts() if args.parts else truth()
        return
    if args.child:
        print(json.dumps(one(args.child)))
        return
    for count in (int(c) for c in args.counts.split(",")):
        out = subprocess.run(
            [sys.executable, __file__, "--child", str(count)], capture_output=True, text=True, check=True
        ).stdout
        r = json.loads(out.strip().splitlines()[-1])
        print(
            f"{r['count']:4d} cycles: {r['seconds']:7.2f} s ({r['seconds'] / r['count'] * 1e3:.0f} ms a cycle; goal "
            f"{GOAL_SECONDS:g} s for 100), grids {', '.join(map(str, r['grids']))}, estimated error {r['worst']:.1e}, "
            f"peak memory {r['peak_mb']:.0f} MB, result file {r['file_mb']:.1f} MB"
        )
        for warning in r["warnings"]:
            print(f"      warning: {warning}")


if __name__ == "__main__":
    main()
