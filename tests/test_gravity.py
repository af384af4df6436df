"""Gravity (`gravity`): the run starts at rest under the weight, solved as a static problem and
held to the closed form of a pile on shaft and toe springs; the kernel keeps it at rest; a helmet
rests on the pile between blows; the energy audit closes; what cannot rest is refused."""

from __future__ import annotations

import math

import numpy as np
import pytest

from percussim.solver.case import CaseError, parse_case
from percussim.solver.grid import make_grid, resolve_numerics
from percussim.solver.rest import at_rest
from percussim.solver.simulate import simulate
from percussim.testing.closed_forms import pile_under_its_weight, static_compression, yielding_pile_under_gravity

G = 9.81


def closed_form(case, x, head_load=0.0):
    tool, shaft, toe = case.tool, case.shaft[0], case.medium
    return static_compression(
        x,
        length=tool.length,
        stiffness=tool.area * tool.youngs_modulus,
        weight_per_length=tool.density * tool.area * G,
        shaft_stiffness_per_length=shaft.ultimate_resistance / shaft.quake / tool.length,
        toe_stiffness=toe.ultimate_resistance / toe.quake,
        head_load=head_load,
    )


@pytest.mark.parametrize("anvil", [False, True])
def test_the_rest_is_the_static_compression_of_a_pile_on_shaft_and_toe_springs(anvil):
    case = parse_case(pile_under_its_weight(anvil=anvil))
    errors = []
    for cells in (100, 200, 400):
        grid = make_grid(case.tool, cells, end_masses=False)
        rest = at_rest(case, grid)
        exact = closed_form(case, grid.x, head_load=500.0 * G if anvil else 0.0)
        errors.append(np.max(np.abs(rest.u - exact)) / np.max(exact))
    assert errors[-1] < 2e-3
    assert errors[0] / errors[-1] > 3.0  # it converges as the grid refines (O(h) at the ends' shares)
    if anvil:
        assert rest.anvil_overlap == pytest.approx(500.0 * G / 2e9)
        assert rest.anvil_displacement == pytest.approx(rest.u[0] + rest.anvil_overlap)


def test_a_run_at_rest_stays_there():
    case = parse_case(pile_under_its_weight(anvil=True) | {"outputs": {"fields": True, "field_stride": 50}})
    result = simulate(case)
    fields = result.fields
    start = fields.displacement[0]
    drift = np.max(np.abs(fields.displacement - start))
    assert drift < 1e-8 * np.max(np.abs(start))  # the 1-mg ram's blow and weight move it less
    assert np.max(start) == pytest.approx(np.max(closed_form(case, fields.x, 500.0 * G)), rel=2e-3)
    energy = result.summary["energy"]
    assert abs(energy["numerical"]) < 1e-6 * energy["stored_at_rest"]


def test_the_energy_audit_closes_with_gravity_shaft_and_toe_yielding():
    summary = simulate(parse_case(yielding_pile_under_gravity(blows={"count": 2}))).summary
    energy = summary["energy"]
    assert energy["to_shaft"] > 0.1 * energy["initial"] and energy["to_medium"] > 0.1 * energy["initial"]
    assert summary["set"] > 1e-3
    supplied = energy["initial"] + abs(energy["gravity_work"])
    assert abs(energy["numerical"]) < 5e-3 * supplied
    # each ram's potential energy m·g·h, and the second blow's helmet set at rest on its cushion
    assert energy["initial"] == pytest.approx(2 * 4000.0 * G * 1.0 + (500.0 * G) ** 2 / (2 * 2e9), rel=1e-12)


def test_a_helmet_rests_on_the_pile_between_blows():
    case = parse_case(yielding_pile_under_gravity(blows={"count": 2}))
    h = simulate(case).history
    anvil, head = h["anvil/displacement"], h["tool/struck_end_displacement"]
    last = np.searchsorted(h["time"], case.numerics.duration)  # the first blow's last layer
    assert anvil[last] - head[last] < -0.01  # the helmet had bounced off the pile
    # one step into the second blow: set at rest on its cushion pressed by its weight, the pile's
    # head moving on under it for that step, and the ram's cushion pushing it on from the blow's
    # start, its force rising as k·W1·t: k·W1·τ³/(6·m_a) (6 nm on 429 cells, 0.3 nm on 1232)
    rest = 500.0 * G / 2e9
    tau = h["time"][last + 1] - h["time"][last]
    pushed = 5.89e9 * case.impact_velocity * tau**3 / (6.0 * 500.0)
    expected = rest - (head[last + 1] - head[last]) + pushed
    assert anvil[last + 1] - head[last + 1] == pytest.approx(expected, rel=1e-2)
    assert abs(h["anvil/velocity"][last + 1]) < 1e-3 * case.impact_velocity


def test_the_weight_drives_the_pile_deeper():
    with_gravity = simulate(parse_case(yielding_pile_under_gravity())).summary
    without = yielding_pile_under_gravity()
    del without["gravity"]
    without["striker"] = {"mass": 4000.0, "velocity": math.sqrt(2 * G * 1.0)}
    without = simulate(parse_case(without)).summary
    assert with_gravity["energy"]["initial"] == pytest.approx(without["energy"]["initial"], rel=1e-9)
    assert with_gravity["set"] > without["set"]


def test_a_ram_falls_its_stroke_under_the_cases_gravity():
    case = parse_case(yielding_pile_under_gravity(gravity={"acceleration": 1.62}))
    assert case.impact_velocity == pytest.approx(math.sqrt(2 * 1.62 * 1.0))


@pytest.mark.parametrize(
    "change",
    [
        lambda c: (
            c.update(shaft=[{"from": 0.0, "to": 20.0, "ultimate_resistance": 1e3, "quake": 0.0025}])
            or c.update(medium={"kind": "smith", "ultimate_resistance": 1e3, "quake": 0.0025})
        ),
        lambda c: c.pop("shaft") and c.pop("medium"),
    ],
    ids=["soil weaker than the weight", "nothing under the tool"],
)
def test_a_tool_the_soil_cannot_hold_is_refused_naming_gravity(change):
    case = pile_under_its_weight()
    change(case)
    with pytest.raises(CaseError) as refused:
        parse_case(case)
    assert [e.field for e in refused.value.errors] == ["gravity"]


def test_gravity_is_refused_by_the_schemes_that_do_not_take_it():
    case = pile_under_its_weight()
    del case["shaft"]
    case["medium"] = {"kind": "linear", "stiffness": 1e9}  # gravity is all the paper's model lacks
    case["numerics"] = {"duration": 0.02, "scheme": "paper", "cells": 100}
    with pytest.raises(CaseError) as refused:
        resolve_numerics(parse_case(case), model="rod")
    assert [e.field for e in refused.value.errors] == ["gravity"]


def test_the_soils_slip_in_a_blow_locks_a_new_balance_into_the_pile_that_the_next_blow_starts_from():
    """A 0.8-MN force for 2 ms drives a 20-m pile under its weight into shaft and toe soil that
    slip; long after, the pile rings about a balance of its own: over the last 0.3 s the soil's
    mean force is the pile's weight (its momentum changes by nothing to speak of), but the toe
    carries a fraction of what it carried at rest before the blow, the shaft the rest. The second
    blow starts from that state, not from the rest."""
    case = pile_under_its_weight()
    del case["striker"], case["contact"]
    case["medium"] = {"kind": "smith", "ultimate_resistance": 3e5, "quake": 0.0025, "damping_factor": 0.5}
    case["shaft"] = [{"from": 0.0, "to": 20.0, "ultimate_resistance": 3e5, "quake": 0.0025, "damping_factor": 0.2}]
    case["struck_end"] = {"force": {"time": [0.0, 0.002], "values": [8e5, 8e5]}}
    case["numerics"] = {"duration": 0.6, "scheme": "explicit", "cells": 200}
    h = simulate(parse_case(case)).history
    weight = 7850.0 * 0.01 * 20.0 * G
    late = h["time"] > 0.3
    toe, shaft = h["medium/force"], h["shaft/segment_0/force"]
    assert (toe + shaft)[late].mean() == pytest.approx(weight, rel=2e-2)
    at_rest = toe[0]
    assert at_rest == pytest.approx(closed_form_toe_share(case) * weight, rel=2e-2)
    assert toe[late].mean() < 0.5 * at_rest  # the slip moved the toe's load onto the shaft

    case["blows"] = {"count": 2}
    case["numerics"]["duration"] = 0.3
    h = simulate(parse_case(case)).history
    toe = h["medium/force"]
    last = np.searchsorted(h["time"], 0.3)  # the first blow's last layer
    assert toe[last + 1] != pytest.approx(at_rest, rel=0.2)
    # the toe goes on ringing as it was: no step back to the rest
    assert abs(toe[last + 1] - toe[last]) < 1.5 * abs(toe[last] - toe[last - 1])


def closed_form_toe_share(case) -> float:
    """The toe's share of a uniform pile's weight at rest on elastic shaft and toe springs."""
    parsed = parse_case(case)
    tool, toe = parsed.tool, parsed.medium
    u_toe = closed_form(parsed, np.array([tool.length]))[0]
    return toe.ultimate_resistance / toe.quake * u_toe / (tool.density * tool.area * tool.length * G)
