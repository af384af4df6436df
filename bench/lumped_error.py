"""How far the lumped model (21)–(25) is from the rod, against the rigidity ε the tolerance uses.

    .venv/bin/python bench/lumped_error.py

Over a family of short tools (5–40 cm, uniform or with a 1:4 conical half, striker 1–100 kg,
c1 = 1e9–1e11 N/m^1.5, media 2e8 and 2e9 N/m) with ε ≤ 0.5, the relative error of every quantity
the summary estimates (those the rod's run leaves out aside) of the lumped model against the rod
(the explicit scheme at Courant number 1 on a fine grid, checked against one twice as fine) is
divided by ε². The largest ratio found is what `solver/adaptive.py`'s LUMPED_ERROR must exceed.
"""

from __future__ import annotations

import numpy as np

from percussim.solver.accuracy import estimated_values, not_estimated
from percussim.solver.adaptive import LUMPED_ERROR, explicit_numerics, rigidity
from percussim.solver.case import parse_case
from percussim.solver.controller import simulate_rod
from percussim.solver.grid import contact_time_estimate, wave_speed
from percussim.solver.lumped import simulate_lumped

BASE = {
    "striker": {"mass": 13.0, "velocity": 5.0},
    "tool": {"length": 0.5, "youngs_modulus": 2.1e11, "density": 7800.0, "area": 0.002},
    "contact": {"stiffness": 8e11, "exponent": 0.5},
    "medium": {"stiffness": 2e8, "damping": 10.0},
    "numerics": {"duration": 1e-3},
}


def case_of(length: float, c1: float, m1: float, c2: float, tapered: bool) -> dict:
    tool = {**BASE["tool"], "length": length}
    if tapered:
        del tool["area"]
        tool["profile"] = {"x": [0.0, length / 2, length], "area": [0.002, 0.002, 0.0005]}
    case = {
        **BASE,
        "tool": tool,
        "striker": {**BASE["striker"], "mass": m1},
        "contact": {**BASE["contact"], "stiffness": c1},
        "medium": {**BASE["medium"], "stiffness": c2},
    }
    period = contact_time_estimate(parse_case(case))
    case["numerics"] = {"duration": 3 * period}
    return case


def rod(case: dict, cells: int) -> dict:
    """The rod's summary on `cells` cells, the explicit scheme at Courant number 1."""
    parsed = parse_case(case)
    return simulate_rod(parsed, numerics=explicit_numerics(parsed, cells)).summary


def main() -> None:
    ratios, worst = [], 0.0
    for length in (0.05, 0.1, 0.2, 0.4):
        for c1 in (1e9, 1e10, 1e11):
            for m1 in (1.0, 13.0, 100.0):
                for c2 in (2e8, 2e9):
                    for tapered in (False, True):
                        case = case_of(length, c1, m1, c2, tapered)
                        parsed = parse_case(case)
                        eps = rigidity(parsed)
                        if eps > 0.5:
                            continue
                        period = contact_time_estimate(parsed)
                        cells = max(16, int(800 * length / (wave_speed(parsed.tool) * period)))
                        summary = rod(case, 2 * cells)
                        skip = not_estimated(summary, parsed.striker.velocity, True)
                        fine = {q: v for q, v in estimated_values(summary).items() if q not in skip}
                        check = estimated_values(rod(case, cells))
                        lumped = estimated_values(simulate_lumped(parsed).summary)
                        errors = [abs(lumped[q] / fine[q] - 1) for q in fine]
                        grid = max(abs(check[q] / fine[q] - 1) for q in fine)
                        ratios.append(max(errors) / eps**2)
                        worst = max(worst, grid)
                        print(
                            f"L {length:4} m  c1 {c1:.0e}  m1 {m1:5}  c2 {c2:.0e}  "
                            f"{'tapered' if tapered else 'uniform'}:  ε {eps:.3f}  "
                            f"error {max(errors):.2e}  error/ε² {ratios[-1]:.3f}"
                        )
    print(
        f"\n{len(ratios)} cases with ε ≤ 0.5: error/ε² at most {max(ratios):.3f} "
        f"(median {np.median(ratios):.3f}); LUMPED_ERROR = {LUMPED_ERROR}; "
        f"rod grid uncertainty at most {worst:.1e}"
    )


if __name__ == "__main__":
    main()
