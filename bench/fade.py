"""How long each first contact takes to fade where it ends, against its length: the figures behind
`accuracy.FADE_FRACTION` (docs/numerics.md, "A first contact that fades out").

    .venv/bin/python bench/fade.py [--seeds 1 2 3 4] [--processes 2]

For every preset at the default accuracy and every case of the matrices drawn with `--seeds` (at
a tolerance of 1e-2 under the raised limits, as `bench/matrix.py` solves them), the summary's
`contact_fade_time` over its `co_impact_time`, and the same ratio of the characteristics solver on
the case's first reference grid: next to nothing where the faces part, a slow link's share of the contact where it fades out.
Then the first contacts over `FADE_FRACTION`, and where the characteristics solver ends seed 4's
matrix-68 on three grids (rounding's, not the grid's, where the contact fades out).
"""

from __future__ import annotations

import argparse
from multiprocessing import Pool

from matrix import COUNT, RAISED

from percussim.solver.accuracy import FADE_FRACTION
from percussim.solver.case import parse_case
from percussim.solver.characteristics import solve
from percussim.solver.matrix import draw_cases, reference_cells
from percussim.solver.presets import preset_names
from percussim.solver.simulate import simulate
from percussim.testing import at_default_accuracy


def share(fade: float | None, length: float | None) -> float | None:
    return None if fade is None or not length else fade / length


def matrix_case(job: tuple[int, dict]) -> dict:
    seed, data = job
    case = parse_case(data)
    at_tolerance = case.model_copy(update={"numerics": case.numerics.model_copy(update={"tolerance": 1e-2})})
    summary = simulate(at_tolerance, limits=RAISED).summary
    reference = solve(case, reference_cells(case))
    return {
        "name": f"seed {seed} {data['name']}",
        "run": share(summary["contact_fade_time"], summary["co_impact_time"]),
        "reference": share(reference.contact_fade_time, reference.co_impact_time),
    }


def text(value: float | None) -> str:
    return "—" if value is None else f"{value:.2e}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=int, nargs="*", default=[1, 2, 3, 4])
    parser.add_argument("--processes", type=int, default=2)
    args = parser.parse_args()

    print("preset               fade / co-impact time")
    for name in preset_names():
        summary = simulate(parse_case(at_default_accuracy(name))).summary
        print(f"{name:20s} {text(share(summary['contact_fade_time'], summary['co_impact_time']))}")

    jobs = [(seed, data) for seed in args.seeds for data in draw_cases(seed, COUNT)]
    with Pool(args.processes) as pool:
        rows = pool.map(matrix_case, jobs, chunksize=1)
    parted = sorted((r for r in rows if r["run"] is not None and r["run"] <= FADE_FRACTION), key=lambda r: r["run"])
    faded = [r for r in rows if r["run"] is not None and r["run"] > FADE_FRACTION]
    print(f"\n{len(rows)} matrix cases, {len(parted) + len(faded)} with a first contact that ends:")
    print(f"  {len(parted)} at most {FADE_FRACTION:g} of its length, the largest:")
    for r in parted[-3:]:
        print(f"  {r['name']}: {text(r['run'])} (the characteristics solver's first grid: {text(r['reference'])})")
    print(f"  {len(faded)} over it:")
    for r in faded:
        print(f"  {r['name']}: {text(r['run'])} (the characteristics solver's first grid: {text(r['reference'])})")

    data = next(c for c in draw_cases(4, 69) if c["name"] == "matrix-68")
    case = parse_case(data)
    ends = {cells: solve(case, cells).co_impact_time for cells in (2000, 4000, 8000)}
    solved = simulate(case).summary
    print(
        f"\nseed 4 matrix-68: the solver ends its first contact at {solved['co_impact_time'] * 1e6:.1f} µs on "
        f"{', '.join(str(r['cells']) for r in solved['runs'])} cells; the characteristics solver at "
        + ", ".join(f"{t * 1e6:.1f} µs on {cells}" for cells, t in ends.items())
    )


if __name__ == "__main__":
    main()
