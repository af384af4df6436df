"""What a pile's head record says by itself (`solver/pile_record.py`): the Case method against its
closed form on a uniform pile whose soil acts at its toe, and F = Z·v at impact."""

from __future__ import annotations

import numpy as np
import pytest

from percussim.solver.case import parse_case
from percussim.solver.pile_record import case_method, proportionality, waves
from percussim.solver.simulate import simulate
from percussim.testing import closed_forms as CF


@pytest.fixture(scope="module")
def head_record():
    """The head of a uniform 1-m pile driven by a rectangular force F_i for T, its toe on
    rigid-plastic soil (a 1-µm quake, no damping) of R_u = 1.2·F_i: force and velocity there."""
    case = CF.rectangular_force_case({"scheme": "explicit", "cells": 1000}, quake=1e-9)
    case["numerics"]["duration"] = 2.2 * CF.TOOL / CF.SPEED + CF.T
    h = simulate(parse_case(case)).history
    velocity = np.gradient(h["tool/struck_end_displacement"], h["time"])
    return h["time"], h["contact/force"], velocity


def test_the_case_method_reads_the_toes_resistance_less_its_damping(head_record):
    """While the wave F_i goes down the toe holds R_u, so R_T = R_u, and with the toe moving at
    (2·F_i − R_u)/Z the static part is R_u − J_c·(2·F_i − R_u)."""
    time, force, velocity = head_record
    rows = case_method(time, force, velocity, CF.Z, 2 * CF.TOOL / CF.SPEED)
    r_u = CF.SOIL_RESISTANCE
    for row in rows:
        assert row["capacity"] == pytest.approx(r_u - row["damping_factor"] * (2 * CF.INCIDENT - r_u), rel=2e-3)
    assert [row["damping_factor"] for row in rows] == [0.2, 0.3, 0.4, 0.5, 0.6, 0.7]


def test_force_is_impedance_times_velocity_until_the_toe_answers(head_record):
    time, force, velocity = head_record
    assert proportionality(time, force, velocity, CF.Z) == pytest.approx(1.0, rel=1e-3)
    down, up = waves(force, velocity, CF.Z)
    # nothing comes up before 2L/c (away from the force's jumps, which the velocity's differences
    # straddle)
    before = (time < 0.9 * 2 * CF.TOOL / CF.SPEED) & (np.abs(time - CF.T) > 0.1 * CF.T) & (time > 0.1 * CF.T)
    assert np.max(np.abs(up[before])) < 1e-3 * CF.INCIDENT
    assert np.max(down) == pytest.approx(CF.INCIDENT, rel=1e-3)


def test_a_record_too_short_for_the_case_method_is_refused(head_record):
    time, force, velocity = head_record
    short = time < 1.5 * CF.TOOL / CF.SPEED
    with pytest.raises(ValueError, match="2L/c"):
        case_method(time[short], force[short], velocity[short], CF.Z, 2 * CF.TOOL / CF.SPEED)
