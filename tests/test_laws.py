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


@pytest.mark.parametrize(("restitution", "deepest"), [(1.0, 0.0), (1.0, 2e-4), (0.8, 2e-4), (0.5, 2e-4)])
def test_a_linear_contacts_branch_is_the_line_its_law_follows_there(restitution, deepest):
    # the direct roots of the kernel's contact solves rest on these lines (tests/test_anvil.py)
    for delta in np.concatenate([DELTAS, np.linspace(0.0, 4e-4, 41)]):
        slope, offset, low, high = laws.linear_branch(float(delta), 8e11, 3e6, restitution, deepest)
        assert low <= delta <= high
        ends = np.linspace(max(low, -1e-3), min(high, 1e-3), 7)
        for k, x in enumerate(ends):
            force, stiffness = laws.contact_spring(float(x), 8e11, 0.0, 3e6, restitution, deepest)
            assert slope * x + offset == pytest.approx(force, rel=1e-12, abs=1e-9 * 8e11 * 1e-12)
            # the stiffness where the law has no kink (a line's ends) and the force is not the
            # cushion's flat set, where contact_spring gives Newton the unloading line's
            if 0 < k < len(ends) - 1 and force != 0.0:
                assert stiffness == pytest.approx(slope, rel=1e-12)
