"""Peak memory of a long run whose outputs are streamed to HDF5, against what holding them would take.

    .venv/bin/python bench/memory.py [--cells 10000] [--steps 1000000] [--field-stride 1000]

A uniform steel tool struck by a 20 kg striker at 5 m/s against an elastic, damped medium, solved
with the explicit scheme at Courant number 1; the whole history (every step), a probe, and the
fields every `--field-stride` steps are kept, streamed to a temporary HDF5 file as
`simulate(..., result_path=...)` does for a queued job. Each run is made in a fresh process
whose peak resident set size (`ru_maxrss`) is read at its end; a small run in the same way gives
the baseline of the interpreter with numpy, Numba, the kernel and h5py loaded. The goal is a
peak under 200 MB for 10^4 cells and 10^6 steps.
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

ROOT = Path(__file__).resolve().parents[1]
GOAL_MB = 200.0
BASELINE = {"cells": 100, "steps": 1000, "field_stride": 10}


def bench_case(cells: int, steps: int, field_stride: int) -> dict:
    length, youngs_modulus, density = 1.0, 2.1e11, 7800.0
    time_step = length / cells / (youngs_modulus / density) ** 0.5  # Courant number 1
    return {
        "name": "memory-bench",
        "striker": {"mass": 20.0, "velocity": 5.0},
        "tool": {"length": length, "area": 0.014209, "youngs_modulus": youngs_modulus, "density": density},
        "contact": {"stiffness": 1e11, "exponent": 0.5, "damping": 1.2e3},
        "medium": {"stiffness": 2e8, "damping": 1e3},
        "numerics": {"duration": steps * time_step, "time_step": time_step, "cells": cells, "scheme": "explicit"},
        "outputs": {"probes": [0.5 * length], "fields": True, "field_stride": field_stride},
    }


def child(cells: int, steps: int, field_stride: int) -> None:
    """Run one case streamed to a temporary file; print its figures as JSON."""
    from percussim.solver.case import parse_case
    from percussim.solver.controller import warm_up
    from percussim.solver.limits import output_values
    from percussim.solver.simulate import simulate

    case = parse_case(bench_case(cells, steps, field_stride))
    warm_up()  # the kernel loaded from Numba's cache before the clock starts
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "result.h5"
        start = time.perf_counter()
        result = simulate(case, result_path=path)
        wall = time.perf_counter() - start
        size = path.stat().st_size
    num = result.numerics
    print(
        json.dumps(
            {
                "cells": num.cells,
                "steps": num.steps,
                "wall": wall,
                "file_bytes": size,
                "node_steps": (num.cells + 1) * num.steps,
                "held_bytes": 8 * output_values(case, num),
                "peak_rss_bytes": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024,  # KiB on Linux
            }
        )
    )


def measure(cells: int, steps: int, field_stride: int) -> dict:
    out = subprocess.run(
        [
            sys.executable,
            __file__,
            "--child",
            "--cells",
            str(cells),
            "--steps",
            str(steps),
            "--field-stride",
            str(field_stride),
        ],
        check=True,
        capture_output=True,
        text=True,
        cwd=ROOT,
    )
    return json.loads(out.stdout)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--cells", type=int, default=10_000)
    parser.add_argument("--steps", type=int, default=1_000_000)
    parser.add_argument("--field-stride", type=int, default=1000)
    parser.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        child(args.cells, args.steps, args.field_stride)
        return

    # Compiled once beforehand, so that no measured process holds the compiler's memory.
    subprocess.run(
        [sys.executable, "-c", "from percussim.solver.controller import warm_up; warm_up()"], check=True, cwd=ROOT
    )
    base = measure(**BASELINE)
    run = measure(args.cells, args.steps, args.field_stride)
    mb = 1e-6
    print(
        f"baseline: {base['cells']} cells × {base['steps']} steps, peak RSS "
        f"{base['peak_rss_bytes'] * mb:.1f} MB (interpreter, numpy, Numba, kernel, h5py)"
    )
    print(
        f"run: {run['cells']} cells × {run['steps']:,} steps ({run['node_steps']:.3g} node-steps), "
        f"history every step, 1 probe, fields every {args.field_stride} steps, streamed to HDF5"
    )
    print(
        f"  peak RSS          {run['peak_rss_bytes'] * mb:8.1f} MB "
        f"({(run['peak_rss_bytes'] - base['peak_rss_bytes']) * mb:.1f} MB over the baseline; "
        f"goal < {GOAL_MB:.0f} MB: {'met' if run['peak_rss_bytes'] * mb < GOAL_MB else 'NOT met'})"
    )
    print(f"  outputs if held   {run['held_bytes'] * mb:8.1f} MB")
    print(f"  file size         {run['file_bytes'] * mb:8.1f} MB")
    print(f"  wall time         {run['wall']:8.1f} s")
    print(f"  per node-step     {run['wall'] / run['node_steps'] * 1e9:8.2f} ns")


if __name__ == "__main__":
    main()
