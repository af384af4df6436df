"""What a pile driving analyser reads off a blow: the energy transferred through the struck end
(EMX), the set and the blow count, and refusal."""

from __future__ import annotations

import pytest

import percussim
from percussim.solver.presets import preset_json
from percussim.testing import at_default_accuracy


def test_the_energy_transferred_to_a_free_tool_is_what_the_tool_holds_after_the_blow():
    """Nothing but the struck end does work on a tool without a medium: once the striker has
    left, ∫F·v dt through that end is the tool's kinetic and strain energy, which the audit sums
    along the tool. EMX is its largest value, reached before the tool gave some back."""
    case = at_default_accuracy("fig3")
    case.pop("medium", None)
    case["numerics"]["duration"] = 2e-3
    result = percussim.simulate(case)
    summary, energy = result.summary, result.summary["energy"]
    assert summary["contacts_total"] == 1 and summary["contacts"][0]["end"] is not None
    held = energy["tool_kinetic"] + energy["tool_strain"]
    through = result.history["tool/transferred_energy"]
    assert through[-1] == pytest.approx(held, rel=2e-3)
    assert energy["transferred"] == pytest.approx(through.max(), rel=1e-9)
    assert held <= energy["transferred"] < energy["initial"]


def test_the_lumped_models_transferred_energy_is_its_tools_and_mediums():
    case = preset_json("fig3")
    summary = percussim.simulate(case, model="lumped").summary
    assert 0.0 < summary["energy"]["transferred"] <= summary["energy"]["initial"] + summary["energy"]["external_work"]


def test_set_and_blow_count_are_the_last_blows():
    case = preset_json("pile")
    case["blows"] = {"count": 2}
    summary = percussim.simulate(case).summary
    last = summary["blows"][-1]
    assert summary["set"] == last["set"] > 0.0
    assert summary["blow_count"] == pytest.approx(1.0 / last["set"])
    assert summary["energy"]["transferred"] == max(blow["transferred"] for blow in summary["blows"])
    assert all(0.0 < blow["transferred"] <= summary["energy"]["initial"] for blow in summary["blows"])


def test_a_medium_the_blow_cannot_move_is_refusal():
    case = preset_json("pile")
    case["medium"]["ultimate_resistance"] = 1e9  # far beyond what the ram's wave can push
    summary = percussim.simulate(case).summary
    assert summary["set"] <= 0.0
    assert summary["blow_count"] is None
    assert any(w.startswith("refusal:") for w in summary["warnings"])


def test_a_medium_that_does_not_yield_has_no_set():
    summary = percussim.simulate(at_default_accuracy("fig3")).summary
    assert summary["set"] is None and summary["blow_count"] is None
    assert not any(w.startswith("refusal:") for w in summary["warnings"])
