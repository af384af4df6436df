"""A hammer at work's cost: the `rock_drill_cycle` preset at the default accuracy (1%) with 10 and
100 cycles, on one core, its result streamed to HDF5 as a queued job's is.

    .venv/bin/python bench/cycle_speed.py [--counts 10,100]

Each count runs in a fresh process, the kernel compiled beforehand: its wall time, the grids of its
ladder, and its peak resident set size (`ru_maxrss`), which stays flat as the cycles grow when
the run's memory is O(cells) (the records go to the file as they are made). The goal: 100 cycles
in 1 s or less.
"""

from __future__ import annotations

import argparse
import json
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


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--counts", default="10,100")
    parser.add_argument("--child", type=int, help=argparse.SUPPRESS)
    args = parser.parse_args()
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
