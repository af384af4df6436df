"""The lumped model problem (21)–(25): closed form, energy closure, and the rod's rigid-tool limit."""

import math

import numpy as np
import pytest
from conftest import BASE_CASE, STEEL, merge
from scipy.integrate import trapezoid

from percussim.solver.case import parse_case
from percussim.solver.controller import HISTORY_PATHS, simulate_rod
from percussim.solver.errors import Cancelled
from percussim.solver.grid import tool_mass
from percussim.solver.lumped import NO_FIELDS_WARNING, simulate_lumped


def relative(value: float, reference: float) -> float:
    return abs(value / reference - 1.0)


class TwoMassLinear:
    """Linear contact (α = 0, c0 = 0, no dampers): a half-period of the reduced mass μ on k."""

    m1, w1, k = 20.0, 5.0, 1e9
    tool = {"length": 1.2, "area": 0.014209, **STEEL}

    def __init__(self):
        self.m2 = tool_mass(parse_case(self.case(1e-3)).tool)
        mu = self.m1 * self.m2 / (self.m1 + self.m2)
        self.contact_time = math.pi * math.sqrt(mu / self.k)
        self.peak_force = self.w1 * math.sqrt(self.k * mu)
        self.rebound_velocity = self.w1 * (self.m1 - self.m2) / (self.m1 + self.m2)

    def case(self, sampling: float) -> dict:
        return {
            "striker": {"mass": self.m1, "velocity": self.w1},
            "tool": self.tool,
            "contact": {"stiffness": self.k, "exponent": 0.0},
            "numerics": {"duration": 3e-3, "time_step": sampling},
        }


def test_linear_contact_matches_the_closed_form():
    ref = TwoMassLinear()
    # Samples 1/7.3 of the contact apart miss the peak: the summary must find it between them.
    result = simulate_lumped(parse_case(ref.case(ref.contact_time / 7.3)))
    summary = result.summary
    assert summary["model"] == "lumped"
    assert summary["contacts_total"] == 1
    assert relative(summary["co_impact_time"], ref.contact_time) < 1e-6
    assert relative(summary["contacts"][0]["end"], ref.contact_time) < 1e-6
    assert relative(summary["peak_contact_force"]["value"], ref.peak_force) < 1e-6
    assert relative(summary["peak_contact_force"]["time"], ref.contact_time / 2) < 1e-6
    assert relative(summary["striker_rebound_velocity"], ref.rebound_velocity) < 1e-6
    assert result.history["contact/force"].max() < (1 - 1e-3) * ref.peak_force


# The trapezoid rule on the sampled R·x1' errs by about P·x1'·τ/2 at each jump of the pulse.
@pytest.mark.parametrize(
    "force, quadrature_tolerance",
    [
        ({"kind": "sine", "amplitude": 9e4, "omega": 800.0}, 1e-5),
        ({"kind": "abs_sine", "amplitude": 9e4, "omega": 3000.0}, 1e-5),
        ({"kind": "pulse", "amplitude": 2e5, "start": 1e-4, "duration": 1.5e-4}, 2e-3),
    ],
)
def test_energy_terms_close(force, quadrature_tolerance):
    case = merge(
        BASE_CASE,
        {
            "force": force,
            "contact": {"damping": 5e3, "tension_stiffness": 3e8},
            "medium": {"stiffness": 2e8, "damping": 2e4},
            "numerics": {"duration": 3e-3},
        },
    )
    result = simulate_lumped(parse_case(case))
    energy = result.summary["energy"]
    supplied = energy["initial"] + abs(energy["external_work"])
    # The case exercises every term and the switch of the contact law (re-contacts via c0).
    assert result.summary["contacts_total"] >= 2
    for term in (
        "external_work",
        "dissipated_contact",
        "dissipated_medium",
        "contact_potential",
        "medium_potential",
        "tool_kinetic",
    ):
        assert abs(energy[term]) > 1e-3 * supplied, term
    assert abs(energy["numerical"]) < 1e-6 * supplied
    # ... and at every sample, not only at the end.
    h = result.history
    terms = (
        "striker_kinetic",
        "tool_kinetic",
        "contact_potential",
        "medium_potential",
        "dissipated_contact",
        "dissipated_medium",
    )
    stored = sum(h[f"energy/{n}"] for n in terms)
    residual = energy["initial"] + h["energy/external_work"] - stored
    assert np.max(np.abs(residual)) < 1e-6 * supplied
    # The work is that of the case's R(t): an independent quadrature of the histories.
    quadrature = trapezoid(h["external/force"] * h["striker/velocity"], h["time"])
    assert abs(quadrature - energy["external_work"]) < quadrature_tolerance * supplied


def test_pulse_works_only_while_on():
    start, duration, amplitude = 1e-4, 1.5e-4, 2e5
    case = merge(BASE_CASE, {"force": {"kind": "pulse", "amplitude": amplitude, "start": start, "duration": duration}})
    h = simulate_lumped(parse_case(case)).history
    t, work, x1 = h["time"], h["energy/external_work"], h["striker/displacement"]
    scale = amplitude * np.ptp(x1)
    on = (start <= t) & (t <= start + duration)
    assert np.all(np.abs(work[t < start]) < 1e-9 * scale)
    np.testing.assert_allclose(work[on] - work[on][0], amplitude * (x1[on] - x1[on][0]), rtol=0, atol=1e-7 * scale)
    assert np.ptp(work[t > start + duration]) < 1e-9 * scale


RIGID_LIMIT = {
    "striker": {"mass": 20.0, "velocity": 5.0},
    "tool": {"length": 1.2, "area": 0.014209, **STEEL},
    "contact": {"stiffness": 1e11, "exponent": 0.5, "tension_stiffness": 0.0, "damping": 0.0},
    "numerics": {"duration": 1e-3, "time_step": 2e-7, "cells": 50},
}


def limit_errors(rod, lumped) -> dict[str, float]:
    """Relative differences of the rod's run from the lumped one (displacement: max-norm)."""
    rs, ls = rod.summary, lumped.summary
    y, y_ref = rod.history["striker/displacement"], lumped.history["striker/displacement"]
    in_contact = lumped.history["time"] <= ls["co_impact_time"]
    return {
        "co_impact": relative(rs["co_impact_time"], ls["co_impact_time"]),
        "peak_force": relative(rs["peak_contact_force"]["value"], ls["peak_contact_force"]["value"]),
        "displacement_in_contact": (np.max(np.abs(y - y_ref)[in_contact]) / np.max(np.abs(y_ref[in_contact]))),
        "displacement": np.max(np.abs(y - y_ref)) / np.max(np.abs(y_ref)),
    }


def rigid_limit_errors(scheme: str, factors) -> dict[float, dict[str, float]]:
    lumped = simulate_lumped(parse_case(RIGID_LIMIT))
    errors = {}
    for factor in factors:
        case = merge(RIGID_LIMIT, {"numerics": {"scheme": scheme}})
        case["tool"]["youngs_modulus"] *= factor
        errors[factor] = limit_errors(simulate_rod(parse_case(case)), lumped)
        print(f"{scheme}, E × {factor:g}: " + ", ".join(f"{k} {v:.3e}" for k, v in errors[factor].items()))
    return errors


def test_stiff_rod_with_end_masses_tends_to_the_lumped_model():
    """model.md reference 2. With the half-cell end masses the rod's mass is all there, and the
    σ-scheme reaches the lumped model to the order of its own error as E grows."""
    errors = rigid_limit_errors("sigma", (1e2, 1e4, 1e6))
    for name in errors[1e2]:
        assert errors[1e4][name] < 1e-4, name
        assert errors[1e6][name] < 1e-5, name
        assert errors[1e6][name] < errors[1e4][name] < errors[1e2][name], name


def test_paper_scheme_keeps_the_floor_of_its_massless_ends():
    """The paper's end rows (9), (10) drop the half-cell masses (m2·(N−1)/N) and the scheme is
    first order in τ: at N = 50, τ = 2e-7 s about 0.9% stays on the rebound, whatever E."""
    errors = rigid_limit_errors("paper", (1e4, 1e6))
    for stiff in errors.values():
        assert stiff["co_impact"] < 2e-3
        assert stiff["peak_force"] < 5e-3
        assert stiff["displacement_in_contact"] < 6e-3
        assert 5e-3 < stiff["displacement"] < 1.25e-2


def test_outputs_keep_the_rod_layout_and_say_what_is_missing():
    case = merge(BASE_CASE, {"outputs": {"probes": [0.0, 0.3, 1.2], "fields": True, "history_stride": 3}})
    result = simulate_lumped(parse_case(case))
    num, h = result.numerics, result.history
    assert set(h) == set(HISTORY_PATHS)
    np.testing.assert_array_equal(h["time"], np.arange(0, num.steps + 1, 3) * num.time_step)
    np.testing.assert_array_equal(h["tool/struck_end_displacement"], h["tool/working_end_displacement"])
    assert not h["energy/tool_strain"].any()
    assert result.fields is None and NO_FIELDS_WARNING in result.summary["warnings"]
    plain = simulate_lumped(parse_case(BASE_CASE))
    assert NO_FIELDS_WARNING not in plain.summary["warnings"]
    for name in h:
        np.testing.assert_allclose(h[name], plain.history[name][::3], rtol=1e-12, atol=1e-300)
    # Quasi-static stress: the end forces over the area at the ends, a mix in between.
    stress = result.probe_stress
    assert stress.shape == (len(h["time"]), 3)
    np.testing.assert_allclose(stress[:, 0], -h["contact/force"] / 0.014209)
    np.testing.assert_allclose(stress[:, 2], -h["medium/force"] / 0.014209)
    np.testing.assert_allclose(stress[:, 1], 0.75 * stress[:, 0] + 0.25 * stress[:, 2])
    peak = result.summary["max_compressive_stress"]
    assert peak["value"] >= result.summary["peak_contact_force"]["value"] / 0.014209 * (1 - 1e-12)


def test_quasi_static_stress_is_the_stiff_rods_stress():
    """On a tapered tool the rigid model's stress at a probe in the taper matches the rod's as
    E grows (the rod's wave part shrinks with the transit time)."""
    case = merge(
        RIGID_LIMIT,
        {
            "tool": {"area": None, "profile": {"x": [0.0, 0.6, 1.2], "area": [0.014, 0.014, 0.004]}},
            "medium": {"stiffness": 2e9, "damping": 1e3},
            "outputs": {"probes": [0.9]},
        },
    )
    lumped = simulate_lumped(parse_case(case))
    stiff = merge(case, {"numerics": {"scheme": "sigma"}})
    stiff["tool"]["youngs_modulus"] *= 1e4
    rod = simulate_rod(parse_case(stiff))
    scale = np.abs(lumped.probe_stress).max()
    difference = np.abs(rod.probe_stress[:, 0] - lumped.probe_stress[:, 0]).max() / scale
    print(f"quasi-static against stiff rod: {difference:.2e} of the peak")
    assert difference < 5e-3
    for key in ("max_compressive_stress", "max_tensile_stress"):
        assert rod.summary[key]["value"] == pytest.approx(lumped.summary[key]["value"], rel=5e-3, abs=1e-3 * scale)


def test_progress_rises_to_one_and_cancel_stops():
    # An abs_sine force breaks the run into many segments.
    case = parse_case(merge(BASE_CASE, {"force": {"kind": "abs_sine", "amplitude": 9e4, "omega": 2e4}}))
    seen = []
    simulate_lumped(case, progress=seen.append)
    assert len(seen) > 5 and seen == sorted(seen) and seen[-1] == 1.0
    calls = []
    with pytest.raises(Cancelled):
        simulate_lumped(case, cancelled=lambda: len(calls) >= 3 or calls.append(1) is not None)
    assert len(calls) == 3
