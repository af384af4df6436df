"""A static load test from a pile's soil (`solver/rest.py`: `static_load_test`): against the closed
form of a pile on a toe spring, and a rigid-plastic soil plunging at its total resistance."""

from __future__ import annotations

import numpy as np
import pytest

from percussim.solver.case import parse_case
from percussim.solver.grid import make_grid
from percussim.solver.rest import static_load_test

PILE = {"length": 20.0, "youngs_modulus": 2.1e11, "density": 7850.0, "area": 0.01}


def pile(medium: dict, shaft: list | None = None) -> dict:
    case = {"tool": PILE, "medium": medium, "struck_end": {"velocity": {"time": [0.0, 1e-3], "values": [1.0, 1.0]}}}
    return case | {"numerics": {"duration": 0.01}} | ({"shaft": shaft} if shaft else {})


def test_a_pile_on_its_toe_settles_by_its_shortening_and_the_toes_quake():
    """On Smith soil at the toe alone (R_u, quake q): s = P·L/(E·A) + P·q/R_u until P reaches R_u."""
    r_u, quake = 2e6, 2.5e-3
    case = parse_case(pile({"kind": "smith", "ultimate_resistance": r_u, "quake": quake, "damping_factor": 0.5}))
    test = static_load_test(case, make_grid(case.tool, 200, end_masses=True))
    load, settlement = np.array(test["load"]), np.array(test["settlement"])
    expected = load * 20.0 / (2.1e11 * 0.01) + load * quake / r_u
    assert settlement == pytest.approx(expected, rel=1e-9, abs=1e-15)
    assert load[-1] == pytest.approx(r_u, rel=1e-5) and len(load) == 41


def test_a_rigid_plastic_soil_holds_until_its_total_resistance():
    """Quakes of 1 µm: the head barely moves until the load reaches Σr + R_u, where it plunges."""
    shaft = [
        {"from": 5.0, "to": 12.0, "ultimate_resistance": 6e5, "quake": 1e-6, "damping_factor": 0.2},
        {"from": 12.0, "to": 20.0, "ultimate_resistance": 9e5, "quake": 1e-6, "damping_factor": 0.2},
    ]
    toe = {"kind": "smith", "ultimate_resistance": 5e5, "quake": 1e-6, "damping_factor": 0.5}
    case = parse_case(pile(toe, shaft))
    test = static_load_test(case, make_grid(case.tool, 200, end_masses=True))
    load, settlement = np.array(test["load"]), np.array(test["settlement"])
    assert load[-1] == pytest.approx(2.0e6, rel=1e-5)
    # before the soil slips the pile's own shortening over its length at most
    assert np.all(settlement[load < 0.25 * 2e6] <= load[load < 0.25 * 2e6] * 20.0 / (2.1e11 * 0.01) * (1 + 1e-9))
    assert np.all(np.diff(settlement) > 0)
