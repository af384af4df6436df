"""Why the drivability's slow depths are slow: the 9-m variant of `bench/piling.py` (driven 3
blows, as its blow count settles) on fixed grids of the ladder's scheme, its largest tension and
how it converges, with the shaft and without it; then its ladder under the default accuracy.

    .venv/bin/python bench/pile_tension.py

The tension near the pile's head (0.5 m down, as the helmet leaves the head) is the only
quantity whose grids disagree by over the tolerance; the others agree within 1e-4 from 512 cells.
It is the sum of a wave going down and one coming up, each a function of t ∓ x/c alone, read at
Courant number 1 from two layers of displacements: each wave's own peak over the head's 1.5 m is
printed for the grids of `WAVE_CELLS`.
"""

from __future__ import annotations

import time

from piling import NO_SETUP, PILE

from percussim.solver.case import Case, Outputs, parse_case
from percussim.solver.controller import simulate_rod, warm_up
from percussim.solver.grid import explicit_numerics
from percussim.solver.pile_requests import at_depth, parse_drivability
from percussim.solver.settle import with_blows
from percussim.solver.simulate import simulate

CELLS = (256, 512, 1008, 1024, 2016, 2048, 4096)
WAVE_CELLS = (256, 512, 1024)
HEAD = 1.5  # m: where the waves' peaks are sought


def tensions(case: Case) -> list[float]:
    return [
        simulate_rod(case, numerics=explicit_numerics(case, cells)).summary["max_tensile_stress"]["value"] / 1e6
        for cells in CELLS
    ]


def wave_peaks(case: Case, cells: int) -> tuple[float, float]:
    """The greatest of the down-going and of the up-going wave, (σ ∓ ρc·v)/2 in MPa, over the
    head's `HEAD` m and the last blow, from every layer's displacements."""
    kept = case.model_copy(update={"outputs": Outputs(fields=True, field_stride=1, history_stride=1 << 30)})
    result = simulate_rod(kept, numerics=explicit_numerics(kept, cells))
    u, time = result.fields.displacement, result.fields.time
    last = time >= time[-1] - case.numerics.duration
    near = int(HEAD / (case.tool.length / cells))
    scale = 0.5 * case.tool.youngs_modulus / (case.tool.length / cells) / 1e6
    before, now = u[:-1][last[1:], : near + 1], u[1:][last[1:], : near + 1]
    down = scale * (before[:, 1:] - now[:, :-1])  # at Courant number 1: the diagonal differences
    up = scale * (now[:, 1:] - before[:, :-1])
    return float(down.max()), float(up.max())


def main() -> None:
    warm_up()
    request = parse_drivability({"case": PILE, "soil": NO_SETUP})
    case = with_blows(parse_case(at_depth(request.case, request.soil, 9.0)), 3)
    bare = Case.model_validate(case.model_dump(mode="json", exclude_none=True, exclude={"shaft"}))
    print("largest tension (MPa) on each grid:")
    print("  cells         " + "".join(f"{n:>9d}" for n in CELLS))
    for label, variant in (("with the shaft", case), ("without it", bare)):
        print(f"  {label:14s}" + "".join(f"{v:9.3f}" for v in tensions(variant)))
    print("\neach wave's own peak near the head (MPa):")
    for cells in WAVE_CELLS:
        down, up = wave_peaks(case, cells)
        print(f"  {cells:5d} cells: going down {down:8.3f}, coming up {up:8.3f}")
    start = time.perf_counter()
    summary = simulate(case).summary
    seconds = time.perf_counter() - start
    grids = ", ".join(str(run["cells"]) for run in summary["runs"])
    print(f"\nthe ladder under the default accuracy: {seconds:.1f} s, grids {grids}")
    print(
        f"  largest tension {summary['max_tensile_stress']['value'] / 1e6:.3f} MPa, estimated error "
        f"{summary['error_estimate']['max_tensile_stress']:.2g}"
    )


if __name__ == "__main__":
    main()
