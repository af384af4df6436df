"""Why the drivability's slow depths are slow: the 9-m variant of `bench/piling.py` (driven 3
blows, as its blow count settles) on fixed grids of the ladder's scheme, its largest tension and
how it converges, with the shaft and without it; then its ladder under the default accuracy.

    .venv/bin/python bench/pile_tension.py

The tension near the pile's head (0.5 m down, as the helmet leaves the head) is the only
quantity whose grids disagree by over the tolerance; the others agree within 1e-4 from 512 cells.
"""

from __future__ import annotations

import time

from piling import NO_SETUP, PILE

from percussim.solver.case import Case, parse_case
from percussim.solver.controller import simulate_rod, warm_up
from percussim.solver.grid import explicit_numerics
from percussim.solver.pile_requests import at_depth, parse_drivability
from percussim.solver.settle import with_blows
from percussim.solver.simulate import simulate

CELLS = (256, 512, 1008, 1024, 2016, 2048, 4096)


def tensions(case: Case) -> list[float]:
    return [
        simulate_rod(case, numerics=explicit_numerics(case, cells)).summary["max_tensile_stress"]["value"] / 1e6
        for cells in CELLS
    ]


def main() -> None:
    warm_up()
    request = parse_drivability({"case": PILE, "soil": NO_SETUP})
    case = with_blows(parse_case(at_depth(request.case, request.soil, 9.0)), 3)
    bare = Case.model_validate(case.model_dump(mode="json", exclude_none=True, exclude={"shaft"}))
    print("largest tension (MPa) on each grid:")
    print("  cells         " + "".join(f"{n:>9d}" for n in CELLS))
    for label, variant in (("with the shaft", case), ("without it", bare)):
        print(f"  {label:14s}" + "".join(f"{v:9.3f}" for v in tensions(variant)))
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
