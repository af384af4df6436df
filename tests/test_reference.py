"""The rod model against the closed form of a linear impact on a long rod (model.md, reference 1)."""

import math

import numpy as np

from percussim.solver.case import parse_case
from percussim.solver.controller import simulate_rod


def _errors(ref, cells):
    return ref.errors(simulate_rod(parse_case(ref.case(cells))).summary)


def test_reference_is_within_one_percent_on_a_fine_grid(linear_impact):
    ref = linear_impact
    assert ref.contact_time < 2 * ref.length / ref.a  # no reflection is back before separation
    time_error, force_error = _errors(ref, 800)
    assert abs(time_error) < 0.01
    assert abs(force_error) < 0.01


def test_observed_order_is_about_one(linear_impact):
    errors = [_errors(linear_impact, cells) for cells in (100, 200, 400)]
    for quantity in (0, 1):
        for coarse, fine in zip(errors, errors[1:]):
            order = math.log2(abs(coarse[quantity]) / abs(fine[quantity]))
            assert 0.8 < order < 1.2, (quantity, errors)


def test_stress_wave_travels_at_the_bar_speed_with_the_contact_force(linear_impact):
    """σ(x, t) = −F_c(t − x/a)/S: a probe down the rod sees the contact pulse, delayed."""
    ref = linear_impact
    x = 0.5
    result = simulate_rod(parse_case(ref.case(800, probes=[x])))
    t = result.history["time"]
    expected = ref.stress(t, x)
    stress = result.probe_stress[:, 0]
    peak = ref.peak_force / ref.area
    assert np.max(np.abs(stress - expected)) < 0.03 * peak
    assert abs(t[np.argmin(stress)] - (ref.peak_time + x / ref.a)) < 0.02 * ref.contact_time
