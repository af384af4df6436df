"""A falling ram (`striker.stroke`, `striker.efficiency`): it strikes at √(2·g·η·h)."""

from __future__ import annotations

import math

import pytest

from percussim.solver.case import CaseError, parse_case
from percussim.solver.presets import preset_json
from percussim.solver.simulate import simulate


def dropped(stroke: float, efficiency: float = 1.0) -> dict:
    case = preset_json("pile")
    case["striker"] |= {"stroke": stroke, "efficiency": efficiency}
    return case


@pytest.mark.parametrize("stroke, efficiency", [(1.0, 1.0), (0.5, 0.8), (2.0, 0.65)])
def test_a_ram_falling_its_stroke_brings_m_g_eta_h(stroke, efficiency):
    summary = simulate(dropped(stroke, efficiency)).summary
    mass = preset_json("pile")["striker"]["mass"]
    assert summary["energy"]["initial"] == pytest.approx(mass * 9.81 * efficiency * stroke, rel=1e-12)
    assert parse_case(dropped(stroke, efficiency)).impact_velocity == pytest.approx(
        math.sqrt(2 * 9.81 * efficiency * stroke), rel=1e-15
    )


def test_the_pile_presets_ram_strikes_as_one_given_its_falls_velocity():
    """The preset's ram falling 0.991 m at an efficiency of 0.67 strikes as a ram given the velocity
    √(2·9.81·0.67·0.991): the same blow."""
    preset = simulate(preset_json("pile")).summary
    given = preset_json("pile")
    given["striker"] = {"mass": given["striker"]["mass"], "velocity": math.sqrt(2 * 9.81 * 0.67 * 0.991)}
    thrown = simulate(given).summary
    assert thrown["peak_contact_force"]["value"] == pytest.approx(preset["peak_contact_force"]["value"], rel=1e-9)
    assert thrown["set"] == pytest.approx(preset["set"], rel=1e-9)
    assert preset["energy"]["initial"] == pytest.approx(4536.0 * 9.81 * 0.67 * 0.991, rel=1e-12)


@pytest.mark.parametrize(
    "striker, field",
    [
        ({"mass": 4000.0, "velocity": 4.0, "stroke": 1.0}, "striker.stroke"),
        ({"mass": 4000.0}, "striker.velocity"),
        ({"mass": 4000.0, "velocity": 4.0, "efficiency": 0.8}, "striker.efficiency"),
        ({"mass": 4000.0, "stroke": 1.0, "efficiency": 1.2}, "striker.efficiency"),
        ({"mass": 4000.0, "stroke": -1.0}, "striker.stroke"),
    ],
)
def test_a_bad_fall_is_refused_naming_the_field(striker, field):
    case = preset_json("pile") | {"striker": striker}
    with pytest.raises(CaseError) as refused:
        parse_case(case)
    assert [e.field for e in refused.value.errors] == [field]
