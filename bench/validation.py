"""Validation tables and figures: the solver against its references (model.md), as markdown.

    .venv/bin/python bench/validation.py [--write docs/validation.md]

1. Reference 1, linear contact on a long rod, closed form: errors and observed order of each
   scheme (what tests/test_reference.py and tests/test_schemes.py assert), and the stress wave.
2. A Hertz contact on a tapered tool (tests/cases/tapered_hertz.json): the refinement ladder.
3. Rigid-tool limit: the rod model against the two-mass model problem as E grows
   (tests/test_lumped.py).
4. The Fig. 3 preset against the values model.md quotes (335 µs, 860 kN).

With --write, the figures go to docs/validation/ beside the markdown.
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from solver import load_case, parse_case, simulate_rod
from solver.lumped import simulate_lumped
from solver.reference import LinearImpact, observed_order

ROOT = Path(__file__).resolve().parents[1]
SCHEMES = ("paper", "sigma", "explicit")
LADDER = (25, 50, 100, 200, 400, 800, 1600)


def _orders(values: list[float]) -> list[str]:
    return ["", *(f"{math.log2(abs(a) / abs(b)):.2f}" for a, b in zip(values, values[1:]))]


def reference_ladder(figures: dict[str, Figure]) -> list[str]:
    ref = LinearImpact()
    errors = {scheme: [] for scheme in SCHEMES}
    pulses = {}
    rows = []
    for scheme in SCHEMES:
        for cells in LADDER:
            case = ref.case(cells)
            case["numerics"]["scheme"] = scheme
            result = simulate_rod(parse_case(case))
            errors[scheme].append(ref.errors(result.summary))
            if cells == 50:
                pulses[scheme] = (result.history["time"], result.history["contact/force"])
            if scheme == "paper":
                s = result.summary
                rows.append((cells, case["numerics"]["time_step"], s["energy"]["numerical"] / s["energy"]["initial"]))
    t_err, f_err = zip(*errors["paper"])
    lines = [
        f"Closed form: co-impact time {ref.contact_time * 1e6:.2f} µs, peak contact force "
        f"{ref.peak_force / 1e3:.1f} kN (ζ = {ref.zeta:.2f}, Courant number 0.5).", "",
        "The paper's scheme:", "",
        "| cells | τ (s) | co-impact error | order | peak-force error | order | numerical dissipation |",
        "|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for (cells, tau, dissipated), te, to, fe, fo in zip(rows, t_err, _orders(t_err), f_err, _orders(f_err)):
        lines.append(f"| {cells} | {tau:.3g} | {te:+.3%} | {to} | {fe:+.3%} | {fo} | {dissipated:.2%} |")
    lines += ["", "Every scheme (observed order: least-squares slope of log |error| over the ladder):", "",
              "| scheme | co-impact error at 1600 cells | order | peak-force error at 1600 cells | order |",
              "|---|---:|---:|---:|---:|"]
    for scheme in SCHEMES:
        e = np.array(errors[scheme])
        lines.append(f"| {scheme} | {e[-1, 0]:+.2e} | {observed_order(LADDER, e[:, 0]):.2f} | "
                     f"{e[-1, 1]:+.2e} | {observed_order(LADDER, e[:, 1]):.2f} |")
    figures["reference"] = _reference_figure(ref, pulses, errors)
    figures["wave"] = _wave_figure(ref)
    lines += ["", "![the closed form against each scheme, and the errors under refinement](validation/reference.png)",
              "", "![the stress wave at x = 0.5 m against the closed form](validation/wave.png)"]
    return lines


def _reference_figure(ref: LinearImpact, pulses: dict, errors: dict) -> Figure:
    fig = Figure(figsize=(11, 4.2), layout="constrained")
    left, right = fig.subplots(1, 2)
    t = np.linspace(0, ref.contact_time, 400)
    left.plot(t * 1e6, ref.force(t) / 1e3, "k-", lw=2.5, label="closed form")
    for scheme, (time, force) in pulses.items():
        left.plot(time * 1e6, force / 1e3, lw=1.2, label=f"{scheme}, 50 cells")
    left.set(xlabel="time (µs)", ylabel="contact force (kN)", xlim=(0, 1.15 * ref.contact_time * 1e6),
             title="Linear impact on a long rod: the contact pulse")
    left.legend()
    for scheme, marker in zip(SCHEMES, "osd"):
        e = np.abs(np.array(errors[scheme]))
        right.loglog(LADDER, e[:, 1], marker + "-", label=f"{scheme}: peak force (order {observed_order(LADDER, e[:, 1]):.2f})")
        right.loglog(LADDER, e[:, 0], marker + "--", mfc="none",
                     label=f"{scheme}: co-impact time (order {observed_order(LADDER, e[:, 0]):.2f})")
    right.set(xlabel="cells (Courant number 0.5)", ylabel="relative error",
              title="Errors against the closed form under refinement")
    right.grid(True, which="both", alpha=0.3)
    right.legend(fontsize=8)
    return fig


def _wave_figure(ref: LinearImpact) -> Figure:
    x = 0.5
    result = simulate_rod(parse_case(ref.case(800, probes=[x])))
    t = result.history["time"]
    fig = Figure(figsize=(7, 3.8), layout="constrained")
    ax = fig.subplots()
    ax.plot(t * 1e6, ref.stress(t, x) / 1e6, "k-", lw=2.5, label="closed form −F(t − x/a)/S")
    ax.plot(t * 1e6, result.probe_stress[:, 0] / 1e6, lw=1.2, label="paper's scheme, 800 cells")
    ax.set(xlabel="time (µs)", ylabel="stress (MPa)", title=f"Stress at x = {x} m: the pulse travels at a")
    ax.legend()
    return fig


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


def rigid_limit(figures: dict[str, Figure]) -> list[str]:
    case = {
        "striker": {"mass": 20.0, "velocity": 5.0},
        "tool": {"length": 1.2, "area": 0.014209, "youngs_modulus": 2.1e11, "density": 7800.0},
        "contact": {"stiffness": 1e11, "exponent": 0.5},
        "numerics": {"duration": 1e-3, "cells": 50, "time_step": 2e-7},
    }
    lumped_run = simulate_lumped(parse_case(case))
    lumped = lumped_run.summary
    fig = Figure(figsize=(7, 3.8), layout="constrained")
    ax = fig.subplots()
    lines = [f"Model problem (21)–(25), adaptive Runge–Kutta: co-impact {lumped['co_impact_time'] * 1e6:.2f} µs, "
             f"peak force {lumped['peak_contact_force']['value'] / 1e3:.2f} kN.", "",
             "| E / E_steel | co-impact (µs) | error | peak force (kN) | error |", "|---:|---:|---:|---:|---:|"]
    for factor in (1, 1e2, 1e4):
        case["tool"]["youngs_modulus"] = 2.1e11 * factor
        run = simulate_rod(parse_case(case))
        s = run.summary
        ax.plot(run.history["time"] * 1e6, run.history["contact/force"] / 1e3, lw=1.2, label=f"rod, E × {factor:g}")
        te = s["co_impact_time"] / lumped["co_impact_time"] - 1
        fe = s["peak_contact_force"]["value"] / lumped["peak_contact_force"]["value"] - 1
        lines.append(f"| {factor:g} | {s['co_impact_time'] * 1e6:.2f} | {te:+.2%} | "
                     f"{s['peak_contact_force']['value'] / 1e3:.2f} | {fe:+.2%} |")
    ax.plot(lumped_run.history["time"] * 1e6, lumped_run.history["contact/force"] / 1e3, "k--", lw=2,
            label="model problem (rigid tool)")
    ax.set(xlabel="time (µs)", ylabel="contact force (kN)", xlim=(0, 1.3 * lumped["co_impact_time"] * 1e6),
           title="Rigid-tool limit: the contact pulse as E grows")
    ax.legend()
    figures["rigid_limit"] = fig
    return lines + ["", "![the rod's contact pulse tends to the model problem's](validation/rigid_limit.png)"]


def fig3() -> list[str]:
    s = simulate_rod(load_case(ROOT / "examples" / "fig3.json")).summary
    return [f"Fig. 3 preset (100 cells, τ = 8.3e-7 s): co-impact time {s['co_impact_time'] * 1e6:.1f} µs "
            f"(model.md: near 335 µs), peak contact force {s['peak_contact_force']['value'] / 1e3:.1f} kN "
            f"(model.md: near 860 kN)."]


def report(figures: dict[str, Figure]) -> str:
    """The markdown; the figures it refers to are added to `figures` by name."""
    sections = [
        ("Reference 1: linear contact on a long rod", reference_ladder(figures)),
        ("A Hertz contact on a tapered tool, refined at Courant number 0.5", tapered_ladder()),
        ("Rigid-tool limit: the rod model tends to the model problem", rigid_limit(figures)),
        ("The paper's Fig. 3", fig3()),
    ]
    out = ["# Validation", "",
           "Produced by `bench/validation.py --write docs/validation.md`, tables and figures; rerun it to "
           "check every number. The test suite holds the solver to the same references with the same "
           "code (`solver/reference.py`): `tests/test_reference.py`, `tests/test_schemes.py`, "
           "`tests/test_convergence.py`, `tests/test_lumped.py`, `tests/test_energy.py`.", ""]
    for title, lines in sections:
        out += [f"## {title}", "", *lines, ""]
    return "\n".join(out)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--write", metavar="FILE", help="also write the markdown here")
    args = parser.parse_args()
    figures: dict[str, Figure] = {}
    text = report(figures)
    print(text)
    if args.write:
        out = Path(args.write)
        out.write_text(text)
        (out.parent / "validation").mkdir(exist_ok=True)
        for name, fig in figures.items():
            fig.savefig(out.parent / "validation" / f"{name}.png", dpi=110)


if __name__ == "__main__":
    main()
