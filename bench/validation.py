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
6. The models beyond the paper against the closed forms of one-dimensional impact, each at fine
   numerics and at `numerics.tolerance` 0.01, with its energy residual, cells and run time; the
   cases and formulas are the tests' own (percussim/testing/closed_forms.py): the elastic striker (the pulses
   of r = 0.5, 1, 2 and a fractional last cell; tests/test_striker_rod.py), bilinear rock against
   Lundberg's η(x) and Smith soil's set and loop (tests/test_media.py), and the set per blow, blow
   after blow (tests/test_blows.py).
7. Piles (`bench/validation_piles.py`): the shaft's rigid-body mode, the static compression under
   gravity, a cushion, a Smith toe's set read through a bearing graph, the audit under gravity,
   and a driven pile against Smith's lumped-mass model (an independent discretisation).
8. A hammer at work (`bench/validation_cycle.py`): the drive between blows against the closed
   forms of ideal hydraulics, its work and gas law, the supply's work a cycle, a matched piston
   struck from rest, the adaptive stroke, and the rock drill's cycle preset.
9. Signal matching (`bench/validation_matching.py`): a known soil recovered from a head record
   made by an independent run with 2% noise, the non-uniqueness warning, the Case method against
   its closed form, and the static load test against its closed form and a rigid-plastic plunge.

With --write, the figures go to docs/validation/ beside the markdown.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path
from time import perf_counter
from typing import NamedTuple

import numpy as np
from matplotlib.figure import Figure

from percussim.solver.case import parse_case
from percussim.solver.controller import simulate_rod
from percussim.solver.grid import explicit_numerics
from percussim.solver.lumped import simulate_lumped
from percussim.solver.presets import load_preset
from percussim.solver.result import Result
from percussim.solver.simulate import simulate
from percussim.testing import closed_forms as CF
from percussim.testing.reference import LinearImpact, observed_order

sys.path.insert(0, str(Path(__file__).resolve().parent))  # the piles' and the cycle's sections, beside this script
from validation_cycle import cycle_sections  # noqa: E402
from validation_matching import matching_sections  # noqa: E402
from validation_piles import pile_sections  # noqa: E402

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
        f"{ref.peak_force / 1e3:.1f} kN (ζ = {ref.zeta:.2f}, Courant number 0.5).",
        "",
        "The paper's scheme:",
        "",
        "| cells | τ (s) | co-impact error | order | peak-force error | order | numerical dissipation |",
        "|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for (cells, tau, dissipated), te, to, fe, fo in zip(rows, t_err, _orders(t_err), f_err, _orders(f_err)):
        lines.append(f"| {cells} | {tau:.3g} | {te:+.3%} | {to} | {fe:+.3%} | {fo} | {dissipated:.2%} |")
    lines += [
        "",
        "Every scheme (observed order: least-squares slope of log |error| over the ladder):",
        "",
        "| scheme | co-impact error at 1600 cells | order | peak-force error at 1600 cells | order |",
        "|---|---:|---:|---:|---:|",
    ]
    for scheme in SCHEMES:
        e = np.array(errors[scheme])
        lines.append(
            f"| {scheme} | {e[-1, 0]:+.2e} | {observed_order(LADDER, e[:, 0]):.2f} | "
            f"{e[-1, 1]:+.2e} | {observed_order(LADDER, e[:, 1]):.2f} |"
        )
    figures["reference"] = _reference_figure(ref, pulses, errors)
    figures["wave"] = _wave_figure(ref)
    lines += [
        "",
        "![the closed form against each scheme, and the errors under refinement](validation/reference.png)",
        "",
        "![the stress wave at x = 0.5 m against the closed form](validation/wave.png)",
    ]
    return lines


def _reference_figure(ref: LinearImpact, pulses: dict, errors: dict) -> Figure:
    fig = Figure(figsize=(11, 4.2), layout="constrained")
    left, right = fig.subplots(1, 2)
    t = np.linspace(0, ref.contact_time, 400)
    left.plot(t * 1e6, ref.force(t) / 1e3, "k-", lw=2.5, label="closed form")
    for scheme, (time, force) in pulses.items():
        left.plot(time * 1e6, force / 1e3, lw=1.2, label=f"{scheme}, 50 cells")
    left.set(
        xlabel="time (µs)",
        ylabel="contact force (kN)",
        xlim=(0, 1.15 * ref.contact_time * 1e6),
        title="Linear impact on a long rod: the contact pulse",
    )
    left.legend()
    for scheme, marker in zip(SCHEMES, "osd"):
        e = np.abs(np.array(errors[scheme]))
        right.loglog(
            LADDER, e[:, 1], marker + "-", label=f"{scheme}: peak force (order {observed_order(LADDER, e[:, 1]):.2f})"
        )
        right.loglog(
            LADDER,
            e[:, 0],
            marker + "--",
            mfc="none",
            label=f"{scheme}: co-impact time (order {observed_order(LADDER, e[:, 0]):.2f})",
        )
    right.set(
        xlabel="cells (Courant number 0.5)",
        ylabel="relative error",
        title="Errors against the closed form under refinement",
    )
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
    lines = [
        "| cells | co-impact (µs) | peak force (kN) | max compression (MPa) | at x (m) | max tension (MPa) |",
        "|---:|---:|---:|---:|---:|---:|",
    ]
    for cells in (50, 100, 200, 400, 800, 1600):
        h = base["tool"]["length"] / cells
        base["numerics"].update(cells=cells, time_step=0.5 * h / a)
        s = simulate_rod(parse_case(base)).summary
        v = [
            s[names[0]] * 1e6,
            s[names[1]]["value"] / 1e3,
            s[names[2]]["value"] / 1e6,
            s[names[2]]["x"],
            s[names[3]]["value"] / 1e6,
        ]
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
    lines = [
        f"Model problem (21)–(25), adaptive Runge–Kutta: co-impact {lumped['co_impact_time'] * 1e6:.2f} µs, "
        f"peak force {lumped['peak_contact_force']['value'] / 1e3:.2f} kN.",
        "",
        "| E / E_steel | co-impact (µs) | error | peak force (kN) | error |",
        "|---:|---:|---:|---:|---:|",
    ]
    for factor in (1, 1e2, 1e4):
        case["tool"]["youngs_modulus"] = 2.1e11 * factor
        run = simulate_rod(parse_case(case))
        s = run.summary
        ax.plot(run.history["time"] * 1e6, run.history["contact/force"] / 1e3, lw=1.2, label=f"rod, E × {factor:g}")
        te = s["co_impact_time"] / lumped["co_impact_time"] - 1
        fe = s["peak_contact_force"]["value"] / lumped["peak_contact_force"]["value"] - 1
        lines.append(
            f"| {factor:g} | {s['co_impact_time'] * 1e6:.2f} | {te:+.2%} | "
            f"{s['peak_contact_force']['value'] / 1e3:.2f} | {fe:+.2%} |"
        )
    ax.plot(
        lumped_run.history["time"] * 1e6,
        lumped_run.history["contact/force"] / 1e3,
        "k--",
        lw=2,
        label="model problem (rigid tool)",
    )
    ax.set(
        xlabel="time (µs)",
        ylabel="contact force (kN)",
        xlim=(0, 1.3 * lumped["co_impact_time"] * 1e6),
        title="Rigid-tool limit: the contact pulse as E grows",
    )
    ax.legend()
    figures["rigid_limit"] = fig
    return lines + ["", "![the rod's contact pulse tends to the model problem's](validation/rigid_limit.png)"]


def fig3() -> list[str]:
    s = simulate_rod(load_preset("fig3")).summary
    return [
        f"Fig. 3 preset (100 cells, τ = 8.3e-7 s): co-impact time {s['co_impact_time'] * 1e6:.1f} µs "
        f"(model.md: near 335 µs), peak contact force {s['peak_contact_force']['value'] / 1e3:.1f} kN "
        f"(model.md: near 860 kN)."
    ]


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

    peak = -minimize_scalar(
        lambda t: -force(t), bounds=(0, math.pi / omega), method="bounded", options={"xatol": 1e-14}
    ).fun
    lines = [
        f"Closed form: peak contact force {peak / 1e3:.2f} kN, contact {math.pi / omega * 1e6:.2f} µs "
        f"(b1 = 0.3·Z); the explicit scheme at Courant number 1, its ends integrating their own "
        "equations:",
        "",
        "| cells | peak-force error | order | co-impact error |",
        "|---:|---:|---:|---:|",
    ]
    errors = []
    for cells in (100, 200, 400, 800, 1600):
        case = ref.case(cells)
        case["contact"]["damping"] = b1
        case["numerics"].update(duration=1.1 * math.pi / omega, scheme="explicit", time_step=None)
        s = simulate_rod(parse_case(case)).summary
        errors.append(s["peak_contact_force"]["value"] / peak - 1)
        order = f"{math.log2(abs(errors[-2] / errors[-1])):.2f}" if len(errors) > 1 else ""
        lines.append(f"| {cells} | {errors[-1]:+.2e} | {order} | {s['co_impact_time'] * omega / math.pi - 1:+.2e} |")
    return lines


def saint_venant() -> list[str]:
    from percussim.solver.characteristics import solve
    from percussim.solver.simulate import simulate
    from percussim.testing.reference import RigidImpact

    ref = RigidImpact()
    case = parse_case(ref.case())
    summary = simulate(case).summary
    truth = ref.truth()
    gap = solve(case, 6400)
    finite = {
        "co_impact_time": gap.co_impact_time,
        "peak_contact_force": gap.peak_contact_force,
        "max_compressive_stress": gap.max_compressive_stress,
    }
    found = {
        "co_impact_time": summary["co_impact_time"],
        "peak_contact_force": summary["peak_contact_force"]["value"],
        "max_compressive_stress": summary["max_compressive_stress"]["value"],
    }
    lines = [
        f"A mass of {ref.m1:g} kg at {ref.w1:g} m/s on a {ref.length:g}-m steel bar of "
        f"{ref.area * 1e4:g} cm², its far end fixed: a contact 100× critically damped against the "
        "bar and a medium 100× stiffer than the contact stand for the rigid mass and the fixed end. "
        f"At the default accuracy ({len(summary['runs'])} grids, the finest "
        f"{summary['runs'][-1]['cells']} cells):",
        "",
        "| quantity | closed form | solver | error | estimate | this case's own gap from the rigid limit |",
        "|---|---:|---:|---:|---:|---:|",
    ]
    for name, value in truth.items():
        lines.append(
            f"| {name} | {value:.6g} | {found[name]:.6g} | {found[name] / value - 1:+.2e} | "
            f"{summary['error_estimate'][name]:.1e} | {finite[name] / value - 1:+.2e} |"
        )
    lines += [
        "",
        "The gap is the characteristics solver's on 6400 cells: the contact's compliance and "
        "the medium's, which the closed form does not have. Where the largest compression is: "
        f"x = {summary['max_compressive_stress']['x']:g} m at "
        f"{summary['max_compressive_stress']['time'] / ref.return_time:.3f}·2L/a (the fixed end at "
        "3L/a).",
    ]
    return lines


def stiff_contacts() -> list[str]:
    from percussim.solver.case import CaseError
    from percussim.solver.characteristics import solve
    from percussim.solver.simulate import simulate

    base = LinearImpact(zeta=0.3, m1=20.0, length=1.0, area=0.01)
    lines = [
        "A 20-kg striker at 5 m/s on a 1-m bar through linear contacts ζ times critically damped "
        "against the bar, over 1.5 returns of the wave; at the default accuracy, against the "
        "characteristics solver on 3200 cells, and what the fixed grids of the other schemes do "
        "on 100 cells:",
        "",
        "| ζ | contacts | reference | peak force error | co-impact error | paper, 100 cells | sigma, 100 cells |",
        "|---:|---:|---:|---:|---:|---|---|",
    ]
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
        lines.append(
            f"| {zeta:g} | {s['contacts_total']} | {r.contacts} | "
            f"{s['peak_contact_force']['value'] / r.peak_contact_force - 1:+.1e} | "
            f"{s['co_impact_time'] / r.co_impact_time - 1:+.1e} | {fixed[0]} | {fixed[1]} |"
        )
    return lines


def recorded_force_report() -> list[str]:
    from percussim.solver.characteristics import solve
    from percussim.solver.presets import preset_json
    from percussim.solver.simulate import simulate
    from percussim.testing.reference import recorded_force

    data = preset_json("fig9")
    data["numerics"] = {"duration": data["numerics"]["duration"]}
    result = simulate(parse_case(data))
    reference = solve(parse_case(data), 1600, history_points=4000)
    found = recorded_force(result.history, result.summary["peak_contact_force"]["value"], reference.history)
    return [
        f"The Fig. 9 case at the default accuracy (finest grid {result.summary['runs'][-1]['cells']} "
        f"cells): its recorded contact force differs from the characteristics solver's (1600 cells) by "
        f"at most {found.deviation:.1e} of the peak; its second differences, where a ripple of "
        f"period 2τ would show, reach {found.second_difference:.1e} of the peak."
    ]


# --- The models beyond the paper: the one-dimensional impacts of percussim/testing/closed_forms.py ------------


TOLERANCE = 0.01


class Run(NamedTuple):
    """One case solved as `simulate` solves it (a fixed grid with its two companions, or a
    tolerance's ladder), timed."""

    case: str
    numerics: str
    result: Result
    seconds: float

    @property
    def summary(self) -> dict:
        return self.result.summary


def _solve(case: str, numerics: str, data: dict) -> Run:
    start = perf_counter()
    result = simulate(data)
    return Run(case, numerics, result, perf_counter() - start)


def _both(case: str, build, fine: dict) -> tuple[Run, Run]:
    """`build(numerics)` solved on the fine grid `fine` and at the tolerance."""
    return (
        _solve(case, f"fine ({fine['cells']} cells)", build(fine)),
        _solve(case, f"tolerance {TOLERANCE:g}", build({"tolerance": TOLERANCE})),
    )


def _residual(summary: dict) -> float:
    """energy.numerical over the energy supplied."""
    energy = summary["energy"]
    return energy["numerical"] / (energy["initial"] + energy["external_work"])


def _grids(summary: dict) -> str:
    cells = [run["cells"] for run in summary["runs"]]
    if summary["tolerance"] is None:
        return f"{cells[-1]} (estimate from {', '.join(map(str, cells[:-1]))})"
    return f"{cells[0]} … {cells[-1]} ({len(cells)} grids)"


def _estimate(summary: dict) -> str:
    """The run's own error estimate, its worst quantity, and whether a tolerance was met."""
    estimate = summary["error_estimate"]
    if not estimate:
        return "none"
    name, worst = max(((k, v) for k, v in estimate.items() if k != "worst" and v is not None), key=lambda item: item[1])
    text = f"{worst:.1e} ({name})"
    if summary["tolerance"] is not None:
        text += " within" if worst <= summary["tolerance"] else " **not met**"
    return text


def runs_table(runs: list[Run]) -> list[str]:
    lines = [
        "| case | numerics | cells | run time (s) | energy residual | its own error estimate, worst |",
        "|---|---|---|---:|---:|---|",
    ]
    for run in runs:
        lines.append(
            f"| {run.case} | {run.numerics} | {_grids(run.summary)} | {run.seconds:.3f} | "
            f"{_residual(run.summary):+.1e} | {_estimate(run.summary)} |"
        )
    return lines


class Check(NamedTuple):
    """A quantity against its closed form, found at fine numerics and at the tolerance. A closed
    form of 0 is met by a share (of what `quantity` says), else the error is relative. `held`: what
    the tests hold the error to (None: not asserted)."""

    case: str
    quantity: str
    closed: float
    fine: float
    tolerance: float
    held: float | None
    scale: float = 1.0

    def errors(self) -> tuple[float, float]:
        if self.closed == 0.0:
            return self.fine, self.tolerance
        return self.fine / self.closed - 1.0, self.tolerance / self.closed - 1.0


def checks_table(checks: list[Check]) -> list[str]:
    lines = [
        f"| case | quantity | closed form | fine | error | tolerance {TOLERANCE:g} | error | tests hold it to |",
        "|---|---|---:|---:|---:|---:|---:|---:|",
    ]
    for c in checks:
        fine, tol = c.errors()
        held = "—" if c.held is None else f"{c.held:.0e}"
        value = "{:.2e}" if c.closed == 0.0 else "{:.6g}"
        lines.append(
            f"| {c.case} | {c.quantity} | {c.closed * c.scale:.6g} | {value.format(c.fine * c.scale)} | "
            f"{fine:+.1e} | {value.format(c.tolerance * c.scale)} | {tol:+.1e} | {held} |"
        )
    return lines


def _label(run: Run) -> str:
    """The run's numerics, and a ladder's finest grid."""
    if run.summary["tolerance"] is None:
        return run.numerics
    return f"{run.numerics} (finest grid {run.summary['runs'][-1]['cells']} cells)"


def _force_at(run: Run, fraction: float) -> float:
    """The contact force at `fraction` of the piston's round trip T."""
    history = run.result.history
    return float(np.interp(fraction * CF.T, history["time"], history["contact/force"]))


def _pulse_deviation(run: Run, ratio: float) -> float:
    """The largest deviation of the force from the closed form, 2% of T clear of its jumps, over F_1."""
    time_, force = run.result.history["time"], run.result.history["contact/force"]
    phase = time_ / CF.T
    clear = np.abs(phase - np.round(phase)) > 0.02
    closed = np.array([CF.piston_force(ratio, t) for t in time_])
    return float(np.max(np.abs(force - closed)[clear]) / CF.first_force(ratio))


def _striker_left(run: Run) -> float:
    energy = run.summary["energy"]
    return (energy["striker_kinetic"] + energy["striker_strain"]) / energy["initial"]


def _passed(summary: dict) -> float:
    energy = summary["energy"]
    return (energy["tool_kinetic"] + energy["tool_strain"]) / energy["initial"]


def piston_report(figures: dict[str, Figure]) -> list[str]:
    """The elastic striker against the closed forms of one-dimensional impact
    (tests/test_striker_rod.py)."""
    runs: dict[float, tuple[Run, Run]] = {}
    for ratio in (0.5, 1.0, 2.0):
        duration = {"duration": CF.STEPPED_DURATION} if ratio > 1.0 else {}
        runs[ratio] = _both(
            f"r = {ratio:g}", lambda numerics, r=ratio, d=duration: CF.piston_case(r, {**numerics, **d}), CF.PISTON_FINE
        )
    checks = []

    def check(ratio, quantity, closed, found, held, scale=1.0):
        fine, tol = runs[ratio]
        checks.append(Check(f"r = {ratio:g}", quantity, closed, found(fine), found(tol), held, scale))

    f1 = {ratio: CF.first_force(ratio) for ratio in runs}
    # r = 1: a rectangle Z·v/2 lasting T, the striker left at rest
    check(1.0, "peak contact force (kN)", f1[1.0], lambda r: r.summary["peak_contact_force"]["value"], 1e-3, 1e-3)
    check(
        1.0,
        "force at 0.05, 0.3, 0.6, 0.95·T, farthest from F_1 (kN)",
        f1[1.0],
        lambda r: max((_force_at(r, s) for s in (0.05, 0.3, 0.6, 0.95)), key=lambda f: abs(f - f1[1.0])),
        2e-3,
        1e-3,
    )
    check(
        1.0,
        "force at 1.05, 1.3, 1.8·T, the largest in magnitude, share of F_1",
        0.0,
        lambda r: max(abs(_force_at(r, s)) for s in (1.05, 1.3, 1.8)) / f1[1.0],
        1e-3,
    )
    check(1.0, "striker's energy left, share of its initial", 0.0, _striker_left, 5e-3)
    # r = 0.5: F_1 for T, then it leaves at R·v having passed 4r/(1 + r)²
    check(0.5, "peak contact force (kN)", f1[0.5], lambda r: r.summary["peak_contact_force"]["value"], 2e-3, 1e-3)
    check(0.5, "force at T/2 (kN)", f1[0.5], lambda r: _force_at(r, 0.5), 2e-3, 1e-3)
    check(0.5, "energy passed, share: 4r/(1 + r)²", CF.passed_share(0.5), lambda r: _passed(r.summary), 1e-2)
    check(
        0.5,
        "rebound velocity R·v (m/s)",
        CF.reflection(0.5) * CF.V,
        lambda r: r.summary["striker_rebound_velocity"],
        1e-2,
    )
    check(0.5, "co-impact time T (µs)", CF.T, lambda r: r.summary["co_impact_time"], 1e-2, 1e6)
    # r = 2: F_1·R^k on the k-th T
    for step in range(3):
        check(
            2.0,
            f"force at {step + 0.5:g}·T: F_1·R^{step} (kN)",
            f1[2.0] * CF.reflection(2.0) ** step,
            lambda r, s=step: _force_at(r, s + 0.5),
            1e-2,
            1e-3,
        )
    for ratio in runs:
        check(
            ratio,
            "pulse 2% of T clear of its jumps: largest deviation, share of F_1",
            0.0,
            lambda r, q=ratio: _pulse_deviation(r, q),
            None,
        )
    figures["piston"] = _piston_figure(runs)

    whole = _solve("stepped piston", "2000 cells (whole)", CF.stepped_piston_case(2000))
    fractional = _solve("stepped piston", "2003 cells (fractional)", CF.stepped_piston_case(2003))
    a, b = whole.summary, fractional.summary
    pairs = [
        ("peak contact force (kN)", a["peak_contact_force"]["value"] / 1e3, b["peak_contact_force"]["value"] / 1e3),
        (
            "max compressive stress (MPa)",
            a["max_compressive_stress"]["value"] / 1e6,
            b["max_compressive_stress"]["value"] / 1e6,
        ),
        ("energy passed, share", _passed(a), _passed(b)),
    ]
    fine = runs[1.0][0].summary["runs"][-1]
    lines = [
        f"A steel piston {CF.PISTON:g} m long at {CF.V:g} m/s strikes a {CF.TOOL:g}-m steel tool of "
        f"{CF.AREA * 1e4:g} cm² through a stiff linear contact; its area is r times the tool's, its "
        f"impedance r·Z (Z = {CF.Z:.0f} N·s/m). T = 2·L_s/a = {CF.T * 1e6:.2f} µs, "
        f"F_1 = r·Z·v/(1 + r) = {f1[0.5] / 1e3:.2f}, {f1[1.0] / 1e3:.2f}, {f1[2.0] / 1e3:.2f} kN for "
        f"r = 0.5, 1, 2, R = (r − 1)/(r + 1). Fine: the explicit scheme at Courant number 1 on "
        f"{CF.PISTON_FINE['cells']} cells of the tool (the piston on {round(CF.PISTON / CF.TOOL * fine['cells'])} "
        f"of its own, τ = {fine['time_step']:.3g} s); tolerance {TOLERANCE:g}: the ladder "
        "`numerics.tolerance` climbs. Errors are relative, or a share where the closed form is 0.",
        "",
        *checks_table(checks),
        "",
        *runs_table([run for pair in runs.values() for run in pair]),
        "",
        "![each pulse against its closed form](validation/piston.png)",
        "",
        "The fractional last cell: a piston whose back half has twice its area, on 2000 cells of the "
        "tool (its length a whole number of its cells) and on 2003 (a fraction of a cell beyond its "
        f"last node, a delay of {2 * (CF.PISTON / CF.SPEED) / fractional.result.numerics.time_step % 2:.3f}·τ "
        "there and back):",
        "",
        "| quantity | whole | fractional | difference | tests hold it to |",
        "|---|---:|---:|---:|---:|",
    ]
    for name, x, y in pairs:
        lines.append(f"| {name} | {x:.6g} | {y:.6g} | {y / x - 1:+.1e} | 2e-03 |")
    lines += ["", *runs_table([whole, fractional])]
    return lines


def _piston_figure(runs: dict[float, tuple[Run, Run]]) -> Figure:
    fig = Figure(figsize=(12, 3.8), layout="constrained")
    for ax, (ratio, (fine, tol)) in zip(fig.subplots(1, 3), runs.items()):
        end = fine.result.history["time"][-1]
        t = np.linspace(0.0, end, 4001)
        ax.plot(t * 1e6, [CF.piston_force(ratio, s) / 1e3 for s in t], "k-", lw=2.5, label="closed form")
        for run, style in ((fine, "-"), (tol, "--")):
            h = run.result.history
            ax.plot(h["time"] * 1e6, h["contact/force"] / 1e3, style, lw=1.2, label=_label(run))
        ax.set(xlabel="time (µs)", ylabel="contact force (kN)", title=f"piston of r = {ratio:g}")
        ax.legend(fontsize=8)
    return fig


ROCK_X = (0.3, 0.6, CF.OPTIMUM, 2.0, 3.0)


def rock_report(figures: dict[str, Figure]) -> list[str]:
    """Bilinear rock against Lundberg's efficiency (tests/test_media.py)."""
    runs = {x: _both(f"x = {x:g}", lambda numerics, x=x: CF.rock_case(x, numerics), CF.MEDIUM_FINE) for x in ROCK_X}
    checks = []
    for x, (fine, tol) in runs.items():
        deepest, permanent = CF.rock_penetration(x)
        for quantity, closed, found, held, scale in (
            ("η = to_medium / initial", CF.lundberg(x), lambda s: s["energy"]["transfer_efficiency"], 1e-2, 1),
            ("deepest penetration F_max/k (µm)", deepest, lambda s: s["medium_penetration"]["max"], 1e-2, 1e6),
            (
                "permanent (1 − k/k_u)·F_max/k (µm)",
                permanent,
                lambda s: s["medium_penetration"]["permanent"],
                1e-2,
                1e6,
            ),
            (
                "medium_plastic / to_medium",
                1.0,
                lambda s: s["energy"]["medium_plastic"] / s["energy"]["to_medium"],
                1e-4,
                1,
            ),
        ):
            checks.append(Check(f"x = {x:g}", quantity, closed, found(fine.summary), found(tol.summary), held, scale))
    x_best, eta_best = CF.lundberg_optimum()
    figures["lundberg"] = _lundberg_figure(runs, x_best)
    return [
        f"The equal piston's wave, F_i = Z·v/2 = {CF.INCIDENT / 1e3:.2f} kN lasting T = {CF.T * 1e6:.2f} µs, "
        f"on rock loading at k = x·Z/T and unloading at k_u = {CF.UNLOADING:g}·k, over "
        f"{CF.MEDIUM_DURATION * 1e6:.1f} µs (2.2·L/a: the wave has passed and the rock is unloaded). "
        f"Closed form: η = 2(1 − e^(−x))²/x·(1 − k/k_u), largest where e^x = 1 + 2x, at x = {x_best:.4f}: "
        f"{eta_best:.4f} for k_u → ∞, {eta_best * (1 - 1 / CF.UNLOADING):.4f} here. Fine: the explicit "
        f"scheme on {CF.MEDIUM_FINE['cells']} cells.",
        "",
        *checks_table(checks),
        "",
        *runs_table([run for pair in runs.values() for run in pair]),
        "",
        "![η(x) and the solver's points](validation/lundberg.png)",
        "",
        *last_instant(0.6),
    ]


def last_instant(x: float) -> list[str]:
    """The largest compression near the run's last instant, where a grid's last layer can lie up
    to a step past the duration: read over the duration exactly, it does not depend on that step."""
    meeting = (2.0 * CF.TOOL + CF.PISTON) / CF.SPEED
    case = parse_case({**CF.rock_case(x, {}), "outputs": {}})
    lines = [
        f"The duration of these media, {CF.MEDIUM_DURATION * 1e6:.3f} µs, ends before the instant "
        f"2L/a + L_s/a = {meeting * 1e6:.3f} µs at which the wave that the free struck end reflects "
        "meets, at x = L_s, the peak of the medium's reflection. A grid's last layer can lie up to a "
        "step past the duration, nearer that meeting; a run's extremes are read over the duration "
        "exactly (its last step where the duration ends), so grids whose last layers differ report "
        f"the same largest compression. On fixed grids, x = {x:g}:",
        "",
        "| cells | last layer (µs) | largest compression (MPa) | at x (m) | at t (µs) |",
        "|---:|---:|---:|---:|---:|",
    ]
    for cells in (640, 768, 1536, 3072):
        numerics = explicit_numerics(case, cells)
        found = simulate_rod(case, numerics).summary["max_compressive_stress"]
        lines.append(
            f"| {cells} | {numerics.steps * numerics.time_step * 1e6:.3f} | "
            f"{found['value'] / 1e6:.1f} | {found['x']:.4f} | {found['time'] * 1e6:.3f} |"
        )
    return lines + ["", "The comparisons with the closed forms do not depend on it."]


def _lundberg_figure(runs: dict[float, tuple[Run, Run]], x_best: float) -> Figure:
    fig = Figure(figsize=(7, 4.2), layout="constrained")
    ax = fig.subplots()
    x = np.linspace(0.05, 5.0, 500)
    ax.plot(x, [CF.lundberg(s) for s in x], "k-", lw=2, label=f"closed form, k_u = {CF.UNLOADING:g}·k")
    ax.plot(x, [CF.lundberg(s, math.inf) for s in x], "k:", lw=1.2, label="closed form, k_u → ∞")
    ax.axvline(x_best, color="0.6", lw=0.8)
    for index, marker in ((0, "o"), (1, "x")):
        ax.plot(
            list(runs),
            [pair[index].summary["energy"]["transfer_efficiency"] for pair in runs.values()],
            marker,
            ms=8,
            mfc="none",
            label=f"solver, {next(iter(runs.values()))[index].numerics}",
        )
    ax.set(
        xlabel="x = k·T/Z",
        ylabel="η, share of the striker's energy kept by the rock",
        title="Lundberg's efficiency on bilinear rock",
    )
    ax.legend()
    return fig


def _loop(run: Run) -> float:
    """∮F du over the history: the net work on the medium."""
    force, penetration = run.result.history["medium/force"], run.result.history["medium/penetration"]
    return float(np.sum(0.5 * (force[1:] + force[:-1]) * np.diff(penetration)))


def soil_report(figures: dict[str, Figure]) -> list[str]:
    """Smith soil against its set and its loop (tests/test_media.py)."""
    runs = {
        j: _both(f"J = {j:g} s/m", lambda numerics, j=j: CF.soil_case(numerics, damping_factor=j), CF.MEDIUM_FINE)
        for j in (0.0, 0.5)
    }
    t_q, set_ = CF.smith_set()
    r_u = CF.SOIL_RESISTANCE
    fine, tol = runs[0.0]
    checks = [
        Check("J = 0", quantity, closed, found(fine), found(tol), held, scale)
        for quantity, closed, found, held, scale in (
            (
                "set (2F_i − R_u)(T − t_q)/Z (µm)",
                set_,
                lambda r: r.summary["medium_penetration"]["permanent"],
                1e-2,
                1e6,
            ),
            ("plastic work R_u·set (J)", r_u * set_, lambda r: r.summary["energy"]["medium_plastic"], 1e-2, 1),
            (
                "dissipated by damping, share of to_medium",
                0.0,
                lambda r: r.summary["energy"]["dissipated_medium"] / r.summary["energy"]["to_medium"],
                0.0,
                1,
            ),
        )
    ]
    for j, (fine, tol) in runs.items():
        checks.append(
            Check(
                f"J = {j:g}",
                "loop ∮F du / to_medium",
                1.0,
                _loop(fine) / fine.summary["energy"]["to_medium"],
                _loop(tol) / tol.summary["energy"]["to_medium"],
                1e-2,
            )
        )
    damped = runs[0.5][0].summary["energy"]
    figures["smith_loop"] = _smith_figure(runs, set_)
    return [
        f"The same wave (F_i = {CF.INCIDENT / 1e3:.2f} kN, T = {CF.T * 1e6:.2f} µs) on soil of ultimate "
        f"resistance R_u = {r_u / 1e3:.2f} kN (1.2·F_i, under 2F_i: the toe flows), quake "
        f"q = {r_u / CF.SOIL_STIFFNESS * 1e6:.2f} µm (k = R_u/q = 5·Z/T). Closed form without damping: "
        f"elastic until t_q = −(Z/k)·ln(1 − R_u/(2F_i)) = {t_q * 1e6:.3f} µs after the wave arrives, then "
        f"flowing at (2F_i − R_u)/Z until T: set = {set_ * 1e6:.3f} µm. With Smith damping "
        f"J = 0.5 s/m the loop still encloses what the soil took; its damping dissipates "
        f"{damped['dissipated_medium'] / damped['to_medium']:.1%} of it (fine).",
        "",
        *checks_table(checks),
        "",
        *runs_table([run for pair in runs.values() for run in pair]),
        "",
        "![the force–penetration loop](validation/smith_loop.png)",
    ]


def _smith_figure(runs: dict[float, tuple[Run, Run]], set_: float) -> Figure:
    fig = Figure(figsize=(7, 4.2), layout="constrained")
    ax = fig.subplots()
    r_u, q = CF.SOIL_RESISTANCE, CF.SOIL_RESISTANCE / CF.SOIL_STIFFNESS
    ax.plot(
        np.array([0.0, q, set_ + q, set_]) * 1e6,
        np.array([0.0, r_u, r_u, 0.0]) / 1e3,
        "k-",
        lw=2.5,
        label="closed form, J = 0",
    )
    for j, (fine, tol) in runs.items():
        for run, style in ((fine, "-"), (tol, "--")):
            h = run.result.history
            ax.plot(
                h["medium/penetration"] * 1e6,
                h["medium/force"] / 1e3,
                style,
                lw=1.2,
                label=f"J = {j:g} s/m, {_label(run)}",
            )
    ax.set(xlabel="penetration (µm)", ylabel="force on the soil (kN)", title="Smith soil: the force–penetration loop")
    ax.legend(fontsize=8)
    return fig


BLOWS = 6
BRANCH_CELLS = (250, 500, 1000, 2000, 4000)


def blows_report(figures: dict[str, Figure]) -> list[str]:
    """Blow after blow on rock at Lundberg's optimum (tests/test_blows.py): the set per blow."""
    grids = (
        ("the tests' grid", CF.BLOW_NUMERICS),
        ("fine", {"scheme": "explicit", "cells": 2000}),
        (f"tolerance {TOLERANCE:g}", {"tolerance": TOLERANCE}),
    )
    runs = [
        _solve(f"{BLOWS} blows", f"{name}" + (f" ({n['cells']} cells)" if "cells" in n else ""), CF.drilling(BLOWS, n))
        for name, n in grids
    ]
    _, single = CF.rock_penetration(CF.OPTIMUM)
    lines = [
        f"{BLOWS} blows of the equal piston on rock at x = {CF.OPTIMUM:g}, k_u = {CF.UNLOADING:g}·k, each "
        f"{CF.BLOW_DURATION * 1e6:.1f} µs (10·L/a). The first blow meets a tool at rest: its set is "
        f"Lundberg's permanent penetration, {single * 1e6:.3f} µm (the waves that come back within "
        "the blow reload the rock below its deepest penetration); the later blows meet fresh rock "
        "and the tool as the blows before left it.",
        "",
        "| blow | "
        + " | ".join(f"set, {run.numerics} (µm)" for run in runs)
        + " | "
        + " | ".join(f"η, {run.numerics}" for run in runs)
        + " |",
        "|---:|" + "---:|" * (2 * len(runs)),
    ]
    for blow in range(BLOWS):
        rows = [run.summary["blows"][blow] for run in runs]
        lines.append(
            f"| {blow + 1} | "
            + " | ".join(f"{row['set'] * 1e6:.3f}" for row in rows)
            + " | "
            + " | ".join(f"{row['transfer_efficiency']:.4f}" for row in rows)
            + " |"
        )
    lines += [
        "",
        "| numerics | last two sets differ by | Σ blows' to_medium / energy.to_medium − 1 | "
        "energy.initial / (6 launches) − 1 | withdrawn, share of initial |",
        "|---|---:|---:|---:|---:|",
    ]
    launch = 0.5 * CF.PISTON_MASS * CF.V**2
    for run in runs:
        s = run.summary
        sets = [b["set"] for b in s["blows"]]
        e = s["energy"]
        lines.append(
            f"| {run.numerics} | {sets[-1] / sets[-2] - 1:+.1e} | "
            f"{sum(b['to_medium'] for b in s['blows']) / e['to_medium'] - 1:+.1e} | "
            f"{e['initial'] / (BLOWS * launch) - 1:+.1e} | {e['striker_withdrawn'] / e['initial']:.2e} |"
        )
    lines += ["", *runs_table(runs), "", "![the set per blow](validation/blows.png)", "", *sets_on_grids(single)]
    figures["blows"] = _blows_figure(runs, single)
    return lines


def sets_on_grids(single: float) -> list[str]:
    """The set of each blow on a ladder of fixed grids: the rock's state depends on no rounding."""
    sets = {
        cells: [
            b["set"]
            for b in simulate_rod(parse_case(CF.drilling(BLOWS, {"scheme": "explicit", "cells": cells}))).summary[
                "blows"
            ]
        ]
        for cells in BRANCH_CELLS
    }
    lines = [
        "The same blows on a ladder of fixed grids (explicit scheme). Within a blow the rock "
        "remembers its deepest penetration: a wave that comes back reloads it at k_u up to "
        "there and crushes it at k beyond; each blow meets fresh rock.",
        "",
        "| cells | "
        + " | ".join(f"set, blow {b + 1} (µm)" for b in range(BLOWS))
        + " | first / Lundberg's single pass − 1 |",
        "|---:|" + "---:|" * (BLOWS + 1),
    ]
    for cells, row in sets.items():
        lines.append(f"| {cells} | " + " | ".join(f"{s * 1e6:.3f}" for s in row) + f" | {row[0] / single - 1:+.1e} |")
    return lines


def _blows_figure(runs: list[Run], single: float) -> Figure:
    fig = Figure(figsize=(7, 4.2), layout="constrained")
    ax = fig.subplots()
    blows = np.arange(1, BLOWS + 1)
    for run, marker in zip(runs, "osx"):
        ax.plot(
            blows, [b["set"] * 1e6 for b in run.summary["blows"]], marker + "-", mfc="none", label=f"{run.numerics}"
        )
    ax.axhline(single * 1e6, color="k", ls=":", label="Lundberg's permanent penetration (one loading)")
    ax.set(xlabel="blow", ylabel="set (µm)", title="Blow after blow on bilinear rock: the set per blow")
    ax.legend(fontsize=8)
    return fig


ANVIL_FINE = {"scheme": "explicit", "cells": 800}


def anvil_report(figures: dict[str, Figure]) -> list[str]:
    """The anvil against the case without one, two-body impact and the linear three-body system
    (tests/test_anvil.py)."""
    checks, runs = [], []
    stiff = {"stiffness": 1e13, "exponent": 0.0}
    without = CF.anvil_case(1e-6, ANVIL_FINE, anvil_contact=stiff)
    del without["anvil"]
    alone = _solve("no anvil", f"fine ({ANVIL_FINE['cells']} cells)", without)
    vanishing = _both("1-mg anvil", lambda n: CF.anvil_case(1e-6, n, anvil_contact=stiff), ANVIL_FINE)
    runs += vanishing
    for quantity, found in (
        ("peak contact force (kN)", lambda r: r.summary["peak_contact_force"]["value"]),
        ("max compressive stress (MPa)", lambda r: r.summary["max_compressive_stress"]["value"]),
        ("energy to the medium (J)", lambda r: r.summary["energy"]["to_medium"]),
    ):
        scale = 1e-3 if "kN" in quantity else 1e-6 if "MPa" in quantity else 1.0
        checks.append(
            Check(
                "1-mg anvil, against none",
                quantity,
                found(alone),
                found(vanishing[0]),
                found(vanishing[1]),
                1e-2,
                scale,
            )
        )
    k = 1e10
    for m1, ma in ((2.0, 1.0), (1.0, 3.0)):
        pair = _both(
            f"two bodies {m1:g}:{ma:g} kg",
            lambda n, a=m1, b=ma: CF.anvil_case(
                b,
                n,
                striker_mass=a,
                anvil_contact={"stiffness": 1e6, "exponent": 0.0},
                contact={"stiffness": k, "exponent": 0.0},
            ),
            ANVIL_FINE,
        )
        runs += pair
        v1, va, time = CF.two_body_impact(m1, ma, k)
        name = f"striker {m1:g} kg on anvil {ma:g} kg"
        checks += [
            Check(name, "contact time π·sqrt(μ/k) (µs)", time, *(r.summary["co_impact_time"] for r in pair), 5e-3, 1e6),
            Check(
                name,
                "striker after, share of v: (m1 − m_a)/(m1 + m_a)",
                v1 / CF.V,
                *(r.summary["striker_rebound_velocity"] / CF.V for r in pair),
                2e-3,
            ),
            Check(
                name,
                "anvil after, share of v: 2·m1/(m1 + m_a)",
                va / CF.V,
                *(_anvil_velocity(r) / CF.V for r in pair),
                2e-3,
            ),
        ]
    m1, ma, k = 2.0, 1.0, 2e9
    pulse = _both(
        "three bodies",
        lambda n: CF.anvil_case(
            ma,
            {**n, "duration": 4e-4},
            striker_mass=m1,
            anvil_contact={"stiffness": k, "exponent": 0.0},
            contact={"stiffness": k, "exponent": 0.0},
            tool={"length": 5.0, "area": CF.AREA, **CF.STEEL},
        ),
        ANVIL_FINE,
    )
    runs += pulse
    deviations = [_three_body_deviation(r, m1, ma, k) for r in pulse]
    for i, what in enumerate(("contact force F1", "force on the tool F2")):
        checks.append(
            Check(
                "2 kg on 1 kg, k1 = k2 = 2e9 N/m",
                f"{what}: largest deviation, share of its peak",
                0.0,
                deviations[0][i],
                deviations[1][i],
                1e-2,
            )
        )
    single = dict(pulse[0].result.case.model_dump(exclude_none=True))
    del single["anvil"]
    figures["anvil"] = _anvil_figure(pulse[0], _solve("no anvil", "fine", single), m1, ma, k)
    return [
        "A lumped striker at 10 m/s on an anvil resting on a 1-m steel tool (10 cm²) through its own "
        "contact. A 1-mg anvil on a contact 5000 times as stiff as the striker's passes the contact "
        "force on: the case without one. Two-body impact: a contact of 1e10 N/m between striker and "
        "anvil, the anvil on a contact 1e4 times as soft (the tool takes next to nothing while they "
        "part). The three-body system: linear contacts on a 5-m tool, the forces against the matrix "
        "exponential of `m1·y'' = −k1·(y − y_a)`, `m_a·y_a'' = k1·(y − y_a) − k2·(y_a − u_0)`, "
        "`Z·u_0' = k2·(y_a − u_0)` until a contact opens.",
        "",
        *checks_table(checks),
        "",
        *runs_table(runs),
        "",
        "![the pulse an anvil prolongs](validation/anvil.png)",
    ]


def _anvil_velocity(run: Run) -> float:
    h = run.result.history
    return float(np.interp(run.summary["co_impact_time"], h["time"], h["anvil/velocity"]))


def _three_body_deviation(run: Run, m1: float, ma: float, k: float) -> tuple[float, float]:
    h = run.result.history
    t = h["time"]
    inside = (t < run.summary["co_impact_time"]) & (h["anvil/force"] > 0.0)
    f1, f2 = CF.linear_three_bodies(m1, ma, k, k, t[inside])
    return (
        float(np.abs(h["contact/force"][inside] - f1).max() / f1.max()),
        float(np.abs(h["anvil/force"][inside] - f2).max() / f2.max()),
    )


def _anvil_figure(run: Run, alone: Run, m1: float, ma: float, k: float) -> Figure:
    fig = Figure(figsize=(7, 4.2), layout="constrained")
    ax = fig.subplots()
    h = run.result.history
    t = h["time"]
    ax.plot(t * 1e6, h["anvil/force"] / 1e3, color="C0", lw=1.6, label="force on the tool, with the anvil")
    ax.plot(t * 1e6, h["contact/force"] / 1e3, color="C1", lw=1.0, label="striker–anvil contact force")
    closed = t[t < run.summary["co_impact_time"]]
    f1, f2 = CF.linear_three_bodies(m1, ma, k, k, closed)
    ax.plot(closed * 1e6, f2 / 1e3, "k--", lw=0.9, label="linear three-body system")
    ax.plot(
        alone.result.history["time"] * 1e6,
        alone.result.history["contact/force"] / 1e3,
        color="0.5",
        lw=1.0,
        label=f"the {m1:g}-kg striker alone",
    )
    ends = [
        times[force > 0.01 * force.max()][-1]
        for times, force in (
            (t, h["anvil/force"]),
            (alone.result.history["time"], alone.result.history["contact/force"]),
        )
    ]
    ax.set(
        xlabel="time (µs)",
        ylabel="force (kN)",
        xlim=(0, 1.1e6 * max(ends)),
        title=f"A {ma:g}-kg anvil prolongs the pulse of a {m1:g}-kg striker",
    )
    ax.legend(fontsize=8)
    return fig


def report(figures: dict[str, Figure]) -> str:
    """The markdown; the figures it refers to are added to `figures` by name."""
    start = perf_counter()
    sections = [
        ("Reference 1: linear contact on a long rod", reference_ladder(figures)),
        ("A Hertz contact on a tapered tool, refined at Courant number 0.5", tapered_ladder()),
        ("Rigid-tool limit: the rod model tends to the model problem", rigid_limit(figures)),
        ("The paper's Fig. 3", fig3()),
        ("A contact damper: the damped oscillator on a long rod", damped_contact()),
        ("Saint-Venant's rigid impact on a bar with a fixed end", saint_venant()),
        ("Contacts far stiffer than the tool's end cell", stiff_contacts()),
        ("The contact force, as the scheme applies it", recorded_force_report()),
        ("The elastic striker: one-dimensional impact", piston_report(figures)),
        ("Bilinear rock: Lundberg's efficiency", rock_report(figures)),
        ("Smith soil: the set and the loop", soil_report(figures)),
        ("Blow after blow", blows_report(figures)),
        ("The anvil: two-body impact and the pulse it prolongs", anvil_report(figures)),
        *pile_sections(),
        *cycle_sections(),
        *matching_sections(),
    ]
    out = [
        "# Validation",
        "",
        "Produced by `bench/validation.py --write docs/validation.md`, tables and figures; rerun it to "
        "check every number. The test suite holds the solver to the same references with the same "
        "code (`percussim/testing/reference.py`): `tests/test_reference.py`, `tests/test_schemes.py`, "
        "`tests/test_convergence.py`, `tests/test_lumped.py`, `tests/test_energy.py`; the models beyond "
        "the paper, with the cases and closed forms of `percussim/testing/closed_forms.py`: "
        "`tests/test_striker_rod.py`, `tests/test_media.py`, `tests/test_blows.py`, `tests/test_anvil.py`; piles: "
        "`tests/test_shaft.py`, `tests/test_gravity.py`, `tests/test_cushion.py`, `tests/test_struck_end.py`, "
        "`tests/test_smith_model.py`; a hammer at work: `tests/test_drive.py`; signal matching: "
        "`tests/test_signal_match.py`, `tests/test_pile_record.py`, `tests/test_load_test.py`. An energy "
        "residual is `energy.numerical` over the energy supplied.",
        "",
    ]
    for title, lines in sections:
        out += [f"## {title}", "", *lines, ""]
    out += [f"This report took {perf_counter() - start:.0f} s to compute (one process)."]
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
