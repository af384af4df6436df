"""Signal matching's section of docs/validation.md (`bench/validation.py` writes it with the rest):
the soil of a 10-m pile recovered from a head record made by an independent run (2% noise), the
non-uniqueness warning where the record cannot tell the shaft from the toe, the Case method against
its closed form, and the static load test against its closed form and a rigid-plastic soil's
plunge. The cases are the tests' own (percussim/testing/pile_records.py, closed_forms.py;
tests/test_signal_match.py, test_pile_record.py, test_load_test.py).
"""

from __future__ import annotations

from time import perf_counter

import numpy as np

from percussim.solver.case import parse_case
from percussim.solver.grid import make_grid
from percussim.solver.pile_record import case_method
from percussim.solver.rest import static_load_test
from percussim.solver.signal_match import signal_match
from percussim.solver.simulate import simulate
from percussim.testing import closed_forms as CF
from percussim.testing.pile_records import SHAFT, TOE, head_record, pile

TRUTH = {
    "shaft.0.ultimate_resistance": SHAFT[0]["ultimate_resistance"],
    "shaft.*.quake": SHAFT[0]["quake"],
    "shaft.*.damping_factor": SHAFT[0]["damping_factor"],
    "medium.ultimate_resistance": TOE["ultimate_resistance"],
    "medium.quake": TOE["quake"],
    "medium.damping_factor": TOE["damping_factor"],
}


def guess(**changes) -> dict:
    """The test pile with every soil value guessed wrong: resistances 1.5 and 0.6 times the truth's,
    quakes 4 mm, damping factors 0.4 and 0.3 s/m."""
    shaft = [
        s | {"ultimate_resistance": 1.5 * s["ultimate_resistance"], "quake": 4e-3, "damping_factor": 0.4}
        for s in changes.pop("shaft", SHAFT)
    ]
    toe = TOE | {"ultimate_resistance": 0.6 * TOE["ultimate_resistance"], "quake": 4e-3, "damping_factor": 0.3}
    return pile(shaft=shaft, medium=toe, **changes)


def recovery() -> list[str]:
    """The default unknowns of the test pile matched to its record: each against the truth."""
    start = perf_counter()
    match = signal_match({"case": guess(), "record": head_record(pile())}, processes=1)
    rows = ["| unknown | truth | matched | standard error | off by |", "|---|---|---|---|---|"]
    for path, truth in TRUTH.items():
        found = match["parameters"][path]
        rows.append(
            f"| `{path}` | {truth:.4g} | {found['value']:.4g} | {found['standard_error']:.2g} | "
            f"{abs(found['value'] - truth) / found['standard_error']:.2f} σ |"
        )
    capacity, truth = match["capacity"], SHAFT[0]["ultimate_resistance"] + TOE["ultimate_resistance"]
    test = match["static_load_test"]
    names = list(match["parameters"])
    pairs = [
        f"`{a}` and `{b}` ({match['correlation'][i][j]:.3f})"
        for i, a in enumerate(names)
        for j, b in enumerate(names[i + 1 :], i + 1)
        if abs(match["correlation"][i][j]) > 0.95
    ]
    rows += [
        f"| capacity | {truth:.4g} | {capacity['value']:.4g} | {capacity['standard_error']:.2g} | "
        f"{abs(capacity['value'] - truth) / capacity['standard_error']:.2f} σ |",
        "",
        f"Match quality {match['match_quality']['value']:.3g} (2L/c window {match['match_quality']['window']:.3g}). "
        f"The static load test of the fitted soil holds {test['load'][-1] / 1e3:.6g} kN at "
        f"{test['settlement'][-1] * 1e3:.3g} mm, the fitted capacity within "
        f"{abs(test['load'][-1] / capacity['value'] - 1):.1e}. Pairs the record does not tell apart, each "
        f"named in a warning: {', '.join(pairs) or 'none'}. {match['evaluations']} runs on "
        f"{match['grid']['cells']} cells, {perf_counter() - start:.0f} s on one process.",
    ]
    return rows


def uniqueness() -> list[str]:
    """Soil along the last half metre only and a record that ends just after 2L/c: the shaft's and
    the toe's answers reach the gauges together."""
    near = [dict(SHAFT[0], **{"from": 9.5})]
    short = {"duration": 0.0062}
    resistances = {"shaft.0.ultimate_resistance": [5e4, 4e6], "medium.ultimate_resistance": [5e4, 4e6]}
    match = signal_match(
        {
            "case": pile(shaft=[s | {"ultimate_resistance": 6e5} for s in near], numerics=short),
            "record": head_record(pile(shaft=near, numerics=short)),
            "parameters": resistances,
        },
        processes=1,
    )
    names = list(match["parameters"])
    r = match["correlation"][names.index("shaft.0.ultimate_resistance")][names.index("medium.ultimate_resistance")]
    warned = [w for w in match["warnings"] if "strongly correlated" in w]
    parts = [match["parameters"][p] for p in resistances]
    capacity = match["capacity"]
    return [
        "| | matched | standard error |",
        "|---|---|---|",
        *(
            f"| `{p}` (truth 4e+05) | {q['value']:.4g} | {q['standard_error']:.2g} |"
            for p, q in zip(resistances, parts)
        ),
        f"| capacity (truth 8e+05) | {capacity['value']:.4g} | {capacity['standard_error']:.2g} |",
        "",
        f'Correlation of the two resistances {r:.3f}; the warning: "{warned[0] if warned else "NONE"}".',
    ]


def case_method_table() -> list[str]:
    """A uniform pile driven by a rectangular force F_i, its toe on a rigid-plastic soil of R_u:
    RMX = R_u − J_c·(2·F_i − R_u)."""
    case = CF.rectangular_force_case({"scheme": "explicit", "cells": 1000}, quake=1e-9)
    case["numerics"]["duration"] = 2.2 * CF.TOOL / CF.SPEED + CF.T
    h = simulate(parse_case(case)).history
    velocity = np.gradient(h["tool/struck_end_displacement"], h["time"])
    rows = ["| J_c | closed form R_u − J_c·(2·F_i − R_u) | Case method | relative error |", "|---|---|---|---|"]
    for row in case_method(h["time"], h["contact/force"], velocity, CF.Z, 2 * CF.TOOL / CF.SPEED):
        closed = CF.SOIL_RESISTANCE - row["damping_factor"] * (2 * CF.INCIDENT - CF.SOIL_RESISTANCE)
        rows.append(
            f"| {row['damping_factor']:g} | {closed / 1e3:.6g} kN | {row['capacity'] / 1e3:.6g} kN | "
            f"{abs(row['capacity'] / closed - 1):.1e} |"
        )
    return rows


def load_test_table() -> list[str]:
    """A 20-m pile on a Smith toe alone, s = P·L/(E·A) + P·q/R_u; and on a rigid-plastic shaft and
    toe, which holds to Σr + R_u."""
    tool = {"length": 20.0, "youngs_modulus": 2.1e11, "density": 7850.0, "area": 0.01}
    drive = {"velocity": {"time": [0.0, 1e-3], "values": [1.0, 1.0]}}

    def test(medium: dict, shaft: list | None = None) -> dict:
        case = parse_case(
            {"tool": tool, "medium": medium, "struck_end": drive, "numerics": {"duration": 0.01}}
            | ({"shaft": shaft} if shaft else {})
        )
        return static_load_test(case, make_grid(case.tool, 200, end_masses=True))

    r_u, quake = 2e6, 2.5e-3
    spring = test({"kind": "smith", "ultimate_resistance": r_u, "quake": quake, "damping_factor": 0.5})
    load, settlement = np.array(spring["load"]), np.array(spring["settlement"])
    closed = load * 20.0 / (2.1e11 * 0.01) + load * quake / r_u
    worst = float(np.max(np.abs(settlement[1:] / closed[1:] - 1)))
    rigid = [
        {"from": 5.0, "to": 12.0, "ultimate_resistance": 6e5, "quake": 1e-6, "damping_factor": 0.2},
        {"from": 12.0, "to": 20.0, "ultimate_resistance": 9e5, "quake": 1e-6, "damping_factor": 0.2},
    ]
    plunge = test({"kind": "smith", "ultimate_resistance": 5e5, "quake": 1e-6, "damping_factor": 0.5}, rigid)
    return [
        "| closed form | expected | load test | relative error |",
        "|---|---|---|---|",
        f"| toe alone: settlement P·L/(E·A) + P·q/R_u, worst of {len(load) - 1} loads | "
        f"{closed[-1] * 1e3:.5g} mm at {load[-1] / 1e3:.5g} kN | {settlement[-1] * 1e3:.5g} mm | {worst:.1e} |",
        f"| rigid-plastic shaft and toe: the largest load held, Σr + R_u | 2000 kN | {plunge['load'][-1] / 1e3:.6g} kN | "
        f"{abs(plunge['load'][-1] / 2e6 - 1):.1e} |",
    ]


def matching_sections() -> list[tuple[str, list[str]]]:
    """(title, lines) of each signal-matching section."""
    return [
        (
            "Signal matching: a known soil recovered from its head record",
            [
                "The 10-m test pile (`percussim/testing/pile_records.py`: sand along its lower 7 m and at its toe, "
                "400 kN each) struck by a 2-MN half-sine; its head record made by an independent run (the explicit "
                "scheme on 2000 cells, driven by the force, where the match runs the velocity-driven pile on its own "
                "grid), sampled at 20 kHz with 2% noise on force and velocity. The match starts from every soil value "
                "guessed wrong (resistances 1.5× and 0.6×, quakes 4 mm, damping factors 0.4 and 0.3 s/m) and fits "
                "the 6 default unknowns.",
                "",
                *recovery(),
            ],
        ),
        (
            "Signal matching: a record that cannot tell the shaft from the toe",
            [
                "Soil along the last half metre only, and a record that ends just after 2L/c: both answers reach the "
                "gauges together, so only their sum is known.",
                "",
                *uniqueness(),
            ],
        ),
        ("Signal matching: the Case method against its closed form", case_method_table()),
        ("Signal matching: the static load test", load_test_table()),
    ]


if __name__ == "__main__":
    for title, lines in matching_sections():
        print(f"## {title}\n")
        print("\n".join(lines))
        print()
