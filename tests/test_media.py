"""Media that yield, against closed forms: Lundberg's rock and Smith's soil.

A piston of the tool's impedance Z sends a rectangular wave of force F_i = Z·v/2 lasting
T = 2·L_s/a into the tool. At the working end, `u' = 2F_i/Z − F/Z`:
- rock loading at k: `F = 2F_i·(1 − e^(−kt/Z))` until T, then unloading at k_u gives back
  F_max²/(2k_u); the share of the wave's energy left in the rock is Lundberg's
  `η = 2(1 − e^(−x))²/x·(1 − k/k_u)`, x = k·T/Z, largest (0.8145 for k_u → ∞) at x ≈ 1.2564;
- Smith soil without damping (k = R_u/q) is elastic until F = R_u, at `t_q = −(Z/k)·ln(1 − R_u/(2F_i))`,
  then flows at `u' = (2F_i − R_u)/Z` until T: its set is `(2F_i − R_u)·(T − t_q)/Z`.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import percussim
from percussim.solver.case import CaseError
from percussim.testing.closed_forms import MEDIUM_FINE as FINE
from percussim.testing.closed_forms import (
    SOIL_RESISTANCE,
    lundberg,
    lundberg_optimum,
    rock_case,
    rock_penetration,
    smith_set,
    soil_case,
)


def test_lundbergs_optimum():
    """The closed form the tests hold the solver to has its maximum 0.8145 at x = 1.2564."""
    xs = np.linspace(0.5, 3.0, 25001)
    eta = [lundberg(x, math.inf) for x in xs]
    assert xs[int(np.argmax(eta))] == pytest.approx(1.2564, abs=1e-4)
    assert max(eta) == pytest.approx(0.8145, abs=1e-4)
    assert lundberg_optimum() == pytest.approx((xs[int(np.argmax(eta))], max(eta)), abs=1e-4)


@pytest.mark.parametrize("x", [0.3, 1.2564, 3.0])
@pytest.mark.parametrize("numerics", [FINE, {"tolerance": 0.01}], ids=["fine", "tolerance"])
def test_rock_takes_lundbergs_share(x, numerics):
    summary = percussim.simulate(rock_case(x, numerics)).summary
    energy = summary["energy"]
    assert energy["transfer_efficiency"] == pytest.approx(lundberg(x), rel=1e-2)
    assert abs(energy["numerical"]) < 5e-3 * energy["initial"]
    # the deepest penetration F_max/k, and what stays of it, (1 − k/k_u) of that
    deepest, permanent = rock_penetration(x)
    assert summary["medium_penetration"]["max"] == pytest.approx(deepest, rel=1e-2)
    assert summary["medium_penetration"]["permanent"] == pytest.approx(permanent, rel=1e-2)
    # what rock keeps is all plastic once it is unloaded (exponentially, at k_u/Z: at x = 0.3 it
    # still holds 0.5% of its peak force at the run's end, 2e-5 of its energy)
    assert energy["medium_plastic"] == pytest.approx(energy["to_medium"], rel=1e-4)


def test_linear_rock_would_give_it_all_back():
    """Switched to a linear medium of the same stiffness, the rock keeps nothing: the comparison
    above cannot pass with the yielding law off."""
    case = rock_case(1.2564, FINE)
    case["medium"] = {"stiffness": case["medium"]["stiffness"]}
    summary = percussim.simulate(case).summary
    assert summary["energy"]["transfer_efficiency"] < 0.05
    assert summary["medium_penetration"]["permanent"] == 0.0


@pytest.mark.parametrize("numerics", [FINE, {"tolerance": 0.01}], ids=["fine", "tolerance"])
def test_smith_soil_sets_as_the_closed_form_says(numerics):
    summary = percussim.simulate(soil_case(numerics)).summary  # R_u under 2F_i: the toe flows
    _, expected = smith_set()
    assert summary["medium_penetration"]["permanent"] == pytest.approx(expected, rel=1e-2)
    energy = summary["energy"]
    assert energy["medium_plastic"] == pytest.approx(SOIL_RESISTANCE * expected, rel=1e-2)
    assert abs(energy["numerical"]) < 5e-3 * energy["initial"]


@pytest.mark.parametrize("damping_factor", [0.0, 0.5])
def test_the_soils_loop_encloses_the_energy_it_absorbed(damping_factor):
    """∮F du over the force–penetration loop is the net work on the soil: what it reports as
    absorbed (plastic, dissipated by its damping and still stored)."""
    result = percussim.simulate(soil_case(FINE, damping_factor=damping_factor))
    force = result.history["medium/force"]
    penetration = result.history["medium/penetration"]
    loop = float(np.sum(0.5 * (force[1:] + force[:-1]) * np.diff(penetration)))
    energy = result.summary["energy"]
    assert loop == pytest.approx(energy["to_medium"], rel=1e-2)
    if damping_factor:
        assert energy["dissipated_medium"] > 0.05 * energy["to_medium"]
    else:
        assert energy["dissipated_medium"] == 0.0


def test_each_medium_takes_only_its_own_fields():
    case = rock_case(1.0, FINE)
    case["medium"]["quake"] = 0.01
    with pytest.raises(CaseError, match=r"medium\.quake: is not a field of a bilinear medium"):
        percussim.simulate(case)
    case = rock_case(1.0, FINE)
    case["medium"]["unloading_stiffness"] = 0.5 * case["medium"]["stiffness"]
    with pytest.raises(CaseError, match=r"medium\.unloading_stiffness: must be ≥ medium\.stiffness"):
        percussim.simulate(case)
