"""Validation tables: the solver against its references (model.md), as markdown.

    .venv/bin/python bench/validation.py [--write docs/validation.md]

1. Reference 1, linear contact on a long rod, closed form: errors and observed order.
2. A Hertz contact on a tapered tool (tests/cases/tapered_hertz.json): the refinement ladder.
3. Rigid-tool limit: the rod model against the two-mass model problem as E grows.
4. The Fig. 3 preset against the values model.md quotes (335 µs, 860 kN).
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

from solver import load_case, parse_case, simulate_rod
from solver.lumped import simulate_lumped
from solver.reference import LinearImpact

ROOT = Path(__file__).resolve().parents[1]


def _orders(values: list[float]) -> list[str]:
    return ["", *(f"{math.log2(abs(a) / abs(b)):.2f}" for a, b in zip(values, values[1:]))]


def reference_ladder() -> list[str]:
    ref = LinearImpact()
    rows, t_err, f_err = [], [], []
    for cells in (100, 200, 400, 800, 1600):
        case = parse_case(ref.case(cells))
        s = simulate_rod(case).summary
        t_err.append(s["co_impact_time"] / ref.contact_time - 1)
        f_err.append(s["peak_contact_force"]["value"] / ref.peak_force - 1)
        rows.append((cells, case.numerics.time_step, s["energy"]["numerical"] / s["energy"]["initial"]))
    lines = [
        f"Closed form: co-impact time {ref.contact_time * 1e6:.2f} µs, peak contact force "
        f"{ref.peak_force / 1e3:.1f} kN (ζ = {ref.zeta:.2f}, Courant number 0.5).", "",
        "| cells | τ (s) | co-impact error | order | peak-force error | order | numerical dissipation |",
        "|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for (cells, tau, dissipated), te, to, fe, fo in zip(rows, t_err, _orders(t_err), f_err, _orders(f_err)):
        lines.append(f"| {cells} | {tau:.3g} | {te:+.3%} | {to} | {fe:+.3%} | {fo} | {dissipated:.2%} |")
    return lines


def tapered_ladder() -> list[str]:
    base = json.loads((ROOT / "tests" / "cases" / "tapered_hertz.json").read_text())
    a = math.sqrt(base["tool"]["youngs_modulus"] / base["tool"]["density"])
    names = ("co_impact_time", "peak_contact_force", "max_compressive_stress", "max_tensile_stress")
    lines = ["| cells | co-impact (µs) | peak force (kN) | max compression (MPa) | at x (m) | "
             "max tension (MPa) |", "|---:|---:|---:|---:|---:|---:|"]
    for cells in (50, 100, 200, 400, 800, 1600):
        h = base["tool"]["length"] / cells
        base["numerics"].update(cells=cells, time_step=0.5 * h / a)
        s = simulate_rod(parse_case(base)).summary
        v = [s[names[0]] * 1e6, s[names[1]]["value"] / 1e3, s[names[2]]["value"] / 1e6,
             s[names[2]]["x"], s[names[3]]["value"] / 1e6]
        lines.append(f"| {cells} | {v[0]:.3f} | {v[1]:.2f} | {v[2]:.2f} | {v[3]:.4f} | {v[4]:.2f} |")
    return lines


def rigid_limit() -> list[str]:
    case = {
        "striker": {"mass": 20.0, "velocity": 5.0},
        "tool": {"length": 1.2, "area": 0.014209, "youngs_modulus": 2.1e11, "density": 7800.0},
        "contact": {"stiffness": 1e11, "exponent": 0.5},
        "numerics": {"duration": 1e-3, "cells": 50, "time_step": 2e-7},
    }
    lumped = simulate_lumped(parse_case(case)).summary
    lines = [f"Model problem (21)–(25), adaptive Runge–Kutta: co-impact {lumped['co_impact_time'] * 1e6:.2f} µs, "
             f"peak force {lumped['peak_contact_force']['value'] / 1e3:.2f} kN.", "",
             "| E / E_steel | co-impact (µs) | error | peak force (kN) | error |", "|---:|---:|---:|---:|---:|"]
    for factor in (1, 1e2, 1e4):
        case["tool"]["youngs_modulus"] = 2.1e11 * factor
        s = simulate_rod(parse_case(case)).summary
        te = s["co_impact_time"] / lumped["co_impact_time"] - 1
        fe = s["peak_contact_force"]["value"] / lumped["peak_contact_force"]["value"] - 1
        lines.append(f"| {factor:g} | {s['co_impact_time'] * 1e6:.2f} | {te:+.2%} | "
                     f"{s['peak_contact_force']['value'] / 1e3:.2f} | {fe:+.2%} |")
    return lines


def fig3() -> list[str]:
    s = simulate_rod(load_case(ROOT / "examples" / "fig3.json")).summary
    return [f"Fig. 3 preset (100 cells, τ = 8.3e-7 s): co-impact time {s['co_impact_time'] * 1e6:.1f} µs "
            f"(model.md: near 335 µs), peak contact force {s['peak_contact_force']['value'] / 1e3:.1f} kN "
            f"(model.md: near 860 kN)."]


def report() -> str:
    sections = [
        ("Reference 1: linear contact on a long rod", reference_ladder()),
        ("A Hertz contact on a tapered tool, refined at Courant number 0.5", tapered_ladder()),
        ("Rigid-tool limit: the rod model tends to the model problem", rigid_limit()),
        ("The paper's Fig. 3", fig3()),
    ]
    out = ["# Validation", "", "Produced by `bench/validation.py`; rerun it to check every number.", ""]
    for title, lines in sections:
        out += [f"## {title}", "", *lines, ""]
    return "\n".join(out)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--write", metavar="FILE", help="also write the markdown here")
    args = parser.parse_args()
    text = report()
    print(text)
    if args.write:
        Path(args.write).write_text(text)


if __name__ == "__main__":
    main()
