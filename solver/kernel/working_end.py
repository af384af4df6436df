"""The working end and the media: the medium's share of the last row (`working_end_diagonal`,
`working_end_row`, `working_end_force`), and the end that integrates its own equations
(`working_end_step`; `yielding_end_step` for rock and Smith soil).
"""

from __future__ import annotations

import math

from ..compiled import compiled
from .bundles import (
    MEDIUM_BILINEAR,
    MEDIUM_LINEAR,
    S_MEDIUM_DEEPEST,
    S_MEDIUM_SET,
    S_MEDIUM_SPENT,
    S_MEDIUM_SURFACE,
    WORK_DEEPEST,
    WORK_DISP,
    WORK_FORCE,
    WORK_SET,
    WORK_SPENT,
    WORK_SURFACE,
    boundary_weights,
)
from .struck_end import SDIRK_GAMMA, SDIRK_MONOTONE, substeps


@compiled(inline="always")
def working_end_step(tau, state, v_mean, v_slope, medium):
    """Advance the working end over one step under the incoming wave's rate
    `v_in(t) = v_mean + v_slope·(t − τ/2)` (t from the step's start):
    `u_N' = −F_m/Z + 2·v_in`, `F_m = c2·u_N + b2·u_N'`, linear, so each SDIRK stage is solved
    directly, in substeps for the medium's relaxation `c2/(Z + b2)`. `state` = (u_N, F_m).
    Returns what the damper b2 dissipated and `(largest F_m, its offset, least F_m, its offset)`
    just after the step's start and at the substeps' ends, offsets from the step's start."""
    if medium.kind != MEDIUM_LINEAR:
        return yielding_end_step(tau, state, v_mean, v_slope, medium)
    z, c2, b2 = medium.impedance, medium.stiffness, medium.damping
    gamma = SDIRK_GAMMA
    z_total = z + b2
    count = substeps(c2 / z_total, tau, SDIRK_MONOTONE)
    span = tau / count
    g = gamma * span
    u = state[WORK_DISP]
    v_start = v_mean - 0.5 * tau * v_slope
    k2 = (2.0 * z * v_start - c2 * u) / z_total
    f_max = f_min = c2 * u + b2 * k2  # under the wave arriving now
    t_max = t_min = 0.0
    dissipated = 0.0
    for j in range(count):
        t_a = j * span
        v1 = v_start + v_slope * (t_a + g)
        u1 = (u + g * 2.0 * z * v1 / z_total) / (1.0 + g * c2 / z_total)
        k1 = (2.0 * z * v1 - c2 * u1) / z_total
        base = u + (1.0 - gamma) * span * k1
        v2 = v_start + v_slope * (t_a + span)
        u = (base + g * 2.0 * z * v2 / z_total) / (1.0 + g * c2 / z_total)
        k2 = (2.0 * z * v2 - c2 * u) / z_total
        dissipated += span * b2 * ((1.0 - gamma) * k1 * k1 + gamma * k2 * k2)
        f = c2 * u + b2 * k2
        if f > f_max:
            f_max, t_max = f, t_a + span
        if f < f_min:
            f_min, t_min = f, t_a + span
    state[WORK_DISP] = u
    state[WORK_FORCE] = c2 * u + b2 * k2
    return dissipated, (f_max, t_max, f_min, t_min)


# --- Media that yield (at the ends that integrate their own equations) ------------------------------
#
# The medium's static resistance F_s(u) at the penetration u = u_N is piecewise linear and depends
# on its state `(set, deepest, surface, spent)`: the permanent penetration u_p; for rock, the
# deepest penetration u_max of the present loading, the surface u_0 it started from and the plastic
# work of the loadings before. The state is held fixed over a substep and updated after it. Each
# branch of the law is linear (or, for Smith's damping, quadratic) in u, so each implicit stage is
# solved exactly on the one branch where it lands: F_s is non-decreasing in u, which makes that
# branch unique. Within a blow rock remembers its deepest penetration: a later wave reloads it at
# k_u up to there and crushes it at k beyond. Each blow meets fresh rock (`fresh_rock`), so that
# blow after blow drills on. The energies are those of the state: rock stores F_s²/(2k_u) and has
# spent ½k·(u_max − u_0)²·(1 − k/k_u) on each loading; soil stores F_s²/(2k) and has spent
# R_u·u_p. Only the dampers' dissipation is integrated, so the energy audit checks the stages
# against the law.


@compiled(inline="always")
def medium_state(ends):
    """The medium's state `(set, deepest, surface, spent)` from its end slots."""
    return ends[S_MEDIUM_SET], ends[S_MEDIUM_DEEPEST], ends[S_MEDIUM_SURFACE], ends[S_MEDIUM_SPENT]


@compiled(inline="always")
def static_resistance(u, state, medium):
    """F_s(u): rock loads at k beyond its deepest penetration and unloads at k_u above its set;
    soil is elastic at k = R_u/q above its set up to R_u; neither pulls (F_s ≥ 0)."""
    set_, deepest, surface, _ = state
    k = medium.stiffness
    if medium.kind == MEDIUM_BILINEAR:
        if u >= deepest:
            return k * (u - surface)
        return max(0.0, medium.unloading_stiffness * (u - set_))
    return min(medium.ultimate_resistance, max(0.0, k * (u - set_)))


@compiled(inline="always")
def medium_energy(u, state, medium):
    """`(stored, plastic)`: what the medium would give back unloading from u, and what its
    permanent penetration cost (module comment above)."""
    k = medium.stiffness
    if medium.kind == MEDIUM_LINEAR:
        return 0.5 * k * u * u, 0.0
    set_, deepest, surface, spent = state
    f = static_resistance(u, state, medium)
    if medium.kind == MEDIUM_BILINEAR:
        k_u = medium.unloading_stiffness
        depth = deepest - surface
        return 0.5 * f * f / k_u, spent + 0.5 * k * depth * depth * (1.0 - k / k_u)
    return 0.5 * f * f / k, medium.ultimate_resistance * set_


@compiled(inline="always")
def yielded(u, state, medium):
    """The medium's state after a substep that ended at u."""
    set_, deepest, surface, spent = state
    k = medium.stiffness
    if medium.kind == MEDIUM_BILINEAR:
        deepest = max(deepest, u)
        return deepest - k * (deepest - surface) / medium.unloading_stiffness, deepest, surface, spent
    if k * (u - set_) > medium.ultimate_resistance:
        set_ = u - medium.ultimate_resistance / k
    return set_, deepest, surface, spent


@compiled()
def fresh_rock(u, state, medium):
    """Rock's state as a new blow meets it at u: a loading starts from where the end is, at k
    (`deepest` = u, the `surface` its line passes through at the present F_s), so that F_s, the
    set and the energies are continuous in u; `spent` takes the plastic work the old loading's
    line counted beyond the new one's. An end off the rock starts the loading on its set."""
    set_, deepest, surface, spent = state
    k, k_u = medium.stiffness, medium.unloading_stiffness
    f = static_resistance(u, state, medium)
    new_deepest, new_surface = (u, u - f / k) if f > 0.0 else (set_, set_)
    share = 0.5 * k * (1.0 - k / k_u)
    spent += share * ((deepest - surface) ** 2 - (new_deepest - new_surface) ** 2)
    return set_, new_deepest, new_surface, spent


@compiled(inline="always")
def yielding_stage(base, g, v_in, state, medium):
    """One implicit stage `u = base + g·u'(u)` of the working end on a yielding medium in `state`,
    with `u' = 2·v_in − F/Z`. Returns `(u, u', F, F_s)`.

    Neither acts while the end is off its set (no contact). Rock: `F = F_s(u) + b2·u'`, so
    `u + g·F_s(u)/(Z + b2) = base + 2g·Z·v_in/(Z + b2)`, solved on the branch the left side's
    breakpoints (the set, the deepest penetration) place it on.
    Soil: `F = F_s(u)·(1 + J·u')`, not below 0 (the toe does not pull): with F_s fixed (no contact,
    or plastic at R_u) `u'` is direct; on the elastic branch the stage is a quadratic in F_s."""
    set_, deepest, surface, _ = state
    z = medium.impedance
    free = base + 2.0 * g * v_in  # u with no resistance
    if free <= set_:
        return free, 2.0 * v_in, 0.0, 0.0
    if medium.kind == MEDIUM_BILINEAR:
        k, k_u, b2 = medium.stiffness, medium.unloading_stiffness, medium.damping
        c = g / (z + b2)
        target = base + 2.0 * g * z * v_in / (z + b2)
        if target <= set_:
            # in contact, the damper alone would take the end back past the surface: it stops there
            rate = (set_ - base) / g
            return set_, rate, z * (2.0 * v_in - rate), 0.0
        if target < deepest + c * k * (deepest - surface):
            u = (target + c * k_u * set_) / (1.0 + c * k_u)
        else:
            u = (target + c * k * surface) / (1.0 + c * k)
        f_s = static_resistance(u, state, medium)
        rate = (2.0 * z * v_in - f_s) / (z + b2)
        return u, rate, f_s + b2 * rate, f_s
    k, r_u, j = medium.stiffness, medium.ultimate_resistance, medium.damping_factor
    if 1.0 + 2.0 * j * v_in <= 0.0:
        # the toe leaves faster than 1/J: the damper takes all the spring gives back (F = 0)
        return free, 2.0 * v_in, 0.0, static_resistance(free, state, medium)
    plastic_rate = (2.0 * v_in - r_u / z) / (1.0 + j * r_u / z)
    u = base + g * plastic_rate
    if u >= set_ + r_u / k:
        return u, plastic_rate, r_u * (1.0 + j * plastic_rate), r_u
    # F_s = s on (0, R_u): (u_p + s/k − base)(1 + J·s/Z) = g·(2·v_in − s/Z), one positive root
    a = j / (k * z)
    b = 1.0 / k + (set_ - base) * j / z + g / z
    c0 = set_ - free  # < 0 here
    root = math.sqrt(b * b - 4.0 * a * c0)
    f_s = -2.0 * c0 / (b + root) if b >= 0.0 else (root - b) / (2.0 * a)
    rate = (2.0 * v_in - f_s / z) / (1.0 + j * f_s / z)
    return set_ + f_s / k, rate, f_s * (1.0 + j * rate), f_s


@compiled()
def yielding_end_step(tau, state, v_mean, v_slope, medium):
    """`working_end_step` for a medium that yields: `state` = (u_N, F_m, set, deepest, surface,
    spent) (the medium's state, the `S_MEDIUM_…` slots' values); the dampers' dissipation (b2, or
    Smith's F_s·J·u'²) and the force's extremes as `working_end_step` returns them."""
    z = medium.impedance
    gamma = SDIRK_GAMMA
    stiffest = max(medium.stiffness, medium.unloading_stiffness)
    count = substeps(stiffest / (z + medium.damping), tau, SDIRK_MONOTONE)
    span = tau / count
    g = gamma * span
    u = state[WORK_DISP]
    held = (state[WORK_SET], state[WORK_DEEPEST], state[WORK_SURFACE], state[WORK_SPENT])
    v_start = v_mean - 0.5 * tau * v_slope
    _, _, f, _ = yielding_stage(u, 0.0, v_start, held, medium)  # under the wave arriving now
    f_max = f_min = f
    t_max = t_min = 0.0
    dissipated = 0.0
    for j in range(count):
        t_a = j * span
        v1 = v_start + v_slope * (t_a + g)
        u1, k1, f1, s1 = yielding_stage(u, g, v1, held, medium)
        v2 = v_start + v_slope * (t_a + span)
        u, k2, f, s2 = yielding_stage(u + (1.0 - gamma) * span * k1, g, v2, held, medium)
        loss1, loss2 = f1 - s1, f - s2  # the damper's share of F
        dissipated += span * ((1.0 - gamma) * loss1 * k1 + gamma * loss2 * k2)
        held = yielded(u, held, medium)
        if f > f_max:
            f_max, t_max = f, t_a + span
        if f < f_min:
            f_min, t_min = f, t_a + span
    state[WORK_DISP], state[WORK_FORCE] = u, f
    state[WORK_SET], state[WORK_DEEPEST], state[WORK_SURFACE], state[WORK_SPENT] = held
    return dissipated, (f_max, t_max, f_min, t_min)


# --- The ends in a step ---------------------------------------------------------------------------
#
# What the tool touches enters a step only here (the module's docstring says how).


@compiled(inline="always")
def working_end_diagonal(tool, rod, weights, medium):
    """The diagonal of the working end's row u_N: `M_N/τ² + θ·k_N + θ_s·c2 + b2·d`, the end node's
    mass, the end cell's stiffness and the medium's spring and damper, weighted as the scheme
    weights them (`boundary_weights`). It is factored with the tool's rows (`factor_tool_rows`)."""
    end_weight, spring_weight, damper_factor, _ = boundary_weights(weights, rod.time_step)
    tau, n = rod.time_step, len(tool.node_area) - 1
    mass_n = rod.density * rod.cell_length * tool.node_area[n] / (tau * tau)
    return (
        mass_n
        + end_weight * rod.working_end_stiffness
        + spring_weight * medium.stiffness
        + medium.damping * damper_factor
    )


@compiled(inline="always")
def working_end_row(u, layer, rows, rod, weights, medium, step):
    """The right-hand side of the working end's row u_N over its diagonal, into row `new` of `u`
    (where the sweep starts from it): the end node's inertia, the medium's spring and damper on the
    reference layer, and with end masses the end cell's share of the known layers."""
    new, cur, old, ref = layer
    n, weight_cur, weight_old = step.n, step.weight_cur, weights.old
    spring_weight, damper_factor = step.boundary.spring_weight, step.boundary.damper_factor
    v_right = weight_cur * u[cur, n] + weight_old * u[old, n]
    v_mid = weight_cur * u[cur, n - 1] + weight_old * u[old, n - 1]
    rhs = (
        step.mass_n * (2.0 * u[cur, n] - u[old, n])
        - medium.stiffness * (1.0 - spring_weight) * u[ref, n]
        + medium.damping * damper_factor * u[ref, n]
    )
    if weights.end_masses:
        rhs -= rod.working_end_stiffness * (v_right - v_mid)
    u[new, n] = rhs * rows.inv_den[n]


@compiled(inline="always")
def working_end_force(u, layer, medium, step):
    """The medium's force on the new layer, `c2·u_N + b2·u_N'` as the scheme weights them."""
    new, _, _, ref = layer
    n = step.n
    _, spring_weight, damper_factor, _ = step.boundary
    return medium.stiffness * (
        spring_weight * u[new, n] + (1.0 - spring_weight) * u[ref, n]
    ) + medium.damping * damper_factor * (u[new, n] - u[ref, n])
