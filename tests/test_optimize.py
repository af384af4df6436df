"""Design optimisation against known optima, and its limits."""

from __future__ import annotations

import json
import math

import pytest

from percussim.cli import main
from percussim.solver.case import CaseError
from percussim.solver.optimize import optimize
from percussim.solver.presets import preset_json
from percussim.testing.closed_forms import AREA, lundberg_optimum, matched_tool_case, passed_share

ROCK_K = 5e8


MAX_PISTON = 0.6  # m


def short_rock_drill() -> dict:
    """The rock_drill preset on a 1.5-m rod. Its duration, 0.55 ms, covers the wave's way to the
    bit (L/a = 0.289 ms) and the longest piston's pulse (2·0.6 m/a = 0.231 ms), and ends before
    the bit's reflection reaches the struck end (2L/a = 0.578 ms): Lundberg's single pass."""
    case = preset_json("rock_drill")
    case.pop("description")
    case["tool"]["length"] = 1.5
    case["numerics"] = {"duration": 0.55e-3}
    return case


def lundberg_optimal_length(case: dict) -> float:
    """The piston length that maximises Lundberg's efficiency 2(1 − e^−x)²/x·(1 − k/k_u), x =
    k·(2L_p/a)/Z, from the stationary point of (1 − e^−x)²/x (percussim/testing/closed_forms.py)."""
    x, _ = lundberg_optimum()
    assert x == pytest.approx(1.2564, abs=1e-4)
    tool = case["tool"]
    speed = math.sqrt(tool["youngs_modulus"] / tool["density"])
    impedance = tool["density"] * speed * tool["area"]
    return x * impedance * speed / (2.0 * case["medium"]["stiffness"])


@pytest.mark.slow
def test_lundbergs_optimal_piston_length_is_found_within_1_percent():
    case = short_rock_drill()
    answer = optimize(
        {
            "case": case,
            "variables": {"striker.length": [0.1, MAX_PISTON]},
            "objective": {"maximize": "energy.transfer_efficiency"},
            "max_evaluations": 200,
        }
    )
    expected = lundberg_optimal_length(case)
    found = answer["values"]["striker.length"]
    assert abs(found / expected - 1.0) <= 0.01, (found, expected)
    # The answer's summary is the one checked under the tolerance, and it is the best seen.
    assert answer["summary"]["tolerance"] == pytest.approx(0.01)
    efficiency = answer["quantities"]["energy.transfer_efficiency"]
    assert efficiency == answer["summary"]["energy"]["transfer_efficiency"]
    assert efficiency == pytest.approx(0.8145 * (1 - 0.1), rel=0.01)  # Lundberg's maximum × (1 − k/k_u)
    assert answer["warnings"] == []
    assert "global stage" in answer["stopped"] and "local stage" in answer["stopped"]
    assert len(answer["history"]) == answer["evaluations"]


def test_the_striker_tool_impedance_ratio_that_passes_the_most_energy_is_one():
    """An elastic striker on a tool whose far end is a matched dashpot (nothing reflects): over
    its first pulse the medium receives 4r/(1 + r)² of the striker's energy, r = Z1/Z2 (the
    transmission of a rod–rod impact), whose maximum is r = 1. Only the striker's area varies
    (the same material: r = A1/A2)."""
    answer = optimize(
        {
            "case": matched_tool_case(1.7),
            "variables": {"striker.area": [AREA / 4, 4 * AREA]},
            "objective": {"maximize": "energy.transfer_efficiency"},
            "max_evaluations": 200,
        }
    )
    ratio = answer["values"]["striker.area"] / AREA
    assert ratio == pytest.approx(1.0, abs=0.01), answer["stopped"]
    assert answer["quantities"]["energy.transfer_efficiency"] == pytest.approx(1.0, abs=0.01)
    # The objective the optimiser saw is the closed form's, run by run (the contact's finite
    # stiffness and the grid of the 1% tolerance aside).
    for run in answer["history"]:
        r = run["values"]["striker.area"] / AREA
        assert run["quantities"]["energy.transfer_efficiency"] == pytest.approx(passed_share(r), rel=0.02)


@pytest.mark.slow
def test_a_limit_is_never_broken_by_the_answer():
    """More energy into the rock from a faster, longer piston, up to an allowable stress: the
    optimum lies on the limit, and the answer, checked under the tolerance, keeps it."""
    allowable = 250e6
    answer = optimize(
        {
            "case": short_rock_drill(),
            "variables": {"striker.length": [0.1, MAX_PISTON], "striker.velocity": [5.0, 20.0]},
            "objective": {"maximize": "energy.to_medium"},
            "limits": {"max_compressive_stress": {"max": allowable}},
            "max_evaluations": 300,
        }
    )
    stress = answer["summary"]["max_compressive_stress"]["value"]
    assert stress <= allowable
    assert stress >= 0.95 * allowable  # the limit is what stopped it
    assert answer["checked"][-1]["feasible"]
    assert all(e["quantities"]["max_compressive_stress"] <= allowable for e in answer["history"] if e["feasible"])
    assert any(not e["feasible"] for e in answer["history"])  # it did try beyond the limit


def test_an_objective_or_limit_not_in_the_summary_is_refused():
    with pytest.raises(CaseError) as refused:
        optimize(
            {
                "case": short_rock_drill(),
                "variables": {"striker.velocity": [5.0, 20.0]},
                "objective": {"maximize": "energy.efficiency"},
                "limits": {"max_stress": {"max": 1e8}},
                "max_evaluations": 10,
            }
        )
    fields = {e.field for e in refused.value.errors}
    assert fields == {"objective.maximize", "limits['max_stress']"}


def test_the_request_is_validated_naming_fields():
    with pytest.raises(CaseError) as refused:
        optimize(
            {
                "case": short_rock_drill(),
                "variables": {"striker.velocity": [20.0, 5.0]},
                "objective": {"maximize": "energy.to_medium", "minimize": "peak_contact_force"},
            }
        )
    assert {e.field for e in refused.value.errors} == {"objective.maximize"}
    with pytest.raises(CaseError) as refused:
        optimize(
            {
                "case": short_rock_drill(),
                "variables": {"striker.velocity": [20.0, 5.0]},
                "objective": {"maximize": "energy.to_medium"},
            }
        )
    assert {e.field for e in refused.value.errors} == {"variables['striker.velocity']"}
    with pytest.raises(CaseError) as refused:
        optimize(
            {
                "case": short_rock_drill(),
                "variables": {"blows.count": [1, 5]},
                "objective": {"maximize": "energy.to_medium"},
            }
        )
    assert "variables['blows.count']" in {e.field for e in refused.value.errors}


def test_the_budget_bounds_the_global_stage(tmp_path, capsys):
    """Through the command line: a tool's profile area as the variable, a budget of 40 runs."""
    case = short_rock_drill()
    area = case["tool"].pop("area")
    case["tool"]["profile"] = {"x": [0.0, 0.75, 1.5], "area": [area, area, area]}
    (tmp_path / "case.json").write_text(json.dumps(case))
    code = main(
        [
            "optimize",
            str(tmp_path / "case.json"),
            "--vary",
            f"tool.profile.area.1={area / 2}:{area * 2}",
            "--minimize",
            "max_compressive_stress",
            "--evaluations",
            "40",
            "--output",
            str(tmp_path / "out.json"),
            "--plot",
            str(tmp_path / "conv.svg"),
        ]
    )
    assert code == 0
    shown = json.loads(capsys.readouterr().out)
    saved = json.loads((tmp_path / "out.json").read_text())
    global_runs = int(saved["stopped"].split("(")[1].split(" runs")[0])
    assert global_runs <= 40 + 2 * 8  # stops at the first generation past the budget
    assert shown["values"]["tool.profile.area.1"] == saved["values"]["tool.profile.area.1"]
    assert (tmp_path / "conv.svg").read_text().startswith("<?xml")
