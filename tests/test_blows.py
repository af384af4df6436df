"""Blow after blow on bilinear rock: the first blow is the single-blow run, the tool and the rock
carry their state into the next, and the set per blow settles."""

from __future__ import annotations

import pytest

import percussim

from closed_forms import AREA, PISTON, STEEL, V, drilling


@pytest.fixture(scope="module")
def six():
    return percussim.simulate(drilling(6)).summary


def test_the_first_blow_is_the_single_blow_run(six):
    one = percussim.simulate(drilling(1)).summary
    assert six["blows"][0] == one["blows"][0]
    assert one["blows"][0]["to_medium"] == pytest.approx(one["energy"]["to_medium"], rel=1e-12)


def test_the_set_per_blow_settles_and_the_rock_keeps_it(six):
    sets = [blow["set"] for blow in six["blows"]]
    assert all(s > 0 for s in sets)
    assert sets[-1] == pytest.approx(sets[-2], rel=2e-2)
    assert sets[-1] > 1.2 * sets[0]  # the first blow starts from a tool at rest, the later ones do not
    assert six["medium_penetration"]["permanent"] == pytest.approx(sum(sets), rel=1e-9)
    assert six["blows"][-1]["permanent_penetration"] == six["medium_penetration"]["permanent"]


def test_the_run_accounts_for_every_blows_energy(six):
    energy = six["energy"]
    launch = 0.5 * STEEL["density"] * AREA * PISTON * V**2
    assert energy["initial"] == pytest.approx(6 * launch, rel=1e-12)
    assert energy["to_medium"] == pytest.approx(sum(b["to_medium"] for b in six["blows"]), rel=1e-9)
    assert abs(energy["numerical"]) < 5e-3 * energy["initial"]
    assert six["peak_contact_force"]["value"] == max(b["peak_contact_force"] for b in six["blows"])
