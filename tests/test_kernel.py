"""The kernel's passes along the tool, against direct NumPy/SciPy computations.

The tool rows' solve (factored once, swept as segments with carries) against a banded solve of the
same rows, on tools too short for segments, with and without a serial head before them, uniform
and tapered, for every kind of scheme weight. The energy sums and the stress extremes (one
vectorised pass, the extreme's node found in its block) against NumPy's sums, min and max.
"""

import numpy as np
import pytest
from scipy.linalg import solve_banded

from percussim.solver import kernel as K
from percussim.solver.controller import tool_on
from percussim.solver.grid import make_grid
from percussim.solver.layout import ENVELOPE_BINS
from percussim.solver.presets import load_preset

RNG = np.random.default_rng(7)


def tool_rows(grid, r, weight_new, end_weight, end_stiffness, diag_n):
    """The rows u_1 … u_N of the new layer as a (1, 1)-banded matrix, u_0 moved to the right."""
    n = grid.cells
    band = np.zeros((3, n))
    wr = weight_new * r
    for i in range(1, n):
        band[1, i - 1] = 1.0 + wr * (grid.lower[i] + grid.upper[i])
        if i > 1:
            band[2, i - 2] = -wr * grid.lower[i]
        band[0, i] = -wr * grid.upper[i]
    band[1, n - 1] = diag_n
    band[2, n - 2] = -end_weight * end_stiffness
    return band


@pytest.mark.parametrize("cells", [5, 31, 32, 33, 101, 2001])
@pytest.mark.parametrize("preset", ["fig3", "fig9"])
@pytest.mark.parametrize(
    "weight_new, centered, end_masses", [(0.5, False, False), (1.0, False, False), (0.25, True, True)]
)
def test_segmented_solve_equals_a_banded_solve(cells, preset, weight_new, centered, end_masses):
    case = load_preset(preset)
    grid = make_grid(case.tool, cells, end_masses)
    end_stiffness = 2e8
    rod = K.Rod(
        cell_length=grid.h,
        time_step=1e-6,
        courant_squared=30.0,
        youngs_modulus=grid.youngs_modulus,
        density=grid.density,
        struck_end_stiffness=end_stiffness,
        working_end_stiffness=end_stiffness,
    )
    weights = K.Weights(
        new=weight_new,
        old=weight_new if centered else 0.0,
        centered=centered,
        end_masses=end_masses,
        impedance_ends=False,
    )
    medium = K.Medium(
        kind=K.MEDIUM_LINEAR,
        stiffness=5e7,
        damping=3e3,
        impedance=0.0,
        unloading_stiffness=0.0,
        ultimate_resistance=0.0,
        damping_factor=0.0,
    )
    rows = K.factor_tool_rows(tool_on(grid), rod, weights, medium)
    p, inv_den = rows.p, rows.inv_den
    end_weight = weight_new if end_masses else 1.0
    diag_n = 1.0 / inv_den[cells]
    rhs = RNG.standard_normal(cells)  # rows 1 … N
    u_0 = RNG.standard_normal()

    u = np.zeros((3, cells + 1))
    u[1, 1:] = rhs * inv_den[1:]
    length, head = K.segment_layout(cells)
    q_1, carries = K.sweep_toward_struck_end(u, 1, rows, length, head)
    K.substitute_toward_working_end(u, 1, rows, length, head, u_0, carries)

    band = tool_rows(grid, rod.courant_squared, weight_new, end_weight, end_stiffness, diag_n)
    moved = rhs.copy()
    moved[0] += weight_new * rod.courant_squared * grid.lower[1] * u_0
    expected = solve_banded((1, 1), band, moved)
    assert np.abs(u[1, 1:] - expected).max() <= 1e-11 * np.abs(expected).max()
    assert (length > 0) == (cells >= K.SEGMENTS * K.MIN_SEGMENT)
    assert head + K.SEGMENTS * length == cells
    # Q_1 is the struck-end row's link: u_1 = P_1·u_0 + Q_1
    assert q_1 == pytest.approx(expected[0] - p[1] * u_0, rel=1e-10, abs=1e-12)


@pytest.mark.parametrize("cells", [1, 2, 5, 63, 64, 65, 130, 2001])
@pytest.mark.parametrize("strain_sigma", [0.25, 0.5])
def test_energy_and_stress_pass_equals_numpy(cells, strain_sigma):
    grid = make_grid(load_preset("fig9").tool, cells, end_masses=True)  # conical: areas vary
    u = RNG.normal(size=(3, cells + 1))
    new, cur, stressed, half_e_over_h = 2, 0, 1, 3.5  # the stresses of a third layer
    chunks, envelope = K.stress_chunks(cells), np.full((2, ENVELOPE_BINS), -np.inf)
    kinetic, strain, low, low_chunk, high, high_chunk = K.tool_energy_and_stresses(
        u, new, cur, stressed, grid.node_area, grid.area_mid, strain_sigma, half_e_over_h, chunks, envelope, True
    )

    ea, eb = np.diff(u[new]), np.diff(u[cur])
    assert kinetic == pytest.approx(grid.node_area @ (u[new] - u[cur]) ** 2, rel=1e-13)
    assert strain == pytest.approx(
        grid.area_mid @ (strain_sigma * (ea * ea + eb * eb) + (1 - 2 * strain_sigma) * ea * eb), rel=1e-13
    )
    stress = half_e_over_h * (u[stressed, 2:] - u[stressed, :-2])  # interior nodes 1 … n − 1
    if cells < 2:
        assert (low, high) == (np.inf, -np.inf)
        assert (envelope == -np.inf).all()
        return
    assert (low, high) == (stress.min(), stress.max())
    for value, chunk, first in ((low, low_chunk, np.argmin(stress)), (high, high_chunk, np.argmax(stress))):
        assert K.first_node(u, stressed, half_e_over_h, chunks, chunk, value) == first + 1
    # each stretch of the envelope: its interior nodes' greatest compression and tension, over
    # this layer and a second, smaller one that raises some stretches and not others
    later = 0.8 * RNG.normal(size=(3, cells + 1))
    K.tool_energy_and_stresses(
        later, new, cur, stressed, grid.node_area, grid.area_mid, strain_sigma, half_e_over_h, chunks, envelope, True
    )
    stresses = np.vstack([stress, half_e_over_h * (later[stressed, 2:] - later[stressed, :-2])])
    stretch = np.arange(1, cells) * ENVELOPE_BINS // cells
    for b in range(ENVELOPE_BINS):
        inside = stresses[:, stretch == b]
        expected = (-inside.min(), inside.max()) if inside.size else (-np.inf, -np.inf)
        assert (envelope[0, b], envelope[1, b]) == expected


def test_a_gap_the_step_cannot_close_takes_one_substep_and_an_overlap_its_stiffness_asks():
    """The struck end's substeps keep a stiff contact's relaxation monotone: they follow the
    stiffness at the largest overlap the stretch may reach. Faces apart by more than the stretch
    can close never reach the law's compression: one substep, where they had taken as many as the
    same overlap pressed (Fig. 9's contact on 128 cells, half its rigid-wall depth: 3); a gap the
    stretch can close, the substeps of the overlap it may reach."""
    from percussim.solver import controller as C
    from percussim.solver.case import parse_case
    from percussim.solver.grid import explicit_numerics, rigid_wall_depth
    from percussim.solver.kernel import bundles as B
    from percussim.solver.kernel.struck_end import struck_substeps
    from percussim.testing import at_default_accuracy

    case = parse_case(at_default_accuracy("fig9"))
    numerics = explicit_numerics(case, 128)
    grid = make_grid(case.tool, numerics.cells, end_masses=False)
    contact, _ = C.end_conditions(case, grid)
    anvil = C.anvil_on(case, grid, contact)
    striker = B.StrikerEnd(elastic=False, impedance=1.0, mass=case.striker.mass, weight=0.0)
    tau, speed = numerics.time_step, case.impact_velocity
    overlap = 0.5 * rigid_wall_depth(case)  # 23 steps' closing at the impact speed

    def count(gap, closing):
        return struck_substeps((gap, closing, 0.0, 0.0, 0.0), 0.0, tau, 0.0, contact, striker, anvil, tau)

    pressed = count(overlap, 0.0)
    assert pressed >= 3
    assert count(-overlap, speed) == count(-overlap, -speed) == 1  # closing by a step's worth, and opening
    # a gap of half a step's closing, closing fast enough to reach the same overlap within the step
    assert count(-0.5 * speed * tau, (overlap + 0.5 * speed * tau) / tau) == pressed


@pytest.mark.parametrize("exponent", [0.2, 0.5])
@pytest.mark.parametrize("restitution, deepest", [(1.0, 0.0), (0.8, 1.5e-4), (0.8, 4e-4)])
@pytest.mark.parametrize("give", [1e-3, 1.0, 1e3])  # compliance·Φ''(target): soft to stiff balances
def test_a_contacts_balance_stops_at_its_root_to_rounding(exponent, restitution, deepest, give):
    """A stage's balance `δ + C·Φ'(δ) = target` (`solve_spring_balance`) accepts a Newton step once
    what it leaves, bounded by the law's curvature (`spring_curvature`), is within rounding of the
    overlap, instead of taking one more step to confirm it: its root agrees with Brent's, found to
    rounding on the same law, within the solve's own scale (1e-15 of its bracket), from guesses
    near and far, on a power law (pressed, where its steps keep no bracket) and on a cushion below,
    at and above the overlap it was pressed to; the force it returns with the root is the law's
    there, to rounding. Accepting every first step fails all 18."""
    from scipy.optimize import brentq

    from percussim.solver import laws
    from percussim.solver.kernel.struck_end import solve_spring_balance

    contact = K.Contact(
        striker_mass=1.0,
        striker_velocity=1.0,
        stiffness=1e11,
        exponent=exponent,
        tension_stiffness=0.0,
        damping=0.0,
        impedance=1.0,
        restitution=restitution,
        deepest=deepest,
    )

    def spring(delta):
        return laws.contact_spring(delta, 1e11, exponent, 0.0, restitution, deepest)

    for target in (1e-4, 3e-4, 6e-4):
        compliance = give / laws.contact_spring(target, 1e11, exponent, 0.0)[1]  # the loading law's
        root = brentq(lambda d: d + compliance * spring(d)[0] - target, 0.0, target, xtol=1e-300, rtol=8.9e-16)
        bracket = 1e-15 * (target + abs(target - compliance * spring(target)[0]))  # the solve's own scale
        for guess in (target, 1.05 * root, 0.5 * root, 0.0, 1e3 * root, 1e-9 * root):
            delta, force = solve_spring_balance(target, compliance, guess, contact)
            assert abs(delta - root) <= bracket, (target, guess, delta, root)
            assert abs(force - spring(delta)[0]) <= 4e-16 * spring(delta)[0], (target, guess, force)
