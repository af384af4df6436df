"""The energy audit closes: every term, the scheme's own dissipation included (model.md, ref. 3).

The summary's physical terms are recomputed here independently, from the stored histories and
fields with other quadratures, so a wrong term in the kernel's audit cannot hide in the residual.
"""

import numpy as np
import pytest
from conftest import BASE_CASE, merge
from scipy.integrate import trapezoid

from percussim.solver.case import parse_case
from percussim.solver.controller import simulate_rod
from percussim.solver.grid import tool_area
from percussim.solver.laws import contact_law

DAMPED_DRIVEN = merge(
    BASE_CASE,
    {
        "force": {"kind": "abs_sine", "amplitude": 9e4, "omega": 800.0},
        "contact": {"damping": 5e3},
        "medium": {"stiffness": 2e8, "damping": 2e4},
        "numerics": {"duration": 2e-3, "time_step": 4e-7, "cells": 100},
        "outputs": {"fields": True, "field_stride": 1},
    },
)


def _independent_budget(result) -> dict[str, float]:
    case, h = result.case, result.history
    t = h["time"]
    c, m = case.contact, case.medium
    overlap, end = h["contact/overlap"], h["tool/working_end_displacement"]
    fields = result.fields
    x = fields.x
    dx = x[1] - x[0]
    u, u_before = fields.displacement[-1], fields.displacement[-2]
    mass = case.tool.density * tool_area(case.tool, x) * dx
    mass[[0, -1]] *= 0.5
    v = (u - u_before) / (fields.time[-1] - fields.time[-2])
    area_mid = tool_area(case.tool, 0.5 * (x[1:] + x[:-1]))
    d = overlap[-1]
    contact = contact_law(d, c.stiffness, c.exponent, c.tension_stiffness)[1]
    return {
        "external_work": trapezoid(h["external/force"] * h["striker/velocity"], t),
        "dissipated_contact": trapezoid(c.damping * np.gradient(overlap, t) ** 2, t),
        "dissipated_medium": trapezoid(m.damping * np.gradient(end, t) ** 2, t),
        "striker_kinetic": 0.5 * case.striker.mass * h["striker/velocity"][-1] ** 2,
        "tool_kinetic": 0.5 * np.sum(mass * v * v),
        "tool_strain": 0.5 * case.tool.youngs_modulus * np.sum(area_mid * np.diff(u) ** 2) / dx,
        "contact_potential": contact,
        "medium_potential": 0.5 * m.stiffness * end[-1] ** 2,
    }


@pytest.fixture(scope="module")
def driven():
    return simulate_rod(parse_case(DAMPED_DRIVEN))


def test_every_term_is_right_and_the_balance_closes(driven):
    energy = driven.summary["energy"]
    mine = _independent_budget(driven)
    supplied = energy["initial"] + mine["external_work"]
    for name, value in mine.items():
        assert abs(energy[name] - value) < 0.005 * supplied, (name, energy[name], value)
    accounted = sum(v for k, v in mine.items() if k != "external_work") + energy["numerical"]
    assert abs(supplied - accounted) < 0.005 * supplied
    # Every term matters in this case: a dropped one would break the balance.
    for name in ("external_work", "dissipated_contact", "dissipated_medium", "medium_potential"):
        assert mine[name] > 0.01 * supplied, name


def test_the_scheme_dissipates_and_never_creates_energy(driven):
    energy = driven.summary["energy"]
    assert energy["numerical"] > 0
    assert energy["max_excess_fraction"] < 0.005
    assert energy["to_medium"] == pytest.approx(energy["medium_potential"] + energy["dissipated_medium"])


def test_numerical_dissipation_halves_with_the_step():
    coarse, fine = (
        simulate_rod(
            parse_case(
                merge(DAMPED_DRIVEN, {"numerics": {"time_step": tau, "cells": cells}, "outputs": {"fields": False}})
            )
        ).summary["energy"]["numerical"]
        for tau, cells in ((4e-7, 100), (2e-7, 200))
    )
    assert 1.6 < coarse / fine < 2.4
