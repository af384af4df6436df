"""Validation tables and figures: the solver against its references (model.md), as markdown.

    .venv/bin/python bench/validation.py [--write docs/validation.md]

1. Reference 1, linear contact on a long rod, closed form: errors and observed order of each
   scheme (what tests/test_reference.py and tests/test_schemes.py assert), and the stress wave.
2. A Hertz contact on a tapered tool (tests/cases/tapered_hertz.json): the refinement ladder.
3. Rigid-tool limit: the rod model against the two-mass model problem as E grows
   (tests/test_lumped.py).
4. The Fig. 3 preset against the values model.md quotes (335 µs, 860 kN).
5. Stiff ends: a damped contact on a long rod (closed form), Saint-Venant's rigid impact on a bar
   with a fixed end (closed form), contacts far stiffer than the tool's end cell (against the
   characteristics solver, `solver/characteristics.py`), and the contact force recorded as the
   scheme applies it (against the characteristics solver's), at the default accuracy or on the
   explicit scheme at Courant number 1 (tests/test_stiff_ends.py, tests/test_accuracy.py).

With --write, the figures go to docs/validation/ beside the markdown.
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from percussim.solver.case import parse_case
from percussim.solver.controller import simulate_rod
from percussim.solver.lumped import simulate_lumped
from percussim.solver.presets import load_preset
from percussim.solver.reference import LinearImpact, observed_order

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
    s = simulate_rod(load_preset("fig3")).summary
    return [f"Fig. 3 preset (100 cells, τ = 8.3e-7 s): co-impact time {s['co_impact_time'] * 1e6:.1f} µs "
            f"(model.md: near 335 µs), peak contact force {s['peak_contact_force']['value'] / 1e3:.1f} kN "
            f"(model.md: near 860 kN)."]


def damped_contact() -> list[str]:
    """A linear contact with a damper b1 = 0.3·Z on a long rod: the overlap obeys
    `(1 + b1/Z)·δ'' + (b1/m1 + k/Z)·δ' + (k/m1)·δ = 0`, δ'(0+) = W1/(1 + b1/Z)."""
    from scipy.optimize import minimize_scalar

    ref = LinearImpact(zeta=0.3)
    k, m1, z, w1 = ref.k, ref.m1, ref.impedance, ref.w1
    b1 = 0.3 * z
    roots = np.roots([1 + b1 / z, b1 / m1 + k / z, k / m1])
    decay, omega = roots[0].real, abs(roots[0].imag)
    rate0 = w1 / (1 + b1 / z)

    def force(t):
        delta = rate0 / omega * np.exp(decay * t) * np.sin(omega * t)
        rate = rate0 / omega * np.exp(decay * t) * (decay * np.sin(omega * t) + omega * np.cos(omega * t))
        return k * delta + b1 * rate

    peak = -minimize_scalar(lambda t: -force(t), bounds=(0, math.pi / omega), method="bounded",
                            options={"xatol": 1e-14}).fun
    lines = [f"Closed form: peak contact force {peak / 1e3:.2f} kN, contact {math.pi / omega * 1e6:.2f} µs "
             f"(b1 = 0.3·Z); the explicit scheme at Courant number 1, its ends integrating their own "
             "equations:", "", "| cells | peak-force error | order | co-impact error |",
             "|---:|---:|---:|---:|"]
    errors = []
    for cells in (100, 200, 400, 800, 1600):
        case = ref.case(cells)
        case["contact"]["damping"] = b1
        case["numerics"].update(duration=1.1 * math.pi / omega, scheme="explicit", time_step=None)
        s = simulate_rod(parse_case(case)).summary
        errors.append(s["peak_contact_force"]["value"] / peak - 1)
        order = f"{math.log2(abs(errors[-2] / errors[-1])):.2f}" if len(errors) > 1 else ""
        lines.append(f"| {cells} | {errors[-1]:+.2e} | {order} | "
                     f"{s['co_impact_time'] * omega / math.pi - 1:+.2e} |")
    return lines


def saint_venant() -> list[str]:
    from percussim.solver.characteristics import solve
    from percussim.solver.reference import RigidImpact
    from percussim.solver.simulate import simulate

    ref = RigidImpact()
    case = parse_case(ref.case())
    summary = simulate(case).summary
    truth = ref.truth()
    gap = solve(case, 6400)
    finite = {"co_impact_time": gap.co_impact_time, "peak_contact_force": gap.peak_contact_force,
              "max_compressive_stress": gap.max_compressive_stress}
    found = {"co_impact_time": summary["co_impact_time"],
             "peak_contact_force": summary["peak_contact_force"]["value"],
             "max_compressive_stress": summary["max_compressive_stress"]["value"]}
    lines = [f"A mass of {ref.m1:g} kg at {ref.w1:g} m/s on a {ref.length:g}-m steel bar of "
             f"{ref.area * 1e4:g} cm², its far end fixed: a contact 100× critically damped against the "
             "bar and a medium 100× stiffer than the contact stand for the rigid mass and the fixed end. "
             f"At the default accuracy ({len(summary['runs'])} grids, the finest "
             f"{summary['runs'][-1]['cells']} cells):", "",
             "| quantity | closed form | solver | error | estimate | this case's own gap from the rigid limit |",
             "|---|---:|---:|---:|---:|---:|"]
    for name, value in truth.items():
        lines.append(f"| {name} | {value:.6g} | {found[name]:.6g} | {found[name] / value - 1:+.2e} | "
                     f"{summary['error_estimate'][name]:.1e} | {finite[name] / value - 1:+.2e} |")
    lines += ["", "The gap is the characteristics solver's on 6400 cells: the contact's compliance and "
              "the medium's, which the closed form does not have. Where the largest compression is: "
              f"x = {summary['max_compressive_stress']['x']:g} m at "
              f"{summary['max_compressive_stress']['time'] / ref.return_time:.3f}·2L/a (the fixed end at "
              "3L/a)."]
    return lines


def stiff_contacts() -> list[str]:
    from percussim.solver.case import CaseError
    from percussim.solver.characteristics import solve
    from percussim.solver.simulate import simulate

    base = LinearImpact(zeta=0.3, m1=20.0, length=1.0, area=0.01)
    lines = ["A 20-kg striker at 5 m/s on a 1-m bar through linear contacts ζ times critically damped "
             "against the bar, over 1.5 returns of the wave; at the default accuracy, against the "
             "characteristics solver on 3200 cells, and what the fixed grids of the other schemes do "
             "on 100 cells:", "",
             "| ζ | contacts | reference | peak force error | co-impact error | paper, 100 cells | sigma, 100 cells |",
             "|---:|---:|---:|---:|---:|---|---|"]
    for zeta in (1.0, 3.0, 10.0, 30.0):
        k = (2.0 * zeta * base.impedance) ** 2 / base.m1
        data = base.case(100)
        data["contact"]["stiffness"] = k
        data["numerics"] = {"duration": 3.0 * base.length / base.a}
        case = parse_case(data)
        s = simulate(case).summary
        r = solve(case, 3200)
        fixed = []
        for scheme in ("paper", "sigma"):
            grid = {**data, "numerics": {**data["numerics"], "scheme": scheme, "cells": 100}}
            try:
                fixed.append(f"{simulate(parse_case(grid)).summary['contacts_total']} contact(s)")
            except CaseError as error:
                fixed.append(f"refused ({error.errors[0].field})")
        lines.append(f"| {zeta:g} | {s['contacts_total']} | {r.contacts} | "
                     f"{s['peak_contact_force']['value'] / r.peak_contact_force - 1:+.1e} | "
                     f"{s['co_impact_time'] / r.co_impact_time - 1:+.1e} | {fixed[0]} | {fixed[1]} |")
    return lines


def recorded_force_report() -> list[str]:
    from percussim.solver.characteristics import solve
    from percussim.solver.presets import preset_json
    from percussim.solver.reference import recorded_force
    from percussim.solver.simulate import simulate

    data = preset_json("fig9")
    data["numerics"] = {"duration": data["numerics"]["duration"]}
    result = simulate(parse_case(data))
    reference = solve(parse_case(data), 1600, history_points=4000)
    found = recorded_force(result.history, result.summary["peak_contact_force"]["value"],
                           reference.history)
    return [f"The Fig. 9 case at the default accuracy (finest grid {result.summary['runs'][-1]['cells']} "
            f"cells): its recorded contact force differs from the characteristics solver's (1600 cells) by "
            f"at most {found.deviation:.1e} of the peak; its second differences, where a ripple of "
            f"period 2τ would show, reach {found.second_difference:.1e} of the peak."]


def report(figures: dict[str, Figure]) -> str:
    """The markdown; the figures it refers to are added to `figures` by name."""
    sections = [
        ("Reference 1: linear contact on a long rod", reference_ladder(figures)),
        ("A Hertz contact on a tapered tool, refined at Courant number 0.5", tapered_ladder()),
        ("Rigid-tool limit: the rod model tends to the model problem", rigid_limit(figures)),
        ("The paper's Fig. 3", fig3()),
        ("A contact damper: the damped oscillator on a long rod", damped_contact()),
        ("Saint-Venant's rigid impact on a bar with a fixed end", saint_venant()),
        ("Contacts far stiffer than the tool's end cell", stiff_contacts()),
        ("The contact force, as the scheme applies it", recorded_force_report()),
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
