"""The three schemes: observed orders (1, 2, 2), energy, the explicit Courant limit, end masses."""

import json
import math
from pathlib import Path

import numpy as np
import pytest
from conftest import BASE_CASE, merge

import percussim.solver.grid as grid_module
from percussim.solver.case import CaseError, parse_case
from percussim.solver.controller import simulate_rod
from percussim.solver.grid import resolve_numerics
from percussim.testing.reference import observed_order

TAPERED = json.loads((Path(__file__).parent / "cases" / "tapered_hertz.json").read_text())
LADDER = (25, 50, 100, 200, 400, 800)


@pytest.fixture(scope="module")
def reference_errors(request):
    from percussim.testing.reference import LinearImpact

    ref = LinearImpact()
    table = {}
    for scheme in ("paper", "sigma", "explicit"):
        rows = []
        for cells in LADDER:
            s = simulate_rod(parse_case(merge(ref.case(cells), {"numerics": {"scheme": scheme}}))).summary
            rows.append(ref.errors(s))
        table[scheme] = np.array(rows)
        print(scheme, ", ".join(f"{c}: {e[0]:+.2e} {e[1]:+.2e}" for c, e in zip(LADDER, rows)))
    return table


@pytest.mark.parametrize("scheme, low, high", [("paper", 0.9, 1.1), ("sigma", 1.7, 2.4), ("explicit", 1.7, 2.4)])
@pytest.mark.parametrize("quantity", [0, 1], ids=["co_impact_time", "peak_contact_force"])
def test_observed_order_against_the_closed_form(reference_errors, scheme, low, high, quantity):
    errors = reference_errors[scheme][:, quantity]
    order = observed_order(LADDER, errors)
    print(f"{scheme}: order {order:.2f}")
    assert low < order < high
    assert abs(errors[-1]) < (3e-3 if scheme == "paper" else 5e-6)


@pytest.mark.parametrize("zeta, m1", [(0.3, 20.0), (0.6, 50.0)])
def test_maximum_stress_converges_at_second_order_where_a_reflected_front_meets_the_peak(zeta, m1):
    """With a stiff contact (ζ = 0.6) the stress peak travels down the rod into the front
    reflected at its free end: the largest stress lies next to a kink, which a refinement between
    nodes would overshoot by O(h)."""
    from percussim.testing.reference import LinearImpact, true_errors

    ref = LinearImpact(zeta=zeta, m1=m1)
    cells = (50, 100, 200, 400, 800)
    errors = [
        true_errors(
            simulate_rod(
                parse_case(merge(ref.case(n, courant=1.0 - 1e-9), {"numerics": {"scheme": "explicit"}}))
            ).summary,
            ref.truth(),
        )["max_compressive_stress"]
        for n in cells
    ]
    order = observed_order(cells, errors)
    print(f"ζ = {zeta}: max stress errors {errors}, order {order:.2f}")
    assert 1.7 < order < 2.4
    assert errors[-1] < 3e-5


@pytest.mark.parametrize("scheme", ["sigma", "explicit"])
def test_second_order_schemes_settle_on_a_tapered_hertz_contact(scheme):
    """No closed form here, and the Hertz law's stiffness δ^½ is not smooth at touch and release,
    so the differences do not shrink at a clean order; between the two finest grids they are a
    few parts in 10^5 on the pulse and below 0.1% on the stress maxima."""
    values = []
    for cells in (100, 400, 1600):
        tau = 0.5 * (0.5 / cells) / math.sqrt(2.1e11 / 7800.0)
        case = merge(TAPERED, {"numerics": {"scheme": scheme, "cells": cells, "time_step": tau}})
        s = simulate_rod(parse_case(case)).summary
        values.append(
            (
                s["co_impact_time"],
                s["peak_contact_force"]["value"],
                s["max_compressive_stress"]["value"],
                s["max_tensile_stress"]["value"],
            )
        )
    values = np.array(values)
    change = np.abs(np.diff(values, axis=0)) / values[-1]
    print(scheme, change)
    assert np.all(change[-1, :2] < 5e-5)
    assert np.all(change[-1, 2:] < 1e-3)


@pytest.mark.parametrize("scheme, courant", [("sigma", 0.3), ("sigma", 8.0), ("explicit", 0.99), ("explicit", 0.4)])
def test_second_order_schemes_conserve_the_discrete_energy(scheme, courant):
    """Undamped, unforced, tapered, with a tension spring c0: nothing is lost or created. (The
    state one step before impact has the overlap −W1·τ; the link c0 does not act before impact.)"""
    tau = courant * (0.5 / 60) / math.sqrt(2.1e11 / 7800.0)
    case = merge(
        TAPERED,
        {
            "contact": {"damping": 0.0, "tension_stiffness": 1e9},
            "medium": {"stiffness": 2e8, "damping": 0.0},
            "numerics": {"scheme": scheme, "cells": 60, "duration": 2e-3, "time_step": tau},
        },
    )
    energy = simulate_rod(parse_case(case)).summary["energy"]
    assert abs(energy["numerical"]) < 1e-10 * energy["initial"], energy
    assert energy["max_excess_fraction"] < 1e-10


def test_ends_that_integrate_their_own_equations_lose_energy_only_at_second_order():
    """At Courant number 1 the explicit scheme's ends integrate the striker, contact and medium in
    continuous time: the audit then compares the tool's discrete energy with the ends' exact
    integrals, and what it finds unaccounted for is the scheme's error, falling as h²."""
    residual = []
    for cells in (60, 120, 240):
        case = merge(
            TAPERED,
            {
                "contact": {"damping": 0.0, "tension_stiffness": 1e9},
                "medium": {"stiffness": 2e8, "damping": 0.0},
                "numerics": {"scheme": "explicit", "cells": cells, "duration": 2e-3},
            },
        )
        result = simulate_rod(parse_case(case))
        assert result.numerics.ends == "impedance"
        residual.append(abs(result.summary["energy"]["numerical"]) / result.summary["energy"]["initial"])
    print(residual)
    assert residual[0] < 1e-3
    assert residual[0] / residual[2] > 10.0  # 16 at second order over two doublings


def test_explicit_scheme_refuses_a_courant_number_above_one():
    h_over_a = (1.2 / 100) / math.sqrt(2.1e11 / 7800.0)
    ok = parse_case(merge(BASE_CASE, {"numerics": {"scheme": "explicit", "time_step": h_over_a}}))
    assert resolve_numerics(ok).courant == pytest.approx(1.0)
    case = parse_case(merge(BASE_CASE, {"numerics": {"scheme": "explicit", "time_step": 1.01 * h_over_a}}))
    with pytest.raises(CaseError) as error:
        resolve_numerics(case)
    [e] = error.value.errors
    assert e.field == "numerics.time_step"
    assert "Courant number a·τ/h ≤ 1" in e.message and f"{h_over_a:.4g}" in e.message
    # Its default time step respects the limit.
    default = parse_case(merge(BASE_CASE, {"numerics": {"scheme": "explicit", "time_step": None}}))
    assert resolve_numerics(default).courant <= 1.0 + 1e-12


def test_sigma_below_a_quarter_is_refused_with_the_reason():
    with pytest.raises(CaseError) as error:
        parse_case(merge(BASE_CASE, {"numerics": {"scheme": "sigma", "sigma": 0.2}}))
    [e] = error.value.errors
    assert e.field == "numerics.sigma" and "≥ 0.25" in e.message and "explicit" in e.message


def test_end_masses_make_the_paper_scheme_keep_the_whole_tool_mass(linear_impact):
    """The option only adds the half-cell masses: on the long rod (ends far from the contact's
    reach) the pulse is unchanged to the scheme's order, and the option is reported."""
    without = simulate_rod(parse_case(linear_impact.case(200)))
    with_masses = simulate_rod(parse_case(merge(linear_impact.case(200), {"numerics": {"end_masses": True}})))
    assert with_masses.numerics.end_masses and not without.numerics.end_masses
    a, b = without.summary, with_masses.summary
    assert b["co_impact_time"] == pytest.approx(a["co_impact_time"], rel=5e-3)
    assert b["peak_contact_force"]["value"] == pytest.approx(a["peak_contact_force"]["value"], rel=2e-2)


@pytest.mark.parametrize("scheme", ["paper", "sigma"])
def test_uniform_fast_path_matches_the_general_operator(monkeypatch, scheme):
    case = parse_case(merge(BASE_CASE, {"numerics": {"scheme": scheme}, "outputs": {"probes": [0.3], "fields": True}}))
    fast = simulate_rod(case)
    monkeypatch.setattr(grid_module.Grid, "uniform", property(lambda self: False))
    general = simulate_rod(case)
    np.testing.assert_allclose(
        general.fields.displacement,
        fast.fields.displacement,
        rtol=1e-12,
        atol=1e-12 * np.abs(fast.fields.displacement).max(),
    )
    assert general.summary["co_impact_time"] == pytest.approx(fast.summary["co_impact_time"], rel=1e-12)
