"""The work cycle's section of docs/validation.md (`bench/validation.py` writes it with the rest): a
hammer's hydraulic drive between blows against the closed forms of ideal hydraulics, its energy
audit, the accumulator's gas law, the supply's work a cycle, a matched piston struck from rest
cycle after cycle, the adaptive stroke, and the rock drill's cycle preset at the default accuracy.
The cases and formulas are the tests' own (percussim/testing/closed_forms.py; tests/test_drive.py).
"""

from __future__ import annotations

import math
from dataclasses import replace
from time import perf_counter

import numpy as np

from percussim.solver.case import parse_case
from percussim.solver.drive import Valve, fly
from percussim.solver.presets import load_preset
from percussim.solver.simulate import simulate
from percussim.testing import closed_forms as CF

IDEAL = CF.IDEAL_DRIVE
RETURNING = CF.RETURNING


def _row(what: str, expected: str, found: str, error: float) -> str:
    return f"| {what} | {expected} | {found} | {error:.1e} |"


def flights() -> list[str]:
    """A flight from the impact point under ideal hydraulics, and the work and gas law of one
    that is not ideal."""
    rows = []
    for rebound in (0.0, -3.0, -8.0):
        flight = fly(IDEAL, 0.0, rebound, 0.0, 0.0, RETURNING)
        t_back, t_in, v_impact = CF.ideal_flight(IDEAL, 0.0, rebound, 0.0)
        closed = math.sqrt(2 * 15e6 * 3e-4 * 0.05 / 2.0 + rebound**2)
        rows.append(
            _row(
                f"impact velocity √(2·p_s·A_r·s/m + v_r²), rebound {rebound:g} m/s",
                f"{closed:.6g} m/s",
                f"{flight.impact_velocity:.6g} m/s",
                abs(flight.impact_velocity / closed - 1),
            )
        )
        rows.append(
            _row(
                f"time back and in, rebound {rebound:g} m/s",
                f"{1e3 * (t_back + t_in):.6g} ms",
                f"{1e3 * flight.duration:.6g} ms",
                abs(flight.duration / (t_back + t_in) - 1),
            )
        )
    drive = CF.LOSSY_DRIVE
    flight = fly(drive, 1e-3, -4.0, 0.0, drive.gas_volume(drive.supply_pressure), Valve(0.0, 0.0, 1.0))
    change = 0.5 * drive.mass * (flight.impact_velocity**2 - 4.0**2)
    work = flight.supplied + flight.returned + flight.rubbed + flight.lifted
    rows.append(
        _row(
            "a flight's work (supply, return line, friction, weight; pump, accumulator, valve time) = ½m(v_i² − v_r²)",
            f"{change:.6g} J",
            f"{work:.6g} J",
            abs(work / change - 1),
        )
    )
    gas = replace(IDEAL, accumulator_volume=2e-4, precharge=8e6, polytropic_exponent=1.3)
    start_gas = gas.gas_volume(12e6)
    flight = fly(gas, 0.0, -3.0, 0.0, start_gas, RETURNING)
    y = flight.displacement
    drawn = -gas.front_area * y + np.where(flight.time > flight.switched, gas.rear_area * (y + gas.stroke), 0.0)
    expected = 8e6 * (2e-4 / (start_gas + drawn)) ** 1.3
    worst = float(np.max(np.abs(flight.supply_pressure / expected - 1)))
    rows.append(
        _row(
            "the accumulator's pressure p_0·(V_0/V_gas)^n over a flight, worst of its records",
            f"{expected.min() / 1e6:.4g}–{expected.max() / 1e6:.4g} MPa",
            f"{flight.supply_pressure.min() / 1e6:.4g}–{flight.supply_pressure.max() / 1e6:.4g} MPa",
            worst,
        )
    )
    return rows


def cycles() -> list[str]:
    """Cycles end to end: each against the closed form from the state its blow left, the supply's
    work a cycle, and a matched piston struck from rest."""
    rows = []
    result = simulate(parse_case(CF.hammer_at_work(cycles={"count": 8})))
    cycle = result.summary["cycle"]
    errors = [
        abs(cycle["impact_velocity"][k + 1] / CF.ideal_flight(IDEAL, *end)[2] - 1)
        for k, end in enumerate(CF.blow_ends(result))
    ]
    rows.append(
        _row(
            "8 cycles of the ideal hammer: each impact velocity from the state its blow left, worst",
            "closed form",
            f"{min(cycle['impact_velocity'][1:]):.4g}–{max(cycle['impact_velocity'][1:]):.4g} m/s",
            max(errors),
        )
    )
    sets = [blow["set"] for blow in result.summary["blows"]][:-1]
    last = math.ceil(0.5 * len(cycle["cycle_time"]))
    expected = float(np.mean([CF.supply_work_per_cycle(15e6, 3e-4, 1e-4, 0.05, d) for d in sets[-last:]]))
    found = cycle["hydraulic_power"] / cycle["frequency"]
    rows.append(
        _row(
            "the supply's work a cycle p_s·(A_r·s − A_f·Δ), mean of the last half",
            f"{expected:.6g} J",
            f"{found:.6g} J",
            abs(found / expected - 1),
        )
    )
    piston = {"velocity": 8.0, "length": 0.12, "youngs_modulus": 2.1e11, "density": 7800.0, "area": 1e-3}
    matched = CF.hammer_at_work(
        striker=piston,
        contact={"stiffness": 1e12, "exponent": 0.0},
        numerics={"duration": 1.5e-4, "scheme": "explicit", "cells": 200},
        cycles={"count": 3},
    )
    velocities = simulate(parse_case(matched)).summary["cycle"]["impact_velocity"]
    closed = math.sqrt(2 * 15e6 * 3e-4 * 0.05 / (7800.0 * 1e-3 * 0.12))
    rows.append(
        _row(
            "an elastic piston of the rod's impedance stops dead; struck again from rest, √(2·p_s·A_r·s/m)",
            f"{closed:.6g} m/s",
            f"{velocities[2]:.6g} m/s",
            max(abs(v / closed - 1) for v in velocities[1:]),
        )
    )
    summary = simulate(parse_case(CF.lundberg_cycles(4))).summary
    eta = CF.lundberg(CF.OPTIMUM)
    shares = [blow["transfer_efficiency"] for blow in summary["blows"]]
    rows.append(
        _row(
            "4 cycles of the equal piston on Lundberg's rock (x = 1.2564): each blow meets the tool at rest, "
            "the rock's share of it, worst",
            f"{eta:.6g}",
            f"{min(shares):.6g}–{max(shares):.6g}",
            max(abs(share / eta - 1) for share in shares),
        )
    )
    mass = CF.PISTON_MASS
    reflected = (1 - eta) * sum(0.5 * mass * v * v for v in summary["cycle"]["impact_velocity"][:-1])
    spent = summary["energy"]["dissipated_between_blows"]
    rows.append(
        _row(
            "what the rock sent back, spent as the tool comes to rest between blows: (1 − η)·Σ½m·v² "
            "of the blows but the last",
            f"{reflected:.6g} J",
            f"{spent:.6g} J",
            abs(spent / reflected - 1),
        )
    )
    return rows


def adaptive() -> list[str]:
    """The adaptive stroke on soft and hard rock, toward a set of 1.6 mm a blow."""
    lines = ["| rock's loading stiffness | last blow's set | its error | stroke: first → last |", "|---|---|---|---|"]
    for stiffness in (5e7, 1.5e8):
        case = CF.hammer_at_work(cycles={"count": 16})
        case["medium"] = {"kind": "bilinear", "stiffness": stiffness, "unloading_stiffness": 10 * stiffness}
        case["drive"]["control"] = {"kind": "adaptive", "target_set": 1.6e-3, "min_stroke": 0.01, "max_stroke": 0.3}
        summary = simulate(parse_case(case)).summary
        last = summary["blows"][-1]["set"]
        strokes = summary["cycle"]["stroke"]
        lines.append(
            f"| {stiffness:.3g} N/m | {1e3 * last:.4g} mm | {abs(last / 1.6e-3 - 1):.1e} | "
            f"{1e3 * strokes[0]:.4g} → {1e3 * strokes[-1]:.4g} mm |"
        )
    return lines


def preset() -> list[str]:
    started = perf_counter()
    summary = simulate(load_preset("rock_drill_cycle")).summary
    seconds = perf_counter() - started
    c = summary["cycle"]
    estimate = summary["error_estimate"]
    return [
        f"The `rock_drill_cycle` preset at the default accuracy ({seconds:.1f} s, grids "
        f"{', '.join(str(run['cells']) for run in summary['runs'])} cells): {c['frequency']:.3g} blows a "
        f"second of {c['impact_energy']:.4g} J, an impact power of {c['impact_power'] / 1e3:.3g} kW from "
        f"{c['hydraulic_power'] / 1e3:.3g} kW of hydraulic power, {100 * c['efficiency']:.3g}% of it to the rock, "
        f"{'repeating' if c['periodic'] else 'not yet repeating'} after {len(c['impact_velocity'])} cycles. "
        f"Estimated errors: impact velocity {estimate['cycle.impact_velocity']:.1e}, frequency "
        f"{estimate['cycle.frequency']:.1e}, impact energy {estimate['cycle.impact_energy']:.1e}, efficiency "
        f"{estimate['cycle.efficiency']:.1e}; worst {estimate['worst']:.1e}.",
    ]


def cycle_sections() -> list[tuple[str, list[str]]]:
    started = perf_counter()
    table = ["| closed form | expected | found | relative error |", "|---|---|---|---|", *flights(), *cycles()]
    lines = [
        "Between blows the tool comes to rest on the medium and the striker flies under the drive, an "
        "ODE integrated to 1e-9 (`solver/drive.py`, `solver/kernel/flight.py`); with ideal hydraulics (constant pressures, an instant valve, no "
        "friction) its flight has a closed form (`closed_forms.ideal_flight`). Rebounds are "
        "velocities away from the tool.",
        "",
        *table,
        "",
        "The adaptive stroke (`drive.control`), 16 cycles toward a set of 1.6 mm a blow: harder rock, a longer stroke.",
        "",
        *adaptive(),
        "",
        *preset(),
        "",
        f"This section took {perf_counter() - started:.0f} s.",
    ]
    return [("A hammer at work: the drive between blows", lines)]
