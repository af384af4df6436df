"""The laws at the struck end (solver/laws.py): the scalar forms the kernel compiles and the array
forms the lumped model uses are one law."""

from __future__ import annotations

import numpy as np
import pytest

from percussim.solver import laws

DELTAS = np.concatenate([-np.geomspace(1e-3, 1e-12, 40), [0.0], np.geomspace(1e-12, 1e-3, 40)])


@pytest.mark.parametrize("exponent", [0.0, 0.25, 0.5])
def test_the_array_law_is_the_scalar_law(exponent):
    force, stored = laws.contact_law_on(DELTAS, 8e11, exponent, 3e6)
    for k, delta in enumerate(DELTAS):
        scalar_force, scalar_stored = laws.contact_law(float(delta), 8e11, exponent, 3e6)
        assert force[k] == pytest.approx(scalar_force, rel=4e-16, abs=0.0)
        assert stored[k] == pytest.approx(scalar_stored, rel=4e-16, abs=0.0)
        spring, stiffness = laws.contact_spring(float(delta), 8e11, exponent, 3e6)
        assert spring == pytest.approx(scalar_force, rel=4e-16, abs=0.0)
        if delta > 0.0:  # the stiffness is the force's derivative
            assert stiffness == pytest.approx((exponent + 1.0) * scalar_force / delta, rel=1e-14)


@pytest.mark.parametrize(
    "kind, amplitude, omega, start, duration",
    [
        (laws.FORCE_NONE, 0.0, 0.0, 0.0, 0.0),
        (laws.FORCE_SINE, 2e3, 3e3, 0.0, 0.0),
        (laws.FORCE_ABS_SINE, -2e3, 3e3, 0.0, 0.0),
        (laws.FORCE_PULSE, 5e3, 0.0, 1e-4, 2e-4),
    ],
)
def test_the_array_force_is_the_scalar_force(kind, amplitude, omega, start, duration):
    times = np.linspace(0.0, 5e-4, 101)
    found = laws.external_force_on(times, kind, amplitude, omega, start, duration)
    assert found.tolist() == [laws.external_force(float(t), kind, amplitude, omega, start, duration) for t in times]
