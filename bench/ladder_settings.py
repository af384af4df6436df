"""The tolerance ladder's margins against what they cost and what they risk.

    .venv/bin/python bench/ladder_settings.py [--write]

`solver.adaptive.Ladder` has three margins: the a-priori error constant that places the first
pair of grids, the safety with which a predicted grid aims below the tolerance, and the factor
the Richardson estimate is taken larger by. Each setting below runs every case of
`bench/accuracy_vs_cost.py` under a tolerance:

- cost: on the 3 closed forms and the 3 presets at 1e-2, 1e-3, 1e-4 (18 runs), the work
  (node-steps, summed over the grids tried) against the least work of a fixed grid that meets
  the tolerance, found in hindsight (closed forms: `solver.reference.cheapest_fixed_grid`, every
  scheme at Courant number 1 and ½; presets: each scheme's ladder of cells 2^(k/4)·10 at Courant
  number 1, a grid meeting the tolerance when it and every finer grid of its ladder do);
- risk: on those 18 and the 14 Fig. 5 variants at 1e-2 and 1e-3 (46 runs), the true error over
  the tolerance, against the closed form or a fine reference (the explicit scheme on two fine
  grids, Richardson-extrapolated), and the runs refused (the ladder gave up, saying why).

The settings run in parallel on every core. Printed: one line a setting; `--write` writes
`docs/ladder_settings.md`.
"""

from __future__ import annotations

import argparse
import math
import os
from concurrent.futures import ProcessPoolExecutor
from dataclasses import astuple
from pathlib import Path

import accuracy_vs_cost as bench
from solver import parse_case
from solver.adaptive import LADDER, Ladder, solve_to_tolerance
from solver.case import CaseError
from solver.controller import warm_up
from solver.reference import LinearImpact, cheapest_fixed_grid, work
from solver.simulate import simulate

ROOT = Path(__file__).resolve().parents[1]
SETTINGS = (
    LADDER,
    Ladder(error_constant=3.0), Ladder(error_constant=4.5), Ladder(error_constant=8.0),
    Ladder(error_constant=12.0),
    Ladder(safety=0.8), Ladder(safety=0.9),
    Ladder(estimate_factor=1.2), Ladder(estimate_factor=1.35), Ladder(estimate_factor=2.0),
    Ladder(error_constant=4.5, safety=0.9, estimate_factor=1.2),
    Ladder(error_constant=8.0, safety=0.6, estimate_factor=2.0),
)
COST_BOUND = 3.0


def yardsticks() -> list[dict]:
    """Every case as (name, tolerance, case, reference, least fixed-grid work or None)."""
    cases = []
    for zeta, m1 in bench.CLOSED_FORMS:
        reference = LinearImpact(zeta=zeta, m1=m1)
        for tol in bench.TOLERANCES:
            cases.append({"name": f"closed form ζ = {zeta:g}", "tol": tol,
                          "case": bench.closed_form_case(reference, tol),
                          "reference": reference.truth(),
                          "least_work": cheapest_fixed_grid(reference, tol)[0]})
    for name, reference_cells in bench.PRESETS.items():
        case = bench.preset(name)
        reference, _ = bench.reference(case, reference_cells)
        ladder = {}
        for scheme in bench.SCHEMES:
            rows = []
            for cells in bench.LADDER:
                summary = simulate(parse_case(bench.with_numerics(
                    case, scheme=scheme, cells=cells, time_step=bench.courant_one(case, cells)))).summary
                rows.append((cells, summary["numerics"]["steps"], work([summary["numerics"]]),
                             bench.error(summary, reference)))
            ladder[scheme] = rows
        for tol in bench.TOLERANCES:
            cases.append({"name": name, "tol": tol, "case": bench.with_numerics(case, tolerance=tol),
                          "reference": reference,
                          "least_work": min(bench.meeting(ladder, tol), default=(math.nan,))[0]})
    for velocity, stiffness in bench.FIG5_VARIANTS:
        case = bench.fig5_variant(velocity, stiffness)
        reference, _ = bench.reference(case, 800)
        for tol in bench.VARIANT_TOLERANCES:
            cases.append({"name": f"Fig. 5 at {velocity:.2f} m/s, c1 = {stiffness:.2g}", "tol": tol,
                          "case": bench.with_numerics(case, tolerance=tol), "reference": reference,
                          "least_work": None})
    return cases


def measure(ladder: Ladder, cases: list[dict]) -> dict:
    """One setting over every case: work ratios, true errors over the tolerance, refusals."""
    ratios, errors, refused = [], [], []
    for c in cases:
        try:
            summary = solve_to_tolerance(parse_case(c["case"]), ladder=ladder).summary
        except CaseError:
            refused.append(f"{c['name']} at {c['tol']:g}")
            continue
        errors.append((bench.error(summary, c["reference"]) / c["tol"], c["name"], c["tol"]))
        if c["least_work"] is not None:
            ratios.append((work(summary["runs"]) / c["least_work"], c["name"], c["tol"]))
    return {"ladder": ladder, "ratios": ratios, "errors": errors, "refused": refused}


def line(m: dict) -> str:
    worst_ratio, worst_error = max(m["ratios"]), max(m["errors"])
    over = sum(r > COST_BOUND for r, _, _ in m["ratios"])
    beyond = sum(e > 1.0 for e, _, _ in m["errors"])
    ratios = sorted(r for r, _, _ in m["ratios"])
    return (f"| {m['ladder'].error_constant:g} | {m['ladder'].safety:g} | {m['ladder'].estimate_factor:g} | "
            f"{ratios[len(ratios) // 2]:.2f}× | {over} of {len(ratios)} | {worst_ratio[0]:.1f}× "
            f"({worst_ratio[1]} at {worst_ratio[2]:g}) | {beyond} of {len(m['errors']) + len(m['refused'])} | "
            f"{worst_error[0]:.2f} ({worst_error[1]} at {worst_error[2]:g}) | {len(m['refused'])} |")


HEADER = ("| error constant | safety | estimate factor | median work ratio | work ratios over 3× | "
          "largest work ratio | true errors over the tolerance | largest true error / tolerance | "
          "refused |\n|---|---|---|---|---|---|---|---|---|")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--write", action="store_true", help="write docs/ladder_settings.md")
    args = parser.parse_args()
    warm_up()
    cases = yardsticks()
    with ProcessPoolExecutor(os.cpu_count()) as pool:
        measured = list(pool.map(measure, SETTINGS, [cases] * len(SETTINGS)))
    lines = [HEADER] + [line(m) for m in measured]
    print("\n".join(lines))
    if args.write:
        chosen = astuple(LADDER)
        (ROOT / "docs" / "ladder_settings.md").write_text("\n".join([
            "# The tolerance ladder's margins",
            "",
            "Written by `bench/ladder_settings.py --write` (rerun it to check). Each row runs every "
            "tolerance case of `bench/accuracy_vs_cost.py` with other margins "
            "(`solver.adaptive.Ladder`): the work against the least work of a fixed grid that "
            "meets the tolerance, found in hindsight, on the 3 closed forms and 3 presets at 1e-2, "
            "1e-3 and 1e-4; the true error over the tolerance on those and 14 Fig. 5 variants at "
            "1e-2 and 1e-3. The first row is the solver's own setting "
            f"(error constant {chosen[0]:g}, safety {chosen[1]:g}, estimate factor {chosen[2]:g}).",
            "",
            *lines,
            "",
        ]))


if __name__ == "__main__":
    main()
