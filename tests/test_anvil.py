"""The anvil: a lumped body between the striker and the tool, against closed forms and an
independent solution.

- An anvil of vanishing mass with a stiff contact on the tool passes the striker's contact force
  straight on: the case without an anvil.
- Two-body impact: a striker m1 at v on an anvil m_a at rest through a stiff linear contact, the
  anvil resting on the tool through a soft one (so that the tool takes almost nothing during the
  impact), leaves them at `v1' = (m1 − m_a)/(m1 + m_a)·v` and `v_a' = 2·m1/(m1 + m_a)·v` after a
  contact of `π·sqrt(μ/k)`, μ = m1·m_a/(m1 + m_a).
- With linear contacts on a tool long enough that nothing returns from its far end, the striker,
  the anvil and the tool's struck end are a linear system: `m1·y'' = −k1·(y − y_a)`,
  `m_a·y_a'' = k1·(y − y_a) − k2·(y_a − u_0)`, `Z·u_0' = k2·(y_a − u_0)` (the rod's end as a
  dashpot Z = ρ·a·S). Its matrix exponential gives the force on the tool until a contact opens:
  the pulse the second body prolongs.
"""

from __future__ import annotations

import numpy as np
import pytest

import percussim
from percussim.testing.closed_forms import AREA, STEEL, V, anvil_case, linear_three_bodies, two_body_impact

FINE = {"scheme": "explicit", "cells": 800}
TOLERANCE = {"tolerance": 0.01}


def supplied(summary: dict) -> float:
    return summary["energy"]["initial"] + summary["energy"]["external_work"]


@pytest.mark.parametrize("numerics", [FINE, TOLERANCE], ids=["fine", "tolerance"])
def test_a_vanishing_anvil_is_no_anvil(numerics):
    """1 mg on a contact 5000 times as stiff as the striker's: the run without an anvil (at fine
    numerics) within 0.1% at fine numerics, within the tolerance under it."""
    case = anvil_case(1e-6, numerics, anvil_contact={"stiffness": 1e13, "exponent": 0.0})
    without = dict(anvil_case(1e-6, FINE, anvil_contact={}))
    del without["anvil"]
    got, want = percussim.simulate(case).summary, percussim.simulate(without).summary
    within = 1e-3 if numerics is FINE else 1e-2
    for key in ("peak_contact_force", "max_compressive_stress"):
        assert got[key]["value"] == pytest.approx(want[key]["value"], rel=within)
    # the rebound is small against the impact velocity: held to the same share of that
    assert got["striker_rebound_velocity"] == pytest.approx(want["striker_rebound_velocity"], abs=within * V)
    assert got["energy"]["to_medium"] == pytest.approx(want["energy"]["to_medium"], rel=within)
    assert abs(got["energy"]["numerical"]) <= 5e-3 * supplied(got)


@pytest.mark.parametrize("numerics", [FINE, TOLERANCE], ids=["fine", "tolerance"])
@pytest.mark.parametrize("striker_mass, anvil_mass", [(2.0, 1.0), (1.0, 3.0)])
def test_two_body_impact(numerics, striker_mass, anvil_mass):
    """The striker–anvil contact (k = 1e10 N/m, 26–43 µs) against the closed forms of a
    two-body elastic impact; the anvil rests on a contact 1e4 times as soft."""
    k = 1e10
    case = anvil_case(
        anvil_mass,
        numerics,
        striker_mass=striker_mass,
        anvil_contact={"stiffness": 1e6, "exponent": 0.0},
        contact={"stiffness": k, "exponent": 0.0},
    )
    result = percussim.simulate(case)
    s = result.summary
    striker_after, anvil_after, contact_time = two_body_impact(striker_mass, anvil_mass, k)
    assert s["co_impact_time"] == pytest.approx(contact_time, rel=5e-3)
    v1 = s["striker_rebound_velocity"]
    va = float(np.interp(s["co_impact_time"], result.history["time"], result.history["anvil/velocity"]))
    assert v1 == pytest.approx(striker_after, abs=2e-3 * V)
    assert va == pytest.approx(anvil_after, abs=2e-3 * V)
    # momentum and energy pass between the two bodies, not to the tool
    assert striker_mass * v1 + anvil_mass * va == pytest.approx(striker_mass * V, rel=2e-3)
    assert 0.5 * (striker_mass * v1**2 + anvil_mass * va**2) == pytest.approx(0.5 * striker_mass * V**2, rel=4e-3)
    assert abs(s["energy"]["numerical"]) <= 5e-3 * supplied(s)


@pytest.mark.parametrize("numerics", [FINE, TOLERANCE], ids=["fine", "tolerance"])
def test_the_pulse_an_anvil_prolongs(numerics):
    """m1 = 2 kg, m_a = 1 kg, k1 = k2 = 2e9 N/m on a 5-m tool: the contact force and the force on
    the tool against the linear system's, until the first contact opens, within 1% of the peak;
    a third of the mass as an anvil makes the pulse longer than the striker alone makes it."""
    m1, ma, k = 2.0, 1.0, 2e9
    case = anvil_case(
        ma,
        {**numerics, "duration": 4e-4},
        striker_mass=m1,
        anvil_contact={"stiffness": k, "exponent": 0.0},
        contact={"stiffness": k, "exponent": 0.0},
        tool={"length": 5.0, "area": AREA, **STEEL},
    )
    result = percussim.simulate(case)
    h = result.history
    opens = result.summary["co_impact_time"]
    t = h["time"]
    inside = (t < opens) & (h["anvil/force"] > 0.0)
    f1, f2 = linear_three_bodies(m1, ma, k, k, t[inside])
    assert np.abs(h["contact/force"][inside] - f1).max() <= 1e-2 * f1.max()
    assert np.abs(h["anvil/force"][inside] - f2).max() <= 1e-2 * f2.max()

    alone = dict(case)
    del alone["anvil"]
    force = result.history["anvil/force"]
    alone_history = percussim.simulate(alone).history
    single = alone_history["contact/force"]
    loaded = t[force > 0.05 * force.max()]
    loaded_alone = alone_history["time"][single > 0.05 * single.max()]
    assert loaded[-1] - loaded[0] > 1.2 * (loaded_alone[-1] - loaded_alone[0])


def test_energy_closes_with_an_anvil():
    """An elastic striker and an anvil on bilinear rock, a Hertz contact with dampers on both
    sides, and four blows on Smith soil: the audit closes within 0.5% under tolerance 0.01, and the
    anvil's terms are in it."""
    piston = {"velocity": V, "length": 0.2, "area": AREA, **STEEL}
    hertz = {"stiffness": 1e11, "exponent": 0.5, "damping": 300.0, "tension_stiffness": 1e6}
    cases = [
        anvil_case(
            0.5,
            TOLERANCE,
            anvil_contact={"stiffness": 5e9, "exponent": 0.0},
            striker=piston,
            medium={"kind": "bilinear", "stiffness": 2e8, "unloading_stiffness": 2e9},
        ),
        anvil_case(
            0.5,
            TOLERANCE,
            anvil_contact=hertz,
            contact={"stiffness": 5e10, "exponent": 0.5, "damping": 100.0},
            medium={"stiffness": 5e7, "damping": 1e3},
        ),
        anvil_case(
            0.5,
            TOLERANCE,
            anvil_contact={"stiffness": 5e9, "exponent": 0.0},
            medium={"kind": "smith", "ultimate_resistance": 3e4, "quake": 2.5e-3, "damping_factor": 0.5},
            blows={"count": 4},
        ),
    ]
    cases[1]["anvil"]["velocity"] = 1.0
    for case in cases:
        s = percussim.simulate(case).summary
        e = s["energy"]
        assert abs(e["numerical"]) <= 5e-3 * supplied(s), case
        assert e["max_excess_fraction"] <= 5e-3
        assert e["to_medium"] > 0.1 * supplied(s)
    # the anvil's own energy at impact is supplied too
    assert s["energy"]["initial"] == pytest.approx(4 * 0.5 * 2.0 * V**2)
    with_velocity = percussim.simulate(cases[1]).summary["energy"]["initial"]
    assert with_velocity == pytest.approx(0.5 * 2.0 * V**2 + 0.5 * 0.5 * 1.0**2)


@pytest.mark.parametrize("restitution", [1.0, 0.6])
@pytest.mark.parametrize("guess", [(0.0, 0.0), (2e-4, 1e-4), (-1e-4, 3e-4), (6e-4, -1e-5)])
@pytest.mark.parametrize("free", [(5e-4, 2e-4), (1e-4, 5e-4), (-2e-4, 1e-4), (8e-4, -3e-4)])
def test_a_stage_of_two_linear_contacts_balances_them_on_any_branch(restitution, guess, free):
    """`δ = free − C·F`, `F_i = Φ_i'(δ_i) + b_i·(δ_i − base_i)/g`: the stage's root holds its
    definition to rounding, whether the guess lies on the root's lines (solved directly as a 2×2
    system) or not (the bracketed iteration), with the striker's contact a cushion pressed to
    0.5 mm, in tension, unloading, at its set or loading again."""
    from percussim.solver import kernel as K
    from percussim.solver.kernel.contact import contact_spring
    from percussim.solver.kernel.struck_end import anvil_balance

    def contact(stiffness, damping, restitution, deepest):
        return K.Contact(
            striker_mass=1.0,
            striker_velocity=1.0,
            stiffness=stiffness,
            exponent=0.0,
            tension_stiffness=1e6,
            damping=damping,
            impedance=1.0,
            restitution=restitution,
            deepest=deepest,
        )

    cushion, end = contact(5.89e9, 2e4, restitution, 5e-4), contact(2e10, 0.0, 1.0, 0.0)
    gives, g, base = (1e-10, 2e-11, 5e-11), 1e-6, (1e-4, 5e-5)
    f1, f2, d1, d2 = anvil_balance(free, base, gives, g, guess, cushion, end)
    a, b, t = gives
    assert f1 == pytest.approx(
        contact_spring(d1, cushion)[0] + cushion.damping * (d1 - base[0]) / g, rel=1e-12, abs=1e-6
    )
    assert f2 == pytest.approx(contact_spring(d2, end)[0], rel=1e-12, abs=1e-6)
    scale = max(abs(free[0]), abs(free[1]))
    assert d1 == pytest.approx(free[0] - (a + b) * f1 + b * f2, abs=1e-12 * scale)
    assert d2 == pytest.approx(free[1] + b * f1 - (b + t) * f2, abs=1e-12 * scale)
