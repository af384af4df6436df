"""Wall time of the solver after compilation, and its cost per node-step, on the Fig. 3 preset.

    .venv/bin/python bench/solver_speed.py [--repeat 20]

The Fig. 3 preset: 100 cells, τ = 8.3e-7 s, 4 ms (4820 steps). The run is timed whole, from the
validated case to the summary, as a user calls it; the best and median of the repeats are printed.
"""

from __future__ import annotations

import argparse
import statistics
import time

from percussim.solver.controller import simulate_rod, warm_up
from percussim.solver.presets import load_preset


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeat", type=int, default=20)
    args = parser.parse_args()

    case = load_preset("fig3")
    warm_up()
    times = []
    for _ in range(args.repeat):
        start = time.perf_counter()
        result = simulate_rod(case)
        times.append(time.perf_counter() - start)
    num = result.numerics
    node_steps = (num.cells + 1) * num.steps
    best, median = min(times), statistics.median(times)
    print(
        f"case: {case.name}, {num.cells} cells, tau = {num.time_step:.3g} s, {num.steps} steps, "
        f"{node_steps:,} node-steps"
    )
    print(f"wall time after compilation: best {best * 1e3:.2f} ms, median {median * 1e3:.2f} ms ({args.repeat} runs)")
    print(f"cost per node-step: best {best / node_steps * 1e9:.2f} ns, median {median / node_steps * 1e9:.2f} ns")
    print(
        f"co-impact time {result.summary['co_impact_time'] * 1e6:.1f} us, "
        f"peak contact force {result.summary['peak_contact_force']['value'] / 1e3:.1f} kN"
    )


if __name__ == "__main__":
    main()
