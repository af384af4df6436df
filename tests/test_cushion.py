"""A cushion (`contact.restitution`): it loads along the contact law and unloads along a stiffer
one, giving back e² of what it stored, with no jump in force; against closed forms."""

from __future__ import annotations

import numpy as np
import pytest

from percussim.solver.case import CaseError
from percussim.solver.simulate import simulate
from percussim.testing.closed_forms import cushion_on_a_wall, cushion_rebound


@pytest.mark.parametrize("restitution", [1.0, 0.8, 0.5, 0.2])
def test_a_linear_cushion_against_a_wall_rebounds_at_e_v_after_the_closed_forms_time(restitution):
    summary = simulate(cushion_on_a_wall(restitution)).summary
    rebound, duration = cushion_rebound(100.0, 1e8, 2.0, restitution)
    contact = summary["contacts"][0]
    assert summary["contacts_total"] == 1
    assert summary["striker_rebound_velocity"] == pytest.approx(rebound, rel=1e-4)
    assert contact["end"] - contact["start"] == pytest.approx(duration, rel=1e-4)
    energy = summary["energy"]
    # what it did not give back, it dissipated: (1 − e²) of the ram's energy
    assert energy["dissipated_contact"] == pytest.approx((1.0 - restitution**2) * energy["initial"], rel=1e-4)
    assert abs(energy["numerical"]) < 1e-6 * energy["initial"]
    assert energy["max_excess_fraction"] < 1e-6
    assert summary["warnings"] == []


@pytest.mark.parametrize("restitution", [0.8, 0.5])
def test_a_hertzian_cushion_unloads_in_e_times_its_loading_time(restitution):
    """Unloading along `c1·((δ − δ_p)/e²)^(α+1)` is the loading's motion with the mass times e²:
    whatever the power, it lasts e times as long."""
    elastic = simulate(cushion_on_a_wall(1.0, exponent=0.5)).summary["contacts"][0]
    cushion = simulate(cushion_on_a_wall(restitution, exponent=0.5)).summary
    loading = 0.5 * (elastic["end"] - elastic["start"])
    contact = cushion["contacts"][0]
    assert contact["end"] - contact["start"] == pytest.approx(loading * (1.0 + restitution), rel=1e-3)
    assert cushion["striker_rebound_velocity"] == pytest.approx(-restitution * 2.0, rel=1e-3)


def test_the_cushions_force_does_not_jump_where_it_turns():
    case = cushion_on_a_wall(0.5, numerics={"duration": 0.004, "scheme": "explicit", "cells": 16})
    history = simulate(case).history
    force = history["contact/force"]
    peak = force.max()
    turn = int(np.argmax(force))
    # each step's change of force stays within what the law's stiffness at the turn allows:
    # the unloading branch starts where the loading one ends
    steps = np.abs(np.diff(force))
    assert steps[turn - 3 : turn + 3].max() < 0.05 * peak
    assert np.all(force >= -1e-9 * peak)  # it never pulls


def test_an_anvils_cushion_closes_the_audit():
    case = cushion_on_a_wall(1.0)
    case["anvil"] = {"mass": 50.0, "contact": {"stiffness": 5e8, "exponent": 0.0, "restitution": 0.6}}
    summary = simulate(case).summary
    energy = summary["energy"]
    assert energy["dissipated_contact"] > 0.05 * energy["initial"]
    assert abs(energy["numerical"]) < 1e-5 * energy["initial"]
    assert energy["max_excess_fraction"] < 1e-5


@pytest.mark.parametrize(
    "change, field",
    [
        ({"contact": {"stiffness": 1e8, "exponent": 0.0, "restitution": 0.0}}, "contact.restitution"),
        ({"contact": {"stiffness": 1e8, "exponent": 0.0, "restitution": 1.2}}, "contact.restitution"),
        ({"numerics": {"duration": 0.01, "scheme": "paper", "cells": 50}}, "contact.restitution"),
        ({"numerics": {"duration": 0.01, "model": "lumped"}}, "contact.restitution"),
    ],
)
def test_a_cushion_is_refused_where_it_cannot_be_taken(change, field):
    with pytest.raises(CaseError) as refused:
        simulate(cushion_on_a_wall(0.8) | change)
    assert refused.value.errors[0].field == field


@pytest.mark.parametrize("exponent", [0.0, 0.5])
@pytest.mark.parametrize("target", [2e-4, 5e-4, 9e-4, 1.2e-3, 2e-3])
def test_a_stage_of_a_cushion_balances_its_law_on_either_branch(exponent, target):
    """`δ + C·Φ'(δ) = target` holds to rounding below the deepest overlap (the unloading line, whose
    stiffness and offset are not the loading's), above it and across the turn, with C·c1 of order
    one as a coarse step with a heavy anvil gives."""
    from percussim.solver import kernel as K
    from percussim.solver.kernel.contact import contact_spring
    from percussim.solver.kernel.struck_end import solve_spring_balance

    stiffness = 5.89e9 if exponent == 0.0 else 5.89e9 / 1e-3**0.5
    cushion = K.Contact(
        striker_mass=1.0,
        striker_velocity=1.0,
        stiffness=stiffness,
        exponent=exponent,
        tension_stiffness=0.0,
        damping=0.0,
        impedance=1.0,
        restitution=0.8,
        deepest=1e-3,
    )
    compliance = 1e-10
    delta = solve_spring_balance(target, compliance, target, cushion)[0]
    assert abs(delta + compliance * contact_spring(delta, cushion)[0] - target) <= 1e-12 * target
