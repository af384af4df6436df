"""The struck end: the striker row (11) and the struck-end row (9) solved with the contact law
(`solve_struck_end`), and the end that integrates its own equations at Courant number 1
(`struck_end_step`: the striker, an anvil, an elastic striker's waves and its free back end).
"""

from __future__ import annotations

import math

from ..compiled import compiled
from ..laws import FORCE_ABS_SINE, FORCE_PULSE
from .bundles import (
    BACK_INCOMING,
    END_ANVIL_CONTACT_DEEPEST,
    END_ANVIL_DISP,
    END_ANVIL_FORCE,
    END_ANVIL_VELOCITY,
    END_CONTACT_DEEPEST,
    END_CONTACT_FORCE,
    END_IMPULSE,
    END_IN_CONTACT,
    END_STRIKER_DISP,
    END_STRIKER_VELOCITY,
    END_TOOL_DISP,
    S_BACK_ENERGY,
    S_BACK_MEAN,
    S_BACK_MEAN_BEFORE,
    S_BACK_SLOPE,
    S_BACK_SLOPE_BEFORE,
    S_POTENTIAL_BEFORE,
    S_POTENTIAL_BEFORE_THAT,
    Anvil,
)
from .contact import (
    ROUNDING,
    bracketed_newton_step,
    contact_spring,
    cushion_loss,
    external_force,
    fade_time,
    linear_branch,
    pressed_to,
    quotient_force,
    rounding_of,
    solve_overlap,
)

# --- Ends that integrate their own equations (the explicit scheme at Courant number 1) -----------
#
# At Courant number 1 the explicit scheme's end row, `ρS(h/2)·ü_0 = S·E·(u_1 − u_0)/h + F`, is
# algebraically `u_0^{n+1} = 2u_1^n − u_0^{n−1} + (2τ/Z)·F^n` (Z = ρ·a·S of the end cell): the
# characteristic relation at the end, `u_0' = F/Z + 2·v_in`, with the impulse of F over the two
# steps taken by the midpoint rule. The incoming wave's displacement `G` follows from the layers,
# `G_{m} = u_1^{m−1} − u_0^{m−2} + G_{m−2}`, so its rate's mean over each step is exact, that of the
# next step too (the row next to the end is computed first). Within a step `v_in` is linear with
# that mean and the smaller of its slopes to the neighbouring steps' means, none where they
# disagree in sign (minmod): second order pointwise for a smooth wave, where a dashpot makes the
# force follow the wave, and a front, which at Courant number 1 arrives on a step's boundary,
# stays sharp. With it, each end's own equations (striker, contact, medium) are
# integrated in continuous time over the step and give the end's new layer, its force and its
# events exactly where they happen: a jump of R(t), the instant the overlap changes sign. The end
# carries no mass of its own, so a contact or medium far stiffer than the end cell cannot ring
# against it, and the integrator, L-stable, relaxes such a stiff link to its quasi-static state
# instead of letting it oscillate.

SDIRK_GAMMA = 1.0 - math.sqrt(0.5)  # Alexander's two-stage SDIRK: L-stable, second order
# Its amplification factor (1 + (1 − 2γ)z)/(1 − γz)² is ≥ 0 for z ≥ −1/(1 − 2γ) = −2.41 and dips to
# −0.2 beyond: a stiff link relaxing faster than that a step would overshoot and ring for a few
# steps. Each end takes as many substeps as keep (its relaxation rate × substep) within this.
SDIRK_MONOTONE = 2.0
# A stiff contact's rise, integrated at a fixed (rate × substep), leaves a bias in the striker's
# motion of about 0.06·z²/ζ² (z that product, ζ the contact's damping ratio on the tool) that no
# refinement of the grid reduces. So z is also kept below this many times β·τ, β = (Z + b1)/m1 the
# rate the tool brakes the striker at: the bias then falls as τ² with the rest of the scheme's error.
STIFF_RISE_STEPS = 4.0
MAX_SUBSTEPS = 100_000
# An anvil's oscillation between its contacts: substeps keep its phase within this a substep (about
# 30 a period), at most this many a step
ANVIL_PHASE = 0.2
ANVIL_SUBSTEPS = 64


@compiled(inline="always")
def substeps(rate, span, limit):
    """Substeps of `span` that keep (`rate` × substep) within `limit`."""
    return min(MAX_SUBSTEPS, max(1, math.ceil(rate * span / limit)))


@compiled()
def solve_spring_balance(target, compliance, guess, contact):
    """`(δ, Φ'(δ))` with `δ + compliance·Φ'(δ) = target`: Φ' increases, so the root is unique.

    Pressed on a power law that is no cushion (target > 0, so that the root is δ > 0), the balance
    `g(δ) = δ + compliance·c1·δ^(1+α) − target` is convex where δ > 0: Newton's first step from any
    δ > 0 (`guess`, else `target`) lands at the root or beyond it, and the next fall to it, with no
    bracket to keep. A step Δ is the last once what it leaves, at most α/δ·Δ² (`spring_curvature`),
    is within rounding of δ; Φ'(δ) is then the law's tangent at the step's start, exact to the same
    rounding. Otherwise the root lies between `target` and `target − compliance·Φ'(target)`, where
    `bracketed_newton_step` finds it (on one linear branch, directly)."""
    if target > 0.0 and contact.exponent > 0.0 and contact.restitution == 1.0:
        x = guess if guess > 0.0 else target
        for _ in range(100):
            spring, stiffness = contact_spring(x, contact)
            step = (x + compliance * spring - target) / (1.0 + compliance * stiffness)
            x -= step
            if not x > 0.0:
                break  # rounded below a root next to nothing: bracketed below
            if spring_curvature(x, contact) * step * step <= ROUNDING * x:
                return x, spring - stiffness * step
    other = target - compliance * contact_spring(target, contact)[0]
    lo, hi = min(target, other), max(target, other)
    if lo == hi:
        return target, contact_spring(target, contact)[0]
    # on one line of the law the root is direct: in separation, or pressed on a linear contact's
    # (a cushion's set, unloading or loading line)
    if hi <= 0.0 or (lo >= 0.0 and contact.exponent == 0.0):
        slope, offset, _, high = linear_branch(lo, contact)
        if hi <= high:
            x = (target - compliance * offset) / (1.0 + compliance * slope)
            return x, contact_spring(x, contact)[0]
    x = min(max(guess, lo), hi)
    scale = 1e-15 * (abs(lo) + abs(hi))
    for _ in range(100):
        spring, stiffness = contact_spring(x, contact)
        g = x + compliance * spring - target
        if g == 0.0:
            break
        x, lo, hi, done = bracketed_newton_step(
            x, g, 1.0 + compliance * stiffness, lo, hi, scale, spring_curvature(x, contact)
        )
        if done:
            break
    return x, contact_spring(x, contact)[0]


@compiled(inline="always")
def spring_curvature(delta, contact):
    """A bound on |g''|/(2g') of a balance `g(δ) = δ + compliance·Φ'(δ) − target` within half the
    way from δ to where the law's pressed branch starts: Φ'''/(2Φ'') = α/(2(δ − δ_0)) at most,
    δ_0 that start (0, or a cushion's set while it unloads); inf beyond it, or as near the
    overlap a cushion was pressed to, where Φ'' jumps."""
    origin = 0.0
    if contact.restitution < 1.0:
        if abs(delta - contact.deepest) <= 0.5 * delta:
            return math.inf
        if delta < contact.deepest:
            origin = contact.deepest * (1.0 - contact.restitution * contact.restitution)
    reach = delta - origin
    return contact.exponent / reach if reach > 0.0 else math.inf


@compiled(inline="always")
def link_force(delta, approach, mobility, contact):
    """A contact's force from its overlap δ, the speed `approach` its faces would close at were it
    off, and its `mobility`, how they give way to it (1/Z at a rod's end, 0 at a mass):
    `F = Φ'(δ) + b·δ'`, `δ' = approach − mobility·F`."""
    b = contact.damping
    return (contact_spring(delta, contact)[0] + b * approach) / (1.0 + b * mobility)


@compiled(inline="always")
def struck_forces(x, v_in, v_face, contact, striker, anvil):
    """`(F1, F2)`: the contact's force and the force on the tool's struck end (F1 without an
    anvil) in the state `x` = (y, w, y_a, w_a, u_0) under the waves arriving now, at the struck
    end (`v_in`) and at an elastic striker's face (`v_face`): a rod's end moves at twice the wave
    arriving at it less F/Z."""
    y, w, y_a, w_a, u0 = x
    near, give = w, 0.0
    if striker.elastic:
        near, give = 2.0 * v_face, 1.0 / striker.impedance
    if anvil.present:
        end = anvil.contact
        return (
            link_force(y - y_a, near - w_a, give, contact),
            link_force(y_a - u0, w_a - 2.0 * v_in, 1.0 / end.impedance, end),
        )
    force = link_force(y - u0, near - 2.0 * v_in, give + 1.0 / contact.impedance, contact)
    return force, force


@compiled(inline="always")
def body_rates(x, g, force, end_force, r, v_in, v_face, contact, striker, anvil):
    """The rates of the state `x` = (y, w, y_a, w_a, u_0) under the contact force F1, the force
    F2 on the tool's end and R, with the velocities a stage `X = x + g·X'` has (g = 0: at x):
    `m1·w' = R + W1 − F1`, or an elastic striker's face `y' = 2·v_face − F1/Z_s`; the anvil's
    `m_a·w_a' = F1 − F2 + W_a`; `u_0' = F2/Z + 2·v_in` (W1, W_a their weights under gravity)."""
    _, w, _, w_a, _ = x
    if striker.elastic:
        w_rate = 0.0
        y_rate = 2.0 * v_face - force * (1.0 / striker.impedance)
    else:
        w_rate = (r + striker.weight - force) * (1.0 / contact.striker_mass)
        y_rate = w + g * w_rate
    ya_rate = wa_rate = 0.0
    impedance = contact.impedance
    if anvil.present:
        wa_rate = (force - end_force + anvil.weight) * (1.0 / anvil.mass)
        ya_rate = w_a + g * wa_rate
        impedance = anvil.contact.impedance
    return y_rate, w_rate, ya_rate, wa_rate, end_force * (1.0 / impedance) + 2.0 * v_in


@compiled(inline="always")
def moved(x, span, rates, striker):
    """`x + span·rates`; an elastic striker's w is its face's velocity, the rate of y."""
    w = rates[0] if striker.elastic else x[1] + span * rates[1]
    return (x[0] + span * rates[0], w, x[2] + span * rates[2], x[3] + span * rates[3], x[4] + span * rates[4])


@compiled(inline="always")
def overlap_rates(rates, anvil):
    """δ1' and δ2' from the state's rates (δ1 = y − y_a, δ2 = y_a − u_0; δ1 = y − u_0 and no δ2
    without an anvil)."""
    if anvil.present:
        return rates[0] - rates[2], rates[2] - rates[4]
    return rates[0] - rates[4], 0.0


@compiled(inline="always")
def spring_stage(free, base, compliance, g, guess, contact):
    """`(F, δ)` of one contact within a stage: `δ = free − compliance·F`,
    `F = Φ'(δ) + b·(δ − base)/g` (its damper sees the stage's δ' = (δ − base)/g)."""
    damper = contact.damping * (1.0 / g)
    give = compliance * damper
    share = 1.0 / (1.0 + give)
    delta, spring = solve_spring_balance((free + give * base) * share, compliance * share, guess, contact)
    return spring + damper * (delta - base), delta


@compiled()
def anvil_balance(free, base, gives, g, guess, contact, end):
    """`(F1, F2, δ1, δ2)` of the two contacts of a stage with an anvil: `δ = free − C·F`,
    `C = [[a + b, −b], [−b, b + t]]` (`gives` = (a, b, t): how the striker's face, the anvil and
    the tool's end give way to a force within the stage), `F_i = Φ_i'(δ_i) + b_i·(δ_i − base_i)/g`.

    δ minimises the convex `½δᵀKδ + Φ1(δ1) + Φ2(δ2) − δᵀr`, `K = C⁻¹ + diag(b_i/g)`: δ1 for a
    given δ2 is a one-contact balance (`solve_spring_balance`), and the gradient left in δ2 is an
    increasing function whose slope is at least det K/K11, so one evaluation brackets its root."""
    a, b, t = gives
    det_c = a * b + a * t + b * t
    inverse_c, inverse_g = 1.0 / det_c, 1.0 / g
    d1, d2 = contact.damping * inverse_g, end.damping * inverse_g
    k11 = (b + t) * inverse_c + d1
    k12 = b * inverse_c
    k22 = (a + b) * inverse_c + d2
    r1 = ((b + t) * free[0] + b * free[1]) * inverse_c + d1 * base[0]
    r2 = (b * free[0] + (a + b) * free[1]) * inverse_c + d2 * base[1]
    if contact.exponent == 0.0 and end.exponent == 0.0:
        # two linear contacts: on the lines the guess lies on, the balance is a 2×2 linear system;
        # a root that lies on those lines is the root (the balance is a convex minimum's)
        s1, o1, low1, high1 = linear_branch(guess[0], contact)
        s2, o2, low2, high2 = linear_branch(guess[1], end)
        a11, a22 = k11 + s1, k22 + s2
        inverse = 1.0 / (a11 * a22 - k12 * k12)
        delta1 = ((r1 - o1) * a22 - k12 * (r2 - o2)) * inverse
        delta2 = (a11 * (r2 - o2) - k12 * (r1 - o1)) * inverse
        if low1 <= delta1 <= high1 and low2 <= delta2 <= high2:
            return (
                s1 * delta1 + o1 + d1 * (delta1 - base[0]),
                s2 * delta2 + o2 + d2 * (delta2 - base[1]),
                delta1,
                delta2,
            )
    least_slope = ((1.0 + d1 * (a + b) + d2 * (b + t)) * inverse_c + d1 * d2) / k11
    delta1, delta2 = guess
    lo = hi = scale = 0.0
    for k in range(100):
        delta1 = solve_spring_balance((r1 - k12 * delta2) / k11, 1.0 / k11, delta1, contact)[0]
        stiffness1 = contact_spring(delta1, contact)[1]
        spring2, stiffness2 = contact_spring(delta2, end)
        h = k12 * delta1 + k22 * delta2 + spring2 - r2
        if k == 0:
            other = delta2 - h / least_slope
            lo, hi = min(delta2, other), max(delta2, other)
            scale = 1e-15 * (abs(lo) + abs(hi))
        if h == 0.0:
            break
        slope = least_slope + stiffness2 + k12 * k12 * stiffness1 / (k11 * (k11 + stiffness1))
        delta2, lo, hi, done = bracketed_newton_step(delta2, h, slope, lo, hi, scale)
        if done:
            delta1 = solve_spring_balance((r1 - k12 * delta2) / k11, 1.0 / k11, delta1, contact)[0]
            break
    return (
        contact_spring(delta1, contact)[0] + d1 * (delta1 - base[0]),
        contact_spring(delta2, end)[0] + d2 * (delta2 - base[1]),
        delta1,
        delta2,
    )


@compiled(inline="always")
def stage_forces(x, g, r, v_in, v_face, guess, contact, striker, anvil):
    """One implicit stage `X = x + g·X'` of the striker, the anvil and the struck end
    (`body_rates`): linear but for the contacts' springs Φ'(δ), so one equation in δ = y − u_0, or
    two in δ1 = y − y_a, δ2 = y_a − u_0 with an anvil (`anvil_balance`). `guess`: (δ1, δ2).
    Returns `(F1, F2, δ1, δ2)`."""
    # where each body would be were the forces off, and how it gives way to them
    # (mobilities, 1/m and 1/Z, as factors: a division each would lengthen the stage's chain)
    if striker.elastic:
        y_free, give = x[0] + 2.0 * g * v_face, g * (1.0 / striker.impedance)
    else:
        mobility = 1.0 / contact.striker_mass
        y_free, give = x[0] + g * (x[1] + g * (r + striker.weight) * mobility), g * g * mobility
    u_free = x[4] + 2.0 * g * v_in
    if not anvil.present:
        compliance = give + g * (1.0 / contact.impedance)
        force, delta = spring_stage(y_free - u_free, x[0] - x[4], compliance, g, guess[0], contact)
        return force, force, delta, 0.0
    anvil_mobility = 1.0 / anvil.mass
    ya_free = x[2] + g * (x[3] + g * anvil.weight * anvil_mobility)
    return anvil_balance(
        (y_free - ya_free, ya_free - u_free),
        (x[0] - x[2], x[2] - x[4]),
        (give, g * g * anvil_mobility, g * (1.0 / anvil.contact.impedance)),
        g,
        guess,
        contact,
        anvil.contact,
    )


@compiled(inline="always")
def mean_velocity(impulse, contact, striker):
    """An elastic striker's mean velocity, its momentum over its mass, after the contact's
    `impulse`."""
    return contact.striker_velocity - impulse / striker.mass


@compiled(inline="always")
def force_on_substep(t, t_a, t_b, force):
    """R at t on a substep [t_a, t_b] that no break of R crosses: a pulse takes its value at the
    substep's midpoint, so that both ends of the substep see its side of a jump."""
    if force.kind == FORCE_PULSE:
        t = 0.5 * (t_a + t_b)
    return external_force(t, force)


@compiled(inline="always")
def next_break(t, force):
    """The first instant after t where R jumps or kinks (inf when there is none)."""
    if force.kind == FORCE_PULSE:
        if t < force.start:
            return force.start
        if t < force.start + force.duration:
            return force.start + force.duration
    elif force.kind == FORCE_ABS_SINE:
        half = math.pi / force.omega
        k = math.floor(t / half) + 1.0
        if k * half <= t:  # t on a break, rounded below it
            k += 1.0
        return k * half
    return math.inf


@compiled(inline="always")
def hermite(a, b, rate_a, rate_b, span, s):
    """The cubic with values a, b and rates rate_a, rate_b at the ends of a span, at fraction s."""
    s2 = s * s
    s3 = s2 * s
    return (
        (2.0 * s3 - 3.0 * s2 + 1.0) * a
        + (s3 - 2.0 * s2 + s) * span * rate_a
        + (3.0 * s2 - 2.0 * s3) * b
        + (s3 - s2) * span * rate_b
    )


@compiled(inline="always")
def hermite_rate(a, b, rate_a, rate_b, span, s):
    """The rate of the cubic of `hermite` at fraction s."""
    s2 = s * s
    return 6.0 * (s2 - s) * (a - b) / span + (3.0 * s2 - 4.0 * s + 1.0) * rate_a + (3.0 * s2 - 2.0 * s) * rate_b


@compiled()
def hermite_root(a, b, rate_a, rate_b, span):
    """Where in [0, 1] the cubic of `hermite` crosses zero (a and b of opposite signs)."""
    lo, hi = 0.0, 1.0
    low_sign = a < 0.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if (hermite(a, b, rate_a, rate_b, span, mid) < 0.0) == low_sign:
            lo = mid
        else:
            hi = mid
        if hi - lo < 1e-13:
            break
    return 0.5 * (lo + hi)


# A one-sided change this many times the other's, of the other sign, is a front between the steps;
# so is one this many times the change before it and larger than the other (a jump after a quiet
# stretch)
FRONT = 4.0


@compiled(inline="always")
def limited_slope(earlier, before, now, after, tau):
    """The slope within a step of a rate whose means over it, its neighbours and the step before
    those are given: the smaller of the two one-sided slopes where they agree in sign (minmod),
    and where they do not, the smoother side's if the other is a front, else none. A front: a
    change `FRONT` times the other side's, or one that follows a quiet stretch (`FRONT` times the
    change before it) and is larger than the other side's.

    A front arrives on a step's boundary at Courant number 1: the step behind it takes the slope
    of the wave behind it, where minmod held the wave at its mean over the step and cut a peak
    just behind the front at first order. A spike that decays within a few steps (a front
    returned by a stiff spring at the far end, relaxing in Z/c2) falls by more than a quarter of
    the jump in the step behind it; the quiet stretch before the jump tells it from an extremum
    (seed 4's matrix-6: on 128 cells the spike's start read at its mean was 29% low, and the
    tension it makes at the struck end 23% low or more up to 300 cells). At an extremum, or an
    oscillation from step to step, the two sides are alike, the change before is no quieter, and
    none is taken, as minmod does: taking one there let a grid-scale ringing at the struck end
    grow over millions of steps (matrix-31 on 11,674 cells)."""
    left, right = now - before, after - now
    if left * right > 0.0:
        return (left if abs(left) < abs(right) else right) / tau
    if abs(left) > FRONT * abs(right) or (abs(left) > abs(right) and abs(left) > FRONT * abs(before - earlier)):
        return right / tau
    if abs(right) > FRONT * abs(left):
        return left / tau
    return 0.0


@compiled(inline="always")
def reached_stiffness(overlap, closing, span, contact):
    """A contact's stiffness at the largest overlap a stretch of `span` may reach, its faces
    closing at `closing` (either way): a gap they cannot close within it takes the law's tension
    line."""
    return max(contact_spring(overlap + span * abs(closing), contact)[1], contact.tension_stiffness)


@compiled(inline="always")
def struck_substeps(x, end_force, span, v_in, contact, striker, anvil, tau):
    """Substeps over a stretch of `span` for the struck end's links: each contact relaxing against
    what gives way to it, at its stiffness at the largest overlap the stretch may reach
    (`reached_stiffness`: a gap that stays open takes one substep), and an anvil's
    oscillation between its two contacts (capped at `ANVIL_SUBSTEPS`: an anvil too light to
    follow is relaxed to its quasi-static state, as a stiff link is)."""
    y, w, y_a, w_a, u0 = x
    b1 = contact.damping
    end = anvil.contact if anvil.present else contact
    z = end.impedance
    end_rate = end_force * (1.0 / z) + 2.0 * v_in
    if not anvil.present:
        stiffness = reached_stiffness(y - u0, w - end_rate, span, contact)
        if striker.elastic:
            z_both = 1.0 / (1.0 / z + 1.0 / striker.impedance)
            return substeps(stiffness / (z_both + b1), span, SDIRK_MONOTONE)
        limit = min(SDIRK_MONOTONE, STIFF_RISE_STEPS * (z + b1) * (1.0 / contact.striker_mass) * tau)
        return substeps(stiffness, span, (z + b1) * limit)  # (k/(Z + b1))·h within limit
    k1 = reached_stiffness(y - y_a, w - w_a, span, contact)
    k2 = reached_stiffness(y_a - u0, w_a - end_rate, span, end)
    b2 = end.damping
    count = substeps(k2 / (z + b2), span, min(SDIRK_MONOTONE, STIFF_RISE_STEPS * (z + b2) / anvil.mass * tau))
    omega2 = (k1 + k2) / anvil.mass
    if striker.elastic:
        count = max(count, substeps(k1 / (striker.impedance + b1), span, SDIRK_MONOTONE))
    else:
        omega2 += k1 / contact.striker_mass
    return max(count, min(ANVIL_SUBSTEPS, substeps(math.sqrt(omega2), span, ANVIL_PHASE)))


@compiled(inline="always")
def pressed_bodies(contact, anvil, deep1, deep2):
    """The striker's contact and the anvil (with its contact) as cushions pressed to `deep1` and
    `deep2`."""
    pressed = Anvil(
        present=anvil.present,
        mass=anvil.mass,
        velocity=anvil.velocity,
        contact=pressed_to(anvil.contact, deep2),
        weight=anvil.weight,
    )
    return pressed_to(contact, deep1), pressed


@compiled(inline="always")
def deepened(contact, deepest, overlap):
    """A cushion's deepest overlap after a substep that ended at `overlap`, and what it lost in
    it (`cushion_loss`: only while it is pressed deeper). Once its faces part (δ < 0) it has
    recovered: the next contact loads it afresh."""
    if contact.restitution == 1.0:
        return deepest, 0.0  # no cushion: nothing to remember
    if overlap < 0.0:
        return 0.0, 0.0
    if overlap > deepest:
        return overlap, cushion_loss(contact, overlap) - cushion_loss(contact, deepest)
    return deepest, 0.0


@compiled()
def struck_end_step(t0, tau, state, waves, contact, striker, anvil, force, events):
    """Advance the striker, the anvil and the struck end over [t0, t0 + τ] under the incoming
    waves' rates `waves` = (mean, slope) at the struck end and at an elastic striker's face, each
    `v(t) = mean + slope·(t − t0 − τ/2)`; split where R jumps or kinks. `striker` is its scalars
    (`StrikerEnd`): a call that took the `Striker` would be passed all its arrays, which cost a
    tenth of the step's time.

    `state` (its slots `END_…`) = (y, w, u_0, F1, I, in contact, y_a, w_a, F2, δ1_m, δ2_m) at t0
    on entry, at t0 + τ on return:
    w the striker's velocity (its face's when elastic), F1 the contact's force, I its impulse,
    y_a, w_a the anvil's displacement and velocity, F2 the force on the tool's end (F1 without an
    anvil), δ1_m and δ2_m the deepest overlaps of the contacts (a cushion's, `laws.contact_law`).
    Returns the work of R and what the contacts' dampers and cushions dissipated over the step, the
    number of changes of sign of δ1 (the contact's overlap), each written to `events` (time,
    striker velocity, +1 into contact or −1 out of it, `fade_time`; at most `events.shape[0]`; an elastic
    striker's velocity is its mean, its momentum over its mass), `(largest F1, its time)` and
    `(largest F2, its time, least F2, its time)` at the substeps' ends (a stiff contact's substeps
    see a peak the layers miss).
    """
    v_mean, v_slope, face_mean, face_slope = waves
    gamma = SDIRK_GAMMA
    b1, b2 = contact.damping, anvil.contact.damping if anvil.present else 0.0
    t_a = t0
    t_end = t0 + tau
    work = 0.0
    dissipated = 0.0
    count = 0
    x = (
        state[END_STRIKER_DISP],
        state[END_STRIKER_VELOCITY],
        state[END_ANVIL_DISP],
        state[END_ANVIL_VELOCITY],
        state[END_TOOL_DISP],
    )
    impulse = state[END_IMPULSE]
    in_contact = state[END_IN_CONTACT] != 0.0
    # a cushion's laws as pressed so far: held over a substep, deepened after it
    deep1, deep2 = state[END_CONTACT_DEEPEST], state[END_ANVIL_CONTACT_DEEPEST]
    contact, anvil = pressed_bodies(contact, anvil, deep1, deep2)
    v_start = v_mean - 0.5 * tau * v_slope
    face_start = face_mean - 0.5 * tau * face_slope
    # under the waves arriving now: the forces can jump at t0
    f, f_end = struck_forces(x, v_start, face_start, contact, striker, anvil)
    if striker.elastic:
        x = (x[0], 2.0 * face_start - f / striker.impedance, x[2], x[3], x[4])
    f_max, t_max = f, t0
    e_max, te_max, e_min, te_min = f_end, t0, f_end, t0
    overlaps = (x[0] - (x[2] if anvil.present else x[4]), x[2] - x[4])
    # and their rates (R moves neither): each stage's balance starts from the overlaps carried to
    # its instant along them, to the second order for the substep's end
    closing = overlap_rates(body_rates(x, 0.0, f, f_end, 0.0, v_start, face_start, contact, striker, anvil), anvil)
    t_stop = t0
    sub = tau
    while t_a < t_end:
        if t_a >= t_stop:
            # the next stretch without a break of R
            t_next = min(t_end, next_break(t_a, force))
            sub = (t_next - t_a) / struck_substeps(x, f_end, t_next - t_a, v_mean, contact, striker, anvil, tau)
            t_stop = t_next
        t_b = t_stop if t_a + 1.5 * sub >= t_stop else t_a + sub
        span = t_b - t_a
        g = gamma * span
        # stage 1 at t_a + γ·span, stage 2 at t_b: the new state (stiffly accurate)
        t1 = t_a + g
        r1 = force_on_substep(t1, t_a, t_b, force)
        r2 = force_on_substep(t_b, t_a, t_b, force)
        v1 = v_start + v_slope * (t1 - t0)
        v2 = v_start + v_slope * (t_b - t0)
        face1 = face_start + face_slope * (t1 - t0)
        face2 = face_start + face_slope * (t_b - t0)
        guess = (overlaps[0] + g * closing[0], overlaps[1] + g * closing[1])
        f1, e1, d1, a1 = stage_forces(x, g, r1, v1, face1, guess, contact, striker, anvil)
        k1 = body_rates(x, g, f1, e1, r1, v1, face1, contact, striker, anvil)
        rate1, end_rate1 = overlap_rates(k1, anvil)
        base = moved(x, (1.0 - gamma) * span, k1, striker)
        bend = 0.5 * span * span / g  # the rates' change from the start to stage 1, carried to t_b
        guess = (
            overlaps[0] + span * closing[0] + bend * (rate1 - closing[0]),
            overlaps[1] + span * closing[1] + bend * (end_rate1 - closing[1]),
        )
        f2, e2, d2, a2 = stage_forces(base, g, r2, v2, face2, guess, contact, striker, anvil)
        k2 = body_rates(base, g, f2, e2, r2, v2, face2, contact, striker, anvil)
        x2 = moved(base, g, k2, striker)
        rate2, end_rate2 = overlap_rates(k2, anvil)
        work += span * ((1.0 - gamma) * r1 * (x[1] + g * k1[1]) + gamma * r2 * x2[1])
        dissipated += span * (
            (1.0 - gamma) * (b1 * rate1 * rate1 + b2 * end_rate1 * end_rate1)
            + gamma * (b1 * rate2 * rate2 + b2 * end_rate2 * end_rate2)
        )
        impulse_b = impulse + span * ((1.0 - gamma) * f1 + gamma * f2)
        # a change of sign of δ1 beyond rounding: where, on the cubic through the ends' values
        # and rates. Faces that come to rest together (equal impedances) graze, δ ≈ 0 within
        # rounding, with no force: the contact ends as δ falls to the rounding's size, and a new
        # one starts only at twice that, so that rounding neither prolongs it nor starts others.
        # A cushion's faces part where its force ends, at its set δ_p = (1 − e²)·δ_m.
        rounding = rounding_of(x[0], x[2] if anvil.present else x[4])
        edge = rounding if in_contact else 2.0 * rounding
        edge += (1.0 - contact.restitution * contact.restitution) * deep1
        if (d2 >= edge) != in_contact and count < events.shape[0]:
            r_a = force_on_substep(t_a, t_a, t_b, force)
            k_a = body_rates(
                x,
                0.0,
                f,
                f_end,
                r_a,
                v_start + v_slope * (t_a - t0),
                face_start + face_slope * (t_a - t0),
                contact,
                striker,
                anvil,
            )
            rate_a = overlap_rates(k_a, anvil)[0]
            s = hermite_root(overlaps[0] - edge, d2 - edge, rate_a, rate2, span)
            in_contact = not in_contact
            events[count, 0] = t_a + s * span
            if striker.elastic:
                events[count, 1] = mean_velocity(impulse + s * (impulse_b - impulse), contact, striker)
            else:
                events[count, 1] = hermite(x[1], x2[1], k_a[1], k2[1], span, s)
            events[count, 2] = 1.0 if in_contact else -1.0
            events[count, 3] = fade_time(rounding, hermite_rate(overlaps[0], d2, rate_a, rate2, span, s))
            count += 1
        x, f, f_end, impulse, overlaps, closing = x2, f2, e2, impulse_b, (d2, a2), (rate2, end_rate2)
        # the overlaps as the state gives them (the audit reads them so), not the stages' roots
        deeper1, lost1 = deepened(contact, deep1, x[0] - (x[2] if anvil.present else x[4]))
        deeper2, lost2 = deepened(anvil.contact, deep2, x[2] - x[4])
        dissipated += lost1 + lost2
        if deeper1 != deep1 or deeper2 != deep2:
            deep1, deep2 = deeper1, deeper2
            contact, anvil = pressed_bodies(contact, anvil, deep1, deep2)
        t_a = t_b
        if f > f_max:
            f_max, t_max = f, t_a
        if f_end > e_max:
            e_max, te_max = f_end, t_a
        if f_end < e_min:
            e_min, te_min = f_end, t_a
    state[END_STRIKER_DISP], state[END_STRIKER_VELOCITY], state[END_TOOL_DISP] = x[0], x[1], x[4]
    state[END_CONTACT_FORCE], state[END_IMPULSE] = f, impulse
    state[END_ANVIL_DISP], state[END_ANVIL_VELOCITY], state[END_ANVIL_FORCE] = x[2], x[3], f_end
    state[END_CONTACT_DEEPEST], state[END_ANVIL_CONTACT_DEEPEST] = deep1, deep2
    return work, dissipated, count, (f_max, t_max), (e_max, te_max, e_min, te_min)


@compiled(inline="always")
def solve_struck_end(state, layer, overlaps, link, r_n, contact, rod, weights, step):
    """The striker row (11) and the struck end's row (9) of the step, solved with the contact.

    The struck end sees the tool only through its link `u_1 = P_1·u_0 + Q_1` (`link` = (P_1, Q_1),
    from the sweep). With it the rows are `a_y·y = b_y − F` and `a_0·u_0 = b_0 + F`, F the contact
    force: a scalar equation in the new overlap δ (`solve_overlap`), from the layers' `Overlaps`;
    R(t_n) = `r_n` is explicit in row (11). Returns `(y, u_0, F)` of the new layer, F the force the
    scheme applies in the step (centred on layer n, or on the new layer for the paper's).
    """
    u, y, ends = state.u, state.y, state.ends
    _, cur, old, _ = layer
    delta_cur, delta_old, delta_ref = overlaps.cur, overlaps.old, overlaps.ref
    p_1, q_1 = link
    k_0, weight_cur, weight_old = rod.struck_end_stiffness, step.weight_cur, weights.old
    end_weight, _, damper_factor, back = step.boundary
    b1 = contact.damping
    a_y = step.m1_tau2
    b_y = step.m1_tau2 * (2.0 * y[cur] - y[old]) + r_n
    a_0 = step.mass_0 + end_weight * k_0 * (1.0 - p_1)
    b_0 = step.mass_0 * (2.0 * u[cur, 0] - u[old, 0]) + end_weight * k_0 * q_1
    if weights.end_masses:
        b_0 += k_0 * (
            (weight_cur * u[cur, 1] + weight_old * u[old, 1]) - (weight_cur * u[cur, 0] + weight_old * u[old, 0])
        )
    delta_free = b_y / a_y - b_0 / a_0
    compliance = 1.0 / a_y + 1.0 / a_0
    # Φ of the reference layer, as computed when it was new (0 for the state before impact)
    ref_potential = ends[S_POTENTIAL_BEFORE if back == 1 else S_POTENTIAL_BEFORE_THAT]
    delta = solve_overlap(
        delta_free, compliance, delta_ref, ref_potential, 2.0 * delta_cur - delta_old, contact, b1 * damper_factor
    )
    contact_force = quotient_force(delta, delta_ref, ref_potential, contact)[0] + b1 * damper_factor * (
        delta - delta_ref
    )
    return (b_y - contact_force) / a_y, (b_0 + contact_force) / a_0, contact_force


@compiled(inline="always")
def rate_integral(rates, tau, a, b, power):
    """∫ v(s)^power ds over [a, b] (power 1 or 2) for a rate linear within each step: `rates` =
    (mean, slope) of this step, on [0, τ], and of the two before it, on [−τ, 0] and [−2τ, −τ]."""
    total = 0.0
    for j in range(3):
        mean, slope = rates[j]
        low = -j * tau
        mid = low + 0.5 * tau
        p, q = max(a, low) - mid, min(b, low + tau) - mid
        if q > p:
            if power == 1:
                total += mean * (q - p) + 0.5 * slope * (q * q - p * p)
            else:
                total += (
                    mean * mean * (q - p)
                    + mean * slope * (q * q - p * p)
                    + slope * slope * (q * q * q - p * p * p) / 3.0
                )
    return total


@compiled(inline="always")
def back_rates(ends, now):
    """The back end's incoming rate over this step (`now`) and the two before, for `rate_integral`."""
    return (now, (ends[S_BACK_MEAN], ends[S_BACK_SLOPE]), (ends[S_BACK_MEAN_BEFORE], ends[S_BACK_SLOPE_BEFORE]))


@compiled(inline="always")
def free_back_end(striker_u, layer, ends, striker, tau):
    """An elastic striker's back end, free, `back_delay` beyond its last node: the node moves at
    the wave arriving at it plus that wave as the free end returns it, `back_delay` later:
    `y_N' = v_b(t) + v_b(t − d)`, integrated over the step exactly for rates linear in each step."""
    new, cur, _, _ = layer
    n_s = striker_u.shape[1] - 1
    now = incoming_wave(striker_u, layer, n_s - 1, n_s, ends, BACK_INCOMING, tau)
    d = striker.back_delay
    rates = back_rates(ends, now)
    returned = rate_integral(rates, tau, -d, tau - d, 1)
    striker_u[new, n_s] = striker_u[cur, n_s] + tau * now[0] + returned
    # each wave there carries Z·v² of power, the arriving one for the last d/2, the returned one
    # for the d/2 before: Z·∫v_b² over [t − d, t], at the step's middle as the grid's energy is
    ends[S_BACK_ENERGY] = striker.back_impedance * rate_integral(rates, tau, 0.5 * tau - d, 0.5 * tau, 2)
    ends[S_BACK_MEAN_BEFORE], ends[S_BACK_SLOPE_BEFORE] = ends[S_BACK_MEAN], ends[S_BACK_SLOPE]
    ends[S_BACK_MEAN], ends[S_BACK_SLOPE] = now


@compiled(inline="always")
def incoming_wave(u, layer, inner, edge, ends, slots, tau):
    """For the ends that integrate their own equations: the mean rate over this step of the wave
    arriving at the end node `edge` (its neighbour `inner`) and its slope within the step. Its
    displacement `G_m = u_inner^{m−1} − u_edge^{m−2} + G_{m−2}`: G_{m−1}, G_{m−2}, G_{m−3} are
    carried in the end's `slots` (`INCOMING`…); G_m, G_{m+1} come from the layers."""
    new, cur, old, _ = layer
    last, before, earlier = slots
    g_earlier, g_before, g_last = ends[earlier], ends[before], ends[last]
    g_now = u[cur, inner] - u[old, edge] + g_before
    g_next = u[new, inner] - u[cur, edge] + g_last
    rate = (g_now - g_last) / tau
    slope = limited_slope((g_before - g_earlier) / tau, (g_last - g_before) / tau, rate, (g_next - g_now) / tau, tau)
    ends[earlier], ends[before], ends[last] = g_before, g_last, g_now
    return rate, slope
