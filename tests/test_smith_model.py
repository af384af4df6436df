"""A driven pile against Smith's lumped-mass model (percussim/testing/smith_model.py), an
independent discretisation: masses and springs stepped by central differences, written apart from
the solver. Shaft and toe yield, their dampers act and the cushion loses energy."""

from __future__ import annotations

import pytest

from percussim.solver.case import parse_case
from percussim.solver.simulate import simulate
from percussim.testing.closed_forms import driven_pile
from percussim.testing.smith_model import smith_pile


@pytest.fixture(scope="module")
def both():
    case = driven_pile({"duration": 0.03, "tolerance": 1e-3})
    return simulate(parse_case(case)), smith_pile(case, segments=600, courant=0.25)


def test_the_lumped_model_converges_to_what_it_is_compared_at():
    case = driven_pile()
    coarse, fine = smith_pile(case, 150, 0.5), smith_pile(case, 600, 0.25)
    # the reference's own error, well under the comparison's bound
    assert fine.set == pytest.approx(coarse.set, rel=2e-3)
    assert fine.peak_force == pytest.approx(coarse.peak_force, rel=5e-3)


def test_the_set_agrees_with_smiths_lumped_model(both):
    summary, smith = both[0].summary, both[1]
    assert summary["set"] == pytest.approx(smith.set, rel=2e-3)
    assert summary["set"] > 5e-3  # the toe yields


def test_the_head_force_stress_transferred_energy_and_the_rams_rebound_agree(both):
    result, smith = both
    summary = result.summary
    assert summary["peak_contact_force"]["value"] == pytest.approx(smith.peak_force, rel=3e-3)
    assert summary["max_compressive_stress"]["value"] == pytest.approx(smith.max_compressive_stress, rel=3e-3)
    assert summary["energy"]["transferred"] == pytest.approx(smith.transferred, rel=2e-3)
    # the ram, struck back twice, at the end
    assert result.history["striker/velocity"][-1] == pytest.approx(smith.ram_velocity, rel=5e-3)
