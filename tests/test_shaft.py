"""The soil along the tool's side (`shaft`): its segments on the grid, its refusals, and the run
against closed forms and the energy audit."""

from __future__ import annotations

import h5py
import numpy as np
import pytest

from percussim.solver.case import CaseError, parse_case
from percussim.solver.grid import make_grid, shaft_nodes
from percussim.solver.io import read_result
from percussim.solver.presets import preset_json
from percussim.solver.simulate import simulate
from percussim.testing.closed_forms import free_pile_on_springs, shaft_rigid_mode
from percussim.testing.reference import ringing


def pile_with_shaft(**numerics) -> dict:
    case = preset_json("pile")
    length = case["tool"]["length"]
    case["shaft"] = [
        {"from": 0.0, "to": 0.4 * length, "ultimate_resistance": 1.5e5, "quake": 0.0025, "damping_factor": 0.16},
        {"from": 0.4 * length, "to": length, "ultimate_resistance": 3.5e5, "quake": 0.0025, "damping_factor": 0.16},
    ]
    if numerics:
        case["numerics"] = {"duration": case["numerics"]["duration"], **numerics}
    return case


@pytest.mark.parametrize("cells", [2, 3, 7, 50, 301])
def test_each_segments_resistance_is_spread_over_the_nodes_along_it(cells):
    case = parse_case(pile_with_shaft())
    case.shaft[0].end = 5.3  # a segment ending inside a cell
    grid = make_grid(case.tool, cells, end_masses=True)
    resistance, stiffness, damping = shaft_nodes(case.shaft, grid)
    assert resistance.sum() == pytest.approx(sum(s.ultimate_resistance for s in case.shaft), rel=1e-12)
    assert resistance[0] == resistance[-1] == 0.0  # the ends keep their own equations
    assert np.allclose(stiffness, resistance / 0.0025)
    assert np.allclose(damping[resistance > 0], 0.16)
    if cells >= 50:
        # away from the ends and the segments' ends, a node takes its cell's length of its segment
        h = case.tool.length / cells
        node = cells // 5
        assert resistance[node] == pytest.approx(1.5e5 * h / 5.3)


@pytest.mark.parametrize(
    "change, field",
    [
        (
            lambda s, L: s.append({"from": 5.0, "to": L + 1.0, "ultimate_resistance": 1e5, "quake": 0.002}),
            "shaft[2].to",
        ),
        (lambda s, L: s[1].update({"from": 5.0}), "shaft[1].from"),
        (lambda s, L: s[0].update({"to": 0.0}), "shaft[0].to"),
        (lambda s, L: s[0].update({"quake": 0.0}), "shaft[0].quake"),
        (lambda s, L: s[0].update({"ultimate_resistance": -1.0}), "shaft[0].ultimate_resistance"),
    ],
)
def test_a_bad_segment_is_refused_naming_it(change, field):
    case = pile_with_shaft()
    change(case["shaft"], case["tool"]["length"])
    with pytest.raises(CaseError) as refused:
        parse_case(case)
    assert [e.field for e in refused.value.errors] == [field]


@pytest.mark.parametrize("scheme", ["paper", "sigma"])
def test_a_shaft_is_refused_by_the_schemes_that_do_not_take_it(scheme):
    case = pile_with_shaft(scheme=scheme, cells=100)
    assert "shaft" in parse_case(case).beyond_paper
    with pytest.raises(CaseError) as refused:
        simulate(case)
    assert refused.value.errors[0].field == parse_case(case).beyond_paper[0]


def test_a_segment_is_written_back_as_it_was_read():
    case = parse_case(pile_with_shaft())
    again = parse_case(case.model_dump(mode="json", exclude_none=True))
    assert again.shaft == case.shaft
    assert case.model_dump(mode="json")["shaft"][0]["from"] == 0.0


def test_a_free_pile_on_shaft_springs_rings_its_rigid_mode_at_the_closed_form():
    case = free_pile_on_springs(frequency_hz=50.0)
    result = simulate(case)
    summary = result.summary
    grid = make_grid(parse_case(case).tool, case["numerics"]["cells"], end_masses=True)
    rings = ringing(result, grid)
    shaft = case["shaft"][0]
    expected = shaft_rigid_mode(shaft["ultimate_resistance"] / shaft["quake"] / 10.0, 7850.0, 0.01)
    assert rings.half_periods >= 3
    assert rings.omega == pytest.approx(expected, rel=2e-3)
    assert rings.spread < 5e-3  # one frequency: the mean ignores the waves
    assert summary["energy"]["to_shaft"] > 0.0
    assert abs(summary["energy"]["numerical"]) < 1e-4 * summary["energy"]["initial"]  # the contact's substeps' own


def test_the_energy_audit_closes_with_shaft_and_toe_yielding():
    summary = simulate(pile_with_shaft()).summary
    energy = summary["energy"]
    supplied = energy["initial"] + max(energy["external_work"], 0.0)
    assert energy["to_shaft"] > 0.1 * supplied  # the shaft takes a share
    assert summary["medium_penetration"]["permanent"] > 0.0  # and the toe yields
    assert abs(energy["numerical"]) < 0.005 * supplied
    assert energy["transfer_efficiency"] == pytest.approx((energy["to_medium"] + energy["to_shaft"]) / supplied)


def test_the_shafts_forces_are_recorded_with_their_units(tmp_path):
    case = free_pile_on_springs(frequency_hz=50.0)
    case["numerics"]["duration"] = 0.01
    case["outputs"]["field_stride"] = 5
    path = tmp_path / "result.h5"
    simulate(case, result_path=path)
    result = read_result(path)
    with h5py.File(path) as f:
        assert f["shaft/segment_0/force"].attrs["units"] == "N"
        assert f["fields/shaft_resistance"].attrs["units"] == "N/m"
        assert f["energy/to_shaft"].attrs["units"] == "J"
    grid = make_grid(parse_case(case).tool, case["numerics"]["cells"], end_masses=True)
    _, stiffness, _ = shaft_nodes(parse_case(case).shaft, grid)
    # springs that never yield, without damping: the force is k·u, node by node
    fields = result.fields
    springs = fields.displacement * stiffness
    length = np.r_[0.0, 1.5 * grid.h, np.full(grid.cells - 3, grid.h), 1.5 * grid.h, 0.0]
    assert np.allclose(fields.shaft_resistance * length, springs, rtol=1e-12, atol=1e-9 * np.abs(springs).max())
    times = result.history["time"]
    on_fields = np.isin(times, fields.time)
    assert np.allclose(result.history["shaft/segment_0/force"][on_fields], springs.sum(axis=1), rtol=1e-12)
