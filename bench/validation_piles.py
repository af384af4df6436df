"""The piles' sections of docs/validation.md (`bench/validation.py` writes them with the rest):
soil along the shaft, gravity, a cushion and a driven struck end against closed forms, and a
driven pile against Smith's lumped-mass model, an independent discretisation. The cases and
formulas are the tests' own (percussim/testing/closed_forms.py, smith_model.py; tests/test_shaft.py,
tests/test_gravity.py, tests/test_cushion.py, tests/test_struck_end.py, tests/test_smith_model.py).
"""

from __future__ import annotations

from time import perf_counter

import numpy as np

from percussim.solver.case import parse_case
from percussim.solver.grid import make_grid
from percussim.solver.pile_studies import bearing_graph
from percussim.solver.rest import at_rest
from percussim.solver.simulate import simulate
from percussim.testing import closed_forms as CF
from percussim.testing.reference import ringing
from percussim.testing.smith_model import smith_pile

G = 9.81


def _row(what: str, expected: float, found: float, unit: str, scale: float = 1.0) -> str:
    error = abs(found / expected - 1.0) if expected else abs(found)
    return f"| {what} | {expected * scale:.6g} {unit} | {found * scale:.6g} {unit} | {error:.2e} |"


def closed_forms_table() -> list[str]:
    """Each closed form against the solver, as the tests hold them."""
    started = perf_counter()
    rows = []
    # the rigid-body mode of a free pile on elastic shaft springs
    case = CF.free_pile_on_springs(frequency_hz=50.0)
    result = simulate(case)
    grid = make_grid(parse_case(case).tool, case["numerics"]["cells"], end_masses=True)
    shaft = case["shaft"][0]
    omega = CF.shaft_rigid_mode(shaft["ultimate_resistance"] / shaft["quake"] / 10.0, 7850.0, 0.01)
    rows.append(
        _row(
            "rigid-body mode ω0 = √(k′/(ρA)) of a free pile on shaft springs",
            omega,
            ringing(result, grid).omega,
            "rad/s",
        )
    )
    # the static compression of a uniform pile on shaft and toe springs under its weight
    pile = parse_case(CF.pile_under_its_weight())
    grid = make_grid(pile.tool, 400, end_masses=False)
    rest = at_rest(pile, grid)
    tool, soil, toe = pile.tool, pile.shaft[0], pile.medium
    exact = CF.static_compression(
        grid.x,
        length=tool.length,
        stiffness=tool.area * tool.youngs_modulus,
        weight_per_length=tool.density * tool.area * G,
        shaft_stiffness_per_length=soil.ultimate_resistance / soil.quake / tool.length,
        toe_stiffness=toe.ultimate_resistance / toe.quake,
    )
    rows.append(
        _row(
            "static compression of a 20-m pile at its head, under its weight (400 cells)",
            exact[0],
            rest.u[0],
            "µm",
            1e6,
        )
    )
    rows.append(_row("… at its toe", exact[-1], rest.u[-1], "µm", 1e6))
    drift = simulate(parse_case(CF.pile_under_its_weight(anvil=True) | {"outputs": {"fields": True}})).fields
    moved = np.max(np.abs(drift.displacement - drift.displacement[0])) / np.max(np.abs(drift.displacement[0]))
    rows.append(
        f"| the pile left at rest by a 1-mg ram: its largest move over its compression | 0 | {moved:.2e} | {moved:.2e} |"
    )
    # a cushion with restitution against a near-rigid wall
    for e in (0.8, 0.5):
        summary = simulate(CF.cushion_on_a_wall(e)).summary
        rebound, duration = CF.cushion_rebound(100.0, 1e8, 2.0, e)
        contact = summary["contacts"][0]
        rows.append(_row(f"cushion e = {e}: rebound −e·v", rebound, summary["striker_rebound_velocity"], "m/s"))
        rows.append(
            _row(
                f"cushion e = {e}: contact time (π/2)·√(m/k)·(1 + e)",
                duration,
                contact["end"] - contact["start"],
                "ms",
                1e3,
            )
        )
    return [
        "| closed form | expected | solver | relative error |",
        "|---|---|---|---|",
        *rows,
        "",
        f"({perf_counter() - started:.1f} s)",
    ]


def smith_toe_table() -> list[str]:
    """The Smith toe's set under a rectangular force F_i lasting T, read through a bearing graph's
    rows (the toe takes all the capacity): `(2F_i − R_u)(T − t_q)/Z` for F_i ≤ R_u < 2F_i, and
    refusal from R_u = 2F_i on."""
    started = perf_counter()
    quake = CF.SOIL_RESISTANCE / CF.SOIL_STIFFNESS
    case = CF.rectangular_force_case({"scheme": "explicit", "cells": 1000}, quake=quake) | {"blows": {"count": 1}}
    capacities = [share * CF.INCIDENT for share in (1.0, 1.2, 1.4, 1.6, 1.8, 1.95, 2.0, 2.2)]
    graph = bearing_graph({"case": case, "capacity": capacities}, processes=1)
    lines = [
        "| R_u / F_i | closed-form set | bearing graph's set | relative error | blow count (1/m) |",
        "|---|---|---|---|---|",
    ]
    for row in graph["rows"]:
        resistance = row["ultimate_resistance"]
        _, expected = CF.smith_set(resistance, resistance / quake)
        found = row["set"]
        if expected > 0:
            error = f"{abs(found / expected - 1.0):.2e}"
        else:
            error = f"refusal: set {found * 1e3:.2g} mm"
        count = "refusal" if row["blow_count"] is None else f"{row['blow_count']:.4g}"
        lines.append(
            f"| {resistance / CF.INCIDENT:.3g} | {expected * 1e3:.5g} mm | {found * 1e3:.5g} mm | {error} | {count} |"
        )
    return [*lines, "", f"({perf_counter() - started:.1f} s)"]


def cross_check_table() -> list[str]:
    """A driven pile (shaft and toe yielding, dampers, a cushion of e = 0.8) against Smith's
    lumped-mass model on 600 masses, and the energy audit."""
    started = perf_counter()
    case = CF.driven_pile({"duration": 0.03, "tolerance": 1e-3})
    result = simulate(parse_case(case))
    summary = result.summary
    smith = smith_pile(case, segments=600, courant=0.25)
    energy = summary["energy"]
    lines = [
        "| quantity | Smith's lumped model (600 masses) | percussim (tolerance 1e-3) | relative difference |",
        "|---|---|---|---|",
        _row("set", smith.set, summary["set"], "mm", 1e3),
        _row("peak force at the head", smith.peak_force, summary["peak_contact_force"]["value"], "MN", 1e-6),
        _row(
            "largest compression", smith.max_compressive_stress, summary["max_compressive_stress"]["value"], "MPa", 1e-6
        ),
        _row("transferred energy (EMX)", smith.transferred, energy["transferred"], "kJ", 1e-3),
        _row("the ram's velocity at the end", smith.ram_velocity, result.history["striker/velocity"][-1], "m/s"),
    ]
    supplied = energy["initial"] + max(energy["external_work"], 0.0)
    return [
        *lines,
        "",
        f"The energy audit of the same run: to the shaft {energy['to_shaft'] / 1e3:.4g} kJ, to the toe "
        f"{energy['to_medium'] / 1e3:.4g} kJ, the cushion's loss {energy['dissipated_contact'] / 1e3:.4g} kJ, "
        f"of {supplied / 1e3:.4g} kJ supplied; the residual `energy.numerical` is "
        f"{energy['numerical'] / supplied:.2e} of it ({len(summary['runs'])} grids, finest "
        f"{summary['runs'][-1]['cells']} cells).",
        "",
        f"({perf_counter() - started:.1f} s)",
    ]


def gravity_audit() -> list[str]:
    """The energy audit under gravity with shaft and toe yielding, two blows, a helmet resting
    between them (tests/test_gravity.py's case)."""
    started = perf_counter()
    case = CF.yielding_pile_under_gravity(blows={"count": 2})
    summary = simulate(parse_case(case)).summary
    e = summary["energy"]
    supplied = e["initial"] + abs(e["gravity_work"]) + e["stored_at_rest"]
    sets = ", ".join(f"{blow['set'] * 1e3:.4g} mm" for blow in summary["blows"])
    return [
        "| energy (J) | |",
        "|---|---|",
        f"| the rams' m·g·h, and the helmet set at rest on its cushion (`initial`) | {e['initial']:.6g} |",
        f"| the weights' work (`gravity_work`) | {e['gravity_work']:.6g} |",
        f"| stored at rest before the first blow (`stored_at_rest`) | {e['stored_at_rest']:.4g} |",
        f"| to the shaft (`to_shaft`) | {e['to_shaft']:.6g} |",
        f"| to the toe (`to_medium`) | {e['to_medium']:.6g} |",
        f"| lost in the cushions (`dissipated_contact`) | {e['dissipated_contact']:.6g} |",
        f"| the residual (`numerical`), over what was supplied | {e['numerical'] / supplied:.2e} |",
        "",
        f"Sets of the two blows: {sets}. ({perf_counter() - started:.1f} s)",
    ]


def pile_sections() -> list[tuple[str, list[str]]]:
    """(title, lines) of each pile section."""
    return [
        ("Piles: soil along the shaft, gravity, a cushion, against closed forms", closed_forms_table()),
        ("Piles: a Smith toe's set under a rectangular force, read through a bearing graph", smith_toe_table()),
        ("Piles: the energy audit under gravity, shaft and toe yielding", gravity_audit()),
        ("Piles: a driven pile against Smith's lumped-mass model", cross_check_table()),
    ]


if __name__ == "__main__":
    for title, lines in pile_sections():
        print(f"## {title}\n")
        print("\n".join(lines))
        print()
