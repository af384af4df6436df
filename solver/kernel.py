"""The time-stepping kernel: every scheme of `schemes.py` as one tridiagonal solve a step.

Unknowns of layer n+1 are `[y, u_0, …, u_N]` (model.md). The rows `u_1 … u_N` never change from
step to step (only their right-hand sides do), so their elimination, swept from the working end
toward the struck end as in the paper's (14)–(20), is factored once in `factor_tool_rows`:
`u_i = P_i·u_{i−1} + Q_i`. A step then computes the `Q_i` (a recurrence toward the struck end),
solves the striker row (11) and the struck-end row (9) together, and substitutes forward (a
recurrence toward the working end). The explicit scheme's interior rows are uncoupled (`P_i = 0`):
its passes have no recurrence and vectorise.

Each recurrence has one multiply-add a node on its critical path, so swept node by node it runs at
that instruction's latency, not at the machine's throughput. So the nodes are cut into
`SEGMENTS` segments, swept together as independent chains from a zero start, and each segment's
true values are its chain's plus a multiple of the value carried into it. The multiples, products
of the recurrence's coefficients along the segment, are constant like the factors and computed
with them; the carries are one step a segment.

Those two rows are linear but for the contact force. It is the difference quotient of the contact
potential Φ (`Φ' = G(δ)·δ`) between the new overlap and a reference one (layer n for the paper,
n−1 for the centred schemes), plus the damper `b1`: a scalar monotone equation for δ^{n+1},
solved by safeguarded Newton. Unlike the paper's lagged `G(δ^n)·δ^{n+1}` it never creates energy,
whatever the time step; the two agree to first order in τ.

Everything the summary needs (contact intervals, peaks, the energy audit) is observed inside the
loop, so a summary-only run keeps nothing of size N·M.

All arrays are float64. Layers n−1, n, n+1 of the tool live in rows `(n−1)%3, n%3, (n+1)%3` of
`u` (3 × (N+1)) and of the striker's `y` (3), so no state but the layer index is carried between
chunks. Layer −1 (row 2) is the state one step before the impact, `z − τ·z'`, so the first step
is an ordinary step of the scheme. The layers are indexed as `u[row, i]`, never through a row view:
Numba counts a view's references with atomic instructions, and three views a step cost about
0.4 ns a node-step on 100 cells, a sixth of the step. Where LLVM cannot prove an index
non-negative, it is unsigned: Numba wraps negative indices around, and that check on every load
keeps loops from vectorising.
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np
from llvmlite import ir
from numba import njit, types
from numba.core import cgutils
from numba.extending import intrinsic

# Force kinds (`force_kind`)
FORCE_NONE, FORCE_SINE, FORCE_ABS_SINE, FORCE_PULSE = 0, 1, 2, 3

# History quantities: `history[H_…, k]` is the k-th kept layer's (one contiguous series each)
H_TIME, H_STRIKER_DISP, H_STRIKER_VEL, H_STRUCK_END, H_WORKING_END = 0, 1, 2, 3, 4
H_CONTACT_FORCE, H_OVERLAP, H_MEDIUM_FORCE, H_EXTERNAL_FORCE = 5, 6, 7, 8
H_EXTERNAL_WORK, H_DISSIPATED_CONTACT, H_DISSIPATED_MEDIUM = 9, 10, 11
H_STRIKER_KINETIC, H_TOOL_KINETIC, H_TOOL_STRAIN, H_CONTACT_POTENTIAL, H_MEDIUM_POTENTIAL = (
    12, 13, 14, 15, 16)
HISTORY_COLUMNS = 17

# Extreme slots (`extremes[X_…]`): what a run reports beyond its recordings, kept up to date
X_PEAK_FORCE, X_PEAK_FORCE_TIME = 0, 1
X_MAX_COMPRESSION, X_MAX_COMPRESSION_X, X_MAX_COMPRESSION_TIME = 2, 3, 4
X_MAX_TENSION, X_MAX_TENSION_X, X_MAX_TENSION_TIME = 5, 6, 7
X_CONTACTS, X_CO_IMPACT, X_REBOUND_VELOCITY = 8, 9, 10  # finished contact intervals; the first's end
X_ENERGY_EXCESS = 11  # max over time of (stored + dissipated − input): > 0 means energy created
X_FAILED_TIME = 12
X_MIN_CONTACT_STEPS = 13  # fewest steps any finished contact interval was resolved by
EXTREME_SLOTS = 14

# End slots (`ends[S_…]`): what the next step needs of the ends beyond the layers. Whether the
# striker is in contact and since when; the end forces and the contact potential at the last
# recorded layers (m−1, m−2, m−3); for the ends that integrate their own equations, the
# striker's velocity and the incoming waves' displacements G at the struck end and at the
# working end, at layers m−1, m−2
S_IN_CONTACT, S_CONTACT_START = 0, 1
S_FORCE_BEFORE, S_FORCE_BEFORE_THAT, S_FORCE_EARLIER = 2, 3, 4  # the contact force
S_MEDIUM_FORCE, S_MEDIUM_FORCE_BEFORE, S_MEDIUM_FORCE_EARLIER = 5, 6, 7
S_POTENTIAL_BEFORE, S_POTENTIAL_BEFORE_THAT = 8, 9  # contact potential Φ at layers m−1, m−2
S_STRIKER_VELOCITY = 10
S_INCOMING, S_INCOMING_BEFORE, S_FAR_INCOMING, S_FAR_INCOMING_BEFORE = 11, 12, 13, 14
END_SLOTS = 15

# Energy slots (`energy[0, …]` at the last layer, `energy[1, …]` at the one before): running work
# and dissipation, and the stored terms
E_EXTERNAL_WORK, E_DISSIPATED_CONTACT, E_DISSIPATED_MEDIUM = 0, 1, 2
E_STRIKER_KINETIC, E_TOOL_KINETIC, E_TOOL_STRAIN, E_CONTACT_POTENTIAL, E_MEDIUM_POTENTIAL = (
    3, 4, 5, 6, 7)
ENERGY_SLOTS = 8

STATUS_OK, STATUS_NON_FINITE = 0, 1

# The end conditions, as the kernel takes them
StruckEnd = namedtuple("StruckEnd", "mass velocity c1 alpha c0 b1 impedance")
"""The striker (m1, W1), the contact (c1, α, c0, b1) and the end cell's impedance ρ·a·S̄ (N·s/m)."""
WorkingEnd = namedtuple("WorkingEnd", "c2 b2 impedance")
"""The medium (c2, b2; 0 for a free end) and the end cell's impedance."""
ForceLaw = namedtuple("ForceLaw", "kind amplitude omega start duration")
"""R(t): a `FORCE_…` kind and its parameters."""

# Independent chains a recurrence along the tool is split into: enough to hide the multiply-add's
# latency (4 cycles) behind the other chains' work. `sweep_toward_struck_end` and
# `substitute_toward_working_end` are written out for this many.
SEGMENTS = 4
MIN_SEGMENT = 8  # shorter segments are not worth their carries: the tool is swept serially


def new_extremes() -> np.ndarray:
    """The extremes before a run: none yet (NaN where nothing may happen)."""
    x = np.zeros(EXTREME_SLOTS)
    x[X_CO_IMPACT] = np.nan
    x[X_REBOUND_VELOCITY] = np.nan
    x[X_FAILED_TIME] = np.nan
    x[X_MIN_CONTACT_STEPS] = np.inf
    return x


@njit(cache=True)
def boundary_weights(weight_new, centered, end_masses, tau):
    """How the end rows and the boundary terms weight the layers.

    Returns `(end_weight, spring_weight, damper_factor, back)`: the end rows' weight of the new
    layer in the tool's own stiffness (the interior's with end masses; 1 for quasi-static massless
    ends); the boundary springs' weight of the new layer (the rest on the reference layer); the
    dampers' rate factor (`1/(2τ)` centred, `1/τ` backward); how many layers before the new one
    the boundary terms' reference layer lies (2: n−1 centred; 1: n for the paper).
    """
    end_weight = weight_new if end_masses else 1.0
    if centered:
        return end_weight, 0.5, 0.5 / tau, 2
    return end_weight, 1.0, 1.0 / tau, 1


@njit(cache=True)
def segment_layout(n):
    """`(length, head)`: nodes `1 … head` are swept serially, nodes `head+1 … n` as `SEGMENTS`
    segments of `length` nodes (none when the tool is too short for them)."""
    length = n // SEGMENTS if n >= SEGMENTS * MIN_SEGMENT else 0
    return length, n - SEGMENTS * length


@njit(cache=True)
def factor_tool_rows(grid_lower, grid_upper, node_area, end_stiffness, medium_stiffness,
                     medium_damping, r, tau, density, h, weight_new, centered, end_masses):
    """Eliminate rows u_N … u_1 once: returns `P`, `1/den`, the coefficient `c` of `Q_{i+1}` in
    `Q_i = rhs_i/den_i + c_i·Q_{i+1}`, and the segments' multiples of their carries: for node i of a
    segment `b … e` (`segment_layout`), `Π c_j` over `i … e` and `Π P_j` over `b … i`.

    Row u_N: `(M_N/τ² + θ·k_N + θ_s·c2 + b2·d)·u_N − θ·k_N·u_{N−1} = rhs`, `k_N = S·E/h`, with
    the weights of `boundary_weights`.
    Rows u_i: `−w·r·lower_i·u_{i−1} + (1 + w·r·(lower_i + upper_i))·u_i − w·r·upper_i·u_{i+1} = rhs_i`.
    """
    end_weight, spring_weight, damper_factor, _ = boundary_weights(weight_new, centered, end_masses, tau)
    n = len(node_area) - 1
    p = np.zeros(n + 1)
    inv_den = np.zeros(n + 1)
    carry = weight_new * r * grid_upper
    mass_n = density * h * node_area[n] / (tau * tau)
    diag_n = (mass_n + end_weight * end_stiffness + spring_weight * medium_stiffness
              + medium_damping * damper_factor)
    p[n] = end_weight * end_stiffness / diag_n
    inv_den[n] = 1.0 / diag_n
    for i in range(n - 1, 0, -1):
        den = 1.0 + weight_new * r * (grid_lower[i] + grid_upper[i]) - carry[i] * p[i + 1]
        p[i] = weight_new * r * grid_lower[i] / den
        inv_den[i] = 1.0 / den
    coefficient = carry * inv_den
    coefficient[n] = 0.0  # nothing is carried into row u_N
    length, head = segment_layout(n)
    coefficient_product = np.ones(n + 1)
    p_product = np.ones(n + 1)
    for start in range(head + 1, n + 1, max(length, 1)):
        end = start + length - 1
        product = 1.0
        for i in range(end, start - 1, -1):
            product *= coefficient[i]
            coefficient_product[i] = product
        product = 1.0
        for i in range(start, end + 1):
            product *= p[i]
            p_product[i] = product
    return p, inv_den, coefficient, coefficient_product, p_product


@njit(cache=True, inline="always")
def segment_starts(length, head):
    """The segments' length and first nodes, unsigned (`segment_layout`)."""
    size = np.uint64(length)
    b0 = np.uint64(head + 1)
    return size, b0, b0 + size, b0 + np.uint64(2) * size, b0 + np.uint64(3) * size


@njit(cache=True, inline="always")
def sweep_toward_struck_end(u, row, coefficient, coefficient_product, length, head):
    """`Q_i = a_i + c_i·Q_{i+1}` for i = n … 1, row `row` of `u` holding `a_i` on entry.

    Returns `Q_1` and the true Q carried into each segment (`Q_{e+1}`, e its last node). On return
    the row holds the segments' chains, started from 0 (true: chain + `Π c`·carry), and the head's
    true values.
    """
    first = 0.0  # Q_{n+1}
    carry_0 = carry_1 = carry_2 = carry_3 = 0.0  # carry_3 stays 0: the last segment ends at row N
    if length > 0:
        size, b0, b1, b2, b3 = segment_starts(length, head)
        s0 = s1 = s2 = s3 = 0.0
        for k in range(size):
            j = size - np.uint64(1) - k
            s0 = u[row, b0 + j] + coefficient[b0 + j] * s0
            u[row, b0 + j] = s0
            s1 = u[row, b1 + j] + coefficient[b1 + j] * s1
            u[row, b1 + j] = s1
            s2 = u[row, b2 + j] + coefficient[b2 + j] * s2
            u[row, b2 + j] = s2
            s3 = u[row, b3 + j] + coefficient[b3 + j] * s3
            u[row, b3 + j] = s3
        carry_2 = u[row, b3] + coefficient_product[b3] * carry_3
        carry_1 = u[row, b2] + coefficient_product[b2] * carry_2
        carry_0 = u[row, b1] + coefficient_product[b1] * carry_1
        first = u[row, b0] + coefficient_product[b0] * carry_0
    for i in range(head, 0, -1):
        first = u[row, i] + coefficient[i] * first
        u[row, i] = first
    return first, carry_0, carry_1, carry_2, carry_3


@njit(cache=True, inline="always")
def substitute_toward_working_end(u, row, p, coefficient_product, p_product, length, head, x_0,
                                  carry_0, carry_1, carry_2, carry_3):
    """`u_i = P_i·u_{i−1} + Q_i` for i = 1 … n from `u_0 = x_0`, row `row` of `u` holding what
    `sweep_toward_struck_end` left, with its carries: the true Q are made on the way."""
    prev = x_0
    for i in range(1, head + 1):
        prev = p[i] * prev + u[row, i]
        u[row, i] = prev
    if length == 0:
        return
    size, b0, b1, b2, b3 = segment_starts(length, head)
    s0 = s1 = s2 = s3 = 0.0
    for j in range(size):
        s0 = p[b0 + j] * s0 + (u[row, b0 + j] + coefficient_product[b0 + j] * carry_0)
        u[row, b0 + j] = s0
        s1 = p[b1 + j] * s1 + (u[row, b1 + j] + coefficient_product[b1 + j] * carry_1)
        u[row, b1 + j] = s1
        s2 = p[b2 + j] * s2 + (u[row, b2 + j] + coefficient_product[b2 + j] * carry_2)
        u[row, b2 + j] = s2
        s3 = p[b3 + j] * s3 + (u[row, b3 + j] + coefficient_product[b3 + j] * carry_3)
        u[row, b3 + j] = s3
    # Each segment's chain plus `Π P` times the true value before it, segment after segment.
    before = prev
    for start in (b0, b1, b2, b3):
        end = start + size - np.uint64(1)
        after = u[row, end] + p_product[end] * before
        for j in range(size):
            u[row, start + j] += p_product[start + j] * before
        before = after


@njit(cache=True, inline="always")
def external_force(t, kind, amplitude, omega, start, duration):
    """`R(t)`: P·sin(ωt), P·|sin(ωt)|, or P on [t1, t1 + Δt]."""
    if kind == FORCE_SINE:
        return amplitude * np.sin(omega * t)
    if kind == FORCE_ABS_SINE:
        return amplitude * abs(np.sin(omega * t))
    if kind == FORCE_PULSE:
        if start <= t <= start + duration:
            return amplitude
    return 0.0


@njit(cache=True, inline="always")
def contact_law(delta, c1, alpha, c0):
    """`(Φ'(δ), Φ(δ))`: the spring force G(δ)·δ of (7), `c1·δ^(α+1)` in contact and `c0·δ` in
    separation, and the energy Φ the contact stores, `c1·δ^(α+2)/(α+2)` or `c0·δ²/2`; one power
    for both, as on a small grid the contact solve is a large part of a step."""
    if delta >= 0.0:
        force = c1 * delta ** (alpha + 1.0)
        return force, force * delta / (alpha + 2.0)
    return c0 * delta, 0.5 * c0 * delta * delta


@njit(cache=True, inline="always")
def contact_spring(delta, c1, alpha, c0):
    """`(Φ'(δ), Φ''(δ))`: the contact's spring force G(δ)·δ and its stiffness; the common
    exponents without a power."""
    if delta >= 0.0:
        if alpha == 0.0:
            return c1 * delta, c1
        if alpha == 0.5:
            root = math.sqrt(delta)
            return c1 * delta * root, 1.5 * c1 * root
        power = delta**alpha
        return c1 * delta * power, (alpha + 1.0) * c1 * power
    return c0 * delta, c0


@njit(cache=True, inline="always")
def quotient_force(delta, ref, ref_potential, c1, alpha, c0):
    """`(Φ(δ) − Φ_ref)/(δ − ref)` and its derivative in δ (the midpoint values when δ ≈ ref).

    `Φ_ref` is Φ(ref) but for the state before impact, where no link acts yet and it is 0.
    """
    diff = delta - ref
    if abs(diff) > 1e-7 * (abs(delta) + abs(ref)):
        spring, potential = contact_law(delta, c1, alpha, c0)
        inverse = 1.0 / diff
        f = (potential - ref_potential) * inverse
        return f, (spring - f) * inverse
    mid = 0.5 * (delta + ref)
    spring, stiffness = contact_spring(mid, c1, alpha, c0)
    return spring, 0.5 * stiffness


@njit(cache=True, inline="always")
def bracketed_newton_step(x, g, slope, lo, hi, scale):
    """One Newton step on an increasing g, g(x) = `g`, g'(x) = `slope`, within the bracket [lo, hi]
    narrowed by the sign of g; a step that leaves it is replaced by bisection. Returns the new x,
    the bracket, and whether the step or the bracket is within `scale`."""
    if g > 0.0:
        hi = x
    else:
        lo = x
    x_new = x - g / slope
    if not lo < x_new < hi:
        x_new = 0.5 * (lo + hi)
    return x_new, lo, hi, abs(x_new - x) <= scale or hi - lo <= scale


@njit(cache=True)
def solve_overlap(free, compliance, ref, ref_potential, guess, c1, alpha, c0, damper):
    """The new overlap δ of `δ + compliance·F(δ) = free`, `F(δ) = quotient(δ, ref) + damper·(δ − ref)`.

    F increases with δ (Φ is convex), so the root is unique and lies between `free` and
    `free − compliance·F(free)`, where `bracketed_newton_step` finds it.
    """
    f_free = quotient_force(free, ref, ref_potential, c1, alpha, c0)[0] + damper * (free - ref)
    other = free - compliance * f_free
    lo, hi = min(free, other), max(free, other)
    if lo == hi:
        return free
    x = min(max(guess, lo), hi)
    scale = 1e-15 * (abs(lo) + abs(hi))
    for _ in range(100):
        f, df = quotient_force(x, ref, ref_potential, c1, alpha, c0)
        g = x + compliance * (f + damper * (x - ref)) - free
        if g == 0.0:
            return x
        x, lo, hi, done = bracketed_newton_step(x, g, 1.0 + compliance * (df + damper), lo, hi, scale)
        if done:
            return x
    return x


@njit(cache=True, inline="always")
def crossing(before_that, before, now):
    """Where in the last step (0 … 1) the overlap crossed zero, on the parabola through its last
    three values (a straight line when it has only two); third order, so the contact times' error
    is the scheme's, not where the crossing fell between two layers."""
    linear = before / (before - now)
    if not (before_that == before_that):
        return linear
    a = 0.5 * (now + before_that) - before
    b = 0.5 * (now - before_that)
    disc = b * b - 4.0 * a * before
    if a == 0.0 or disc < 0.0:
        return linear
    root = math.sqrt(disc)
    for x in ((-b + root) / (2.0 * a), (-b - root) / (2.0 * a)):
        if 0.0 <= x <= 1.0:
            return x
    return linear


@njit(cache=True, inline="always")
def node_stress(u, row, i, n, e_over_h, struck_end_stress, working_end_stress):
    """`σ_i = E·∂u/∂x` (tension +) of the layer in row `row` of `u`: central inside; at the ends
    the end force over the area."""
    if i == 0:
        return struck_end_stress
    if i == n:
        return working_end_stress
    return 0.5 * e_over_h * (u[row, i + 1] - u[row, i - 1])


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


@njit(cache=True, inline="always")
def substeps(rate, span, limit):
    """Substeps of `span` that keep (`rate` × substep) within `limit`."""
    return min(MAX_SUBSTEPS, max(1, math.ceil(rate * span / limit)))


@njit(cache=True)
def solve_spring_balance(target, compliance, guess, c1, alpha, c0):
    """δ with `δ + compliance·Φ'(δ) = target`: Φ' increases, so the root is unique and lies between
    `target` and `target − compliance·Φ'(target)`, where `bracketed_newton_step` finds it (on one
    linear branch, directly)."""
    other = target - compliance * contact_spring(target, c1, alpha, c0)[0]
    lo, hi = min(target, other), max(target, other)
    if lo == hi:
        return target
    # on one linear branch the root is direct (in separation, or for a linear contact)
    if hi <= 0.0:
        return target / (1.0 + compliance * c0)
    if lo >= 0.0 and alpha == 0.0:
        return target / (1.0 + compliance * c1)
    x = min(max(guess, lo), hi)
    scale = 1e-15 * (abs(lo) + abs(hi))
    for _ in range(100):
        spring, stiffness = contact_spring(x, c1, alpha, c0)
        g = x + compliance * spring - target
        if g == 0.0:
            return x
        x, lo, hi, done = bracketed_newton_step(x, g, 1.0 + compliance * stiffness, lo, hi, scale)
        if done:
            return x
    return x


@njit(cache=True, inline="always")
def struck_end_force(delta, w, v_in, end):
    """The contact force from the overlap, the striker's velocity and the incoming wave: the
    damper sees `δ' = w − u_0'`, `u_0' = F/Z + 2·v_in`, so `F(1 + b1/Z) = Φ'(δ) + b1·(w − 2·v_in)`."""
    spring = contact_spring(delta, end.c1, end.alpha, end.c0)[0]
    return (spring + end.b1 * (w - 2.0 * v_in)) / (1.0 + end.b1 / end.impedance)


@njit(cache=True, inline="always")
def struck_end_stage(by, bw, bu, g, r, v_in, guess, end):
    """One implicit stage `X = B + g·f(X)` of the striker and the struck end, X = (y, w, u_0):
    `y' = w`, `m1·w' = R − F`, `u_0' = F/Z + 2·v_in`. Everything is linear in F but the spring
    Φ'(δ), so the stage is one scalar equation in δ = y − u_0. Returns `(y, w, u_0, F, δ)`."""
    m1, z, b1 = end.mass, end.impedance, end.b1
    compliance = g * g / m1 + g / z  # how δ gives way to F within the stage
    denominator = 1.0 + b1 / z + b1 * g / m1
    pushed = b1 * (bw + g * r / m1 - 2.0 * v_in)
    free = by - bu - 2.0 * g * v_in + g * bw + g * g * r / m1  # δ were F = 0
    delta = solve_spring_balance(free - compliance * pushed / denominator, compliance / denominator,
                                 guess, end.c1, end.alpha, end.c0)
    force = (contact_spring(delta, end.c1, end.alpha, end.c0)[0] + pushed) / denominator
    w = bw + g * (r - force) / m1
    return by + g * w, w, bu + g * (force / z + 2.0 * v_in), force, delta


@njit(cache=True, inline="always")
def force_on_substep(t, t_a, t_b, force):
    """R at t on a substep [t_a, t_b] that no break of R crosses: a pulse takes its value at the
    substep's midpoint, so that both ends of the substep see its side of a jump."""
    if force.kind == FORCE_PULSE:
        t = 0.5 * (t_a + t_b)
    return external_force(t, force.kind, force.amplitude, force.omega, force.start, force.duration)


@njit(cache=True, inline="always")
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


@njit(cache=True, inline="always")
def hermite(a, b, rate_a, rate_b, span, s):
    """The cubic with values a, b and rates rate_a, rate_b at the ends of a span, at fraction s."""
    s2 = s * s
    s3 = s2 * s
    return ((2.0 * s3 - 3.0 * s2 + 1.0) * a + (s3 - 2.0 * s2 + s) * span * rate_a
            + (3.0 * s2 - 2.0 * s3) * b + (s3 - s2) * span * rate_b)


@njit(cache=True)
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


@njit(cache=True, inline="always")
def limited_slope(before, now, after, tau):
    """The slope within a step of a rate whose means over it and its neighbours are given: the
    smaller of the two one-sided slopes, 0 where they disagree in sign (minmod)."""
    left, right = now - before, after - now
    if left * right <= 0.0:
        return 0.0
    return (left if abs(left) < abs(right) else right) / tau


@njit(cache=True)
def struck_end_step(t0, tau, state, v_mean, v_slope, end, force, events):
    """Advance the striker and the struck end over [t0, t0 + τ] under the incoming wave's rate
    `v_in(t) = v_mean + v_slope·(t − t0 − τ/2)`, split where R jumps or kinks.

    `state` = (y, w, u_0, F) at t0 on entry, at t0 + τ on return. Returns the work of R and what the damper b1 dissipated over the step,
    the number of changes of sign of δ, each written to `events` (time, striker velocity, +1 into
    contact or −1 out of it; at most `events.shape[0]`), and the largest and least force at the
    substeps' ends with their times (a stiff contact's substeps see a peak the layers miss).
    """
    gamma = SDIRK_GAMMA
    t_a = t0
    t_end = t0 + tau
    work = 0.0
    dissipated = 0.0
    count = 0
    y, w, u0 = state[0], state[1], state[2]
    v_start = v_mean - 0.5 * tau * v_slope
    f = struck_end_force(y - u0, w, v_start, end)  # under the wave arriving now: F can jump at t0
    f_max, t_max, f_min, t_min = f, t0, f, t0
    t_stop = t0
    sub = tau
    while t_a < t_end:
        if t_a >= t_stop:
            # the next stretch without a break of R, in substeps for the contact's relaxation
            # against the tool (its stiffness at the overlap the stretch may reach)
            t_next = min(t_end, next_break(t_a, force))
            reach = abs(y - u0) + (t_next - t_a) * abs(w - f / end.impedance - 2.0 * v_mean)
            stiffness = max(contact_spring(reach, end.c1, end.alpha, end.c0)[1], end.c0)
            braking = (end.impedance + end.b1) / end.mass
            count_sub = substeps(stiffness / (end.impedance + end.b1), t_next - t_a,
                                 min(SDIRK_MONOTONE, STIFF_RISE_STEPS * braking * tau))
            sub = (t_next - t_a) / count_sub
            t_stop = t_next
        t_b = t_stop if t_a + 1.5 * sub >= t_stop else t_a + sub
        span = t_b - t_a
        g = gamma * span
        # stage 1 at t_a + γ·span
        t1 = t_a + g
        r1 = force_on_substep(t1, t_a, t_b, force)
        v1 = v_start + v_slope * (t1 - t0)
        y1, w1, u1, f1, d1 = struck_end_stage(y, w, u0, g, r1, v1, y - u0, end)
        ky, kw, ku = w1, (r1 - f1) / end.mass, f1 / end.impedance + 2.0 * v1
        # stage 2 at t_b: the new state (stiffly accurate)
        r2 = force_on_substep(t_b, t_a, t_b, force)
        v2 = v_start + v_slope * (t_b - t0)
        step = (1.0 - gamma) * span
        y2, w2, u2, f2, d2 = struck_end_stage(y + step * ky, w + step * kw, u0 + step * ku, g,
                                              r2, v2, d1, end)
        rate1 = w1 - ku
        rate2 = w2 - (f2 / end.impedance + 2.0 * v2)
        work += span * ((1.0 - gamma) * r1 * w1 + gamma * r2 * w2)
        dissipated += span * end.b1 * ((1.0 - gamma) * rate1 * rate1 + gamma * rate2 * rate2)
        # a change of sign of δ: where, on the cubic through the ends' values and rates
        delta_a = y - u0
        if (delta_a >= 0.0) != (d2 >= 0.0) and count < events.shape[0]:
            r_a = force_on_substep(t_a, t_a, t_b, force)
            rate_a = w - (f / end.impedance + 2.0 * (v_start + v_slope * (t_a - t0)))
            s = hermite_root(delta_a, d2, rate_a, rate2, span)
            events[count, 0] = t_a + s * span
            events[count, 1] = hermite(w, w2, (r_a - f) / end.mass, (r2 - f2) / end.mass, span, s)
            events[count, 2] = 1.0 if d2 >= 0.0 else -1.0
            count += 1
        y, w, u0, f = y2, w2, u2, f2
        t_a = t_b
        if f > f_max:
            f_max, t_max = f, t_a
        if f < f_min:
            f_min, t_min = f, t_a
    state[0], state[1], state[2], state[3] = y, w, u0, f
    return work, dissipated, count, f_max, t_max, f_min, t_min


@njit(cache=True, inline="always")
def working_end_step(tau, state, v_mean, v_slope, end):
    """Advance the working end over one step under the incoming wave's rate
    `v_in(t) = v_mean + v_slope·(t − τ/2)` (t from the step's start):
    `u_N' = −F_m/Z + 2·v_in`, `F_m = c2·u_N + b2·u_N'`, linear, so each SDIRK stage is solved
    directly, in substeps for the medium's relaxation `c2/(Z + b2)`. `state` = (u_N, F_m).
    Returns what the damper b2 dissipated and the largest and least F_m just after the step's
    start and at the substeps' ends, with their offsets from the step's start."""
    gamma = SDIRK_GAMMA
    z_total = end.impedance + end.b2
    count = substeps(end.c2 / z_total, tau, SDIRK_MONOTONE)
    span = tau / count
    g = gamma * span
    u = state[0]
    v_start = v_mean - 0.5 * tau * v_slope
    k2 = (2.0 * end.impedance * v_start - end.c2 * u) / z_total
    f_max = f_min = end.c2 * u + end.b2 * k2  # under the wave arriving now
    t_max = t_min = 0.0
    dissipated = 0.0
    for j in range(count):
        t_a = j * span
        v1 = v_start + v_slope * (t_a + g)
        u1 = (u + g * 2.0 * end.impedance * v1 / z_total) / (1.0 + g * end.c2 / z_total)
        k1 = (2.0 * end.impedance * v1 - end.c2 * u1) / z_total
        base = u + (1.0 - gamma) * span * k1
        v2 = v_start + v_slope * (t_a + span)
        u = (base + g * 2.0 * end.impedance * v2 / z_total) / (1.0 + g * end.c2 / z_total)
        k2 = (2.0 * end.impedance * v2 - end.c2 * u) / z_total
        dissipated += span * end.b2 * ((1.0 - gamma) * k1 * k1 + gamma * k2 * k2)
        f = end.c2 * u + end.b2 * k2
        if f > f_max:
            f_max, t_max = f, t_a + span
        if f < f_min:
            f_min, t_min = f, t_a + span
    state[0] = u
    state[1] = end.c2 * u + end.b2 * k2
    return dissipated, f_max, t_max, f_min, t_min


def _llvm_binary(name):
    """A Numba function `(float64, float64) → float64` that is the LLVM intrinsic `name`."""
    @intrinsic
    def call(typingctx, a, b):
        def codegen(context, builder, signature, args):
            double = ir.DoubleType()
            fn = cgutils.get_or_insert_function(
                builder.module, ir.FunctionType(double, [double, double]), name)
            return builder.call(fn, args)
        return types.float64(types.float64, types.float64), codegen
    return call


# LLVM vectorises a min/max reduction written with these. Numba's `min`/`max` are a compare and a
# select, which it does not, even under `fastmath` (Numba flags the compare, not the select).
fmin = _llvm_binary("llvm.minnum.f64")
fmax = _llvm_binary("llvm.maxnum.f64")

# Nodes a block: enough for a block's vector reduction to pay, few for searching one to be cheap
STRESS_BLOCK = 64


# One pass for the energy and the stresses, in one vectorised loop; its fast-math flags:
# - `reassoc`: sums of N terms may be reordered, which changes them by rounding only;
# - `nnan`, `nsz`: min/max are plain vector instructions, without NaN or signed-zero fix-ups (LLVM
#   vectorises them beside the sums only with both). Sound: a non-finite displacement makes the
#   kinetic energy non-finite, which `advance` checks before it uses the stresses, and a stress of
#   −0 or +0 is the same record.
@njit(cache=True, fastmath={"contract", "reassoc", "nnan", "nsz"})
def tool_energy_and_stresses(u, new, cur, stressed, node_area, area_mid, strain_sigma,
                             half_e_over_h):
    """The tool's energy terms between the layers in rows `new`, `cur` of `u` and the interior
    stress extremes of the layer in row `stressed`: `(Σ S_i·(u_i − uc_i)², Σ S_{i+½}·[σ(e_a² +
    e_b²) + (1 − 2σ)·e_a·e_b], least stress, its block, greatest stress, its block)`.

    The sums are twice the kinetic energy times τ²/(ρh) and twice the strain energy times h/E, e
    the cell strains. The stresses are `½·E/h·(u_{i+1} − u_{i−1})` at the interior nodes of that
    layer (±inf when it has none), each with the first node of the first block of `STRESS_BLOCK`
    nodes that holds it: a loop that carries an extreme's index does not vectorise, so
    `first_node` finds the node in the block, when it is wanted.
    """
    n = u.shape[1] - 1
    one = np.uint64(1)
    strain_cross = 1.0 - 2.0 * strain_sigma
    du = u[new, 0] - u[cur, 0]
    kinetic = node_area[0] * du * du
    strain = 0.0
    low, high = np.inf, -np.inf
    low_start = high_start = 0
    for start in range(1, n, STRESS_BLOCK):
        lo, hi = low, high
        for i in range(np.uint64(start), np.uint64(min(start + STRESS_BLOCK, n))):
            du = u[new, i] - u[cur, i]
            kinetic += node_area[i] * du * du
            ea = u[new, i] - u[new, i - one]
            eb = u[cur, i] - u[cur, i - one]
            strain += area_mid[i - one] * (strain_sigma * (ea * ea + eb * eb) + strain_cross * ea * eb)
            s = half_e_over_h * (u[stressed, i + one] - u[stressed, i - one])
            lo = fmin(lo, s)
            hi = fmax(hi, s)
        if lo < low:
            low, low_start = lo, start
        if hi > high:
            high, high_start = hi, start
    du = u[new, n] - u[cur, n]
    kinetic += node_area[n] * du * du
    ea = u[new, n] - u[new, n - 1]
    eb = u[cur, n] - u[cur, n - 1]
    strain += area_mid[n - 1] * (strain_sigma * (ea * ea + eb * eb) + strain_cross * ea * eb)
    return kinetic, strain, low, low_start, high, high_start


@njit(cache=True, fastmath={"nnan"})
def first_node(u, row, half_e_over_h, start, value):
    """The first node of the block from `start` where the stress is `value` (its last if none)."""
    one = np.uint64(1)
    last = min(start + STRESS_BLOCK, u.shape[1] - 1) - 1
    first = last
    for i in range(np.uint64(start), np.uint64(last + 1)):
        found = half_e_over_h * (u[row, i + one] - u[row, i - one]) == value
        first = min(first, np.int64(i) if found else last)
    return first



@njit(cache=True, inline="always")
def track_contact(ends, extremes, contacts, t_cross, velocity, into_contact, tau):
    """A change of the overlap's sign at `t_cross`: opens or closes a contact interval (δ ≥ 0 is
    contact); the first one to close sets the co-impact time and the rebound velocity."""
    in_contact = ends[S_IN_CONTACT] != 0.0
    if in_contact and not into_contact:
        k = int(extremes[X_CONTACTS])
        if k < contacts.shape[0]:
            contacts[k, 0] = ends[S_CONTACT_START]
            contacts[k, 1] = t_cross
        extremes[X_CONTACTS] = k + 1
        steps = (t_cross - ends[S_CONTACT_START]) / tau
        if steps < extremes[X_MIN_CONTACT_STEPS]:
            extremes[X_MIN_CONTACT_STEPS] = steps
        if k == 0:
            extremes[X_CO_IMPACT] = t_cross
            extremes[X_REBOUND_VELOCITY] = velocity
        ends[S_IN_CONTACT] = 0.0
    elif not in_contact and into_contact:
        ends[S_IN_CONTACT] = 1.0
        ends[S_CONTACT_START] = t_cross


@njit(cache=True, inline="always")
def vertex(earliest, before_that, before, now):
    """The maximum between four equally spaced samples whose third is a strict maximum: the vertex
    of the parabola through the last three, `(value, where it lies from the third sample in
    steps)`, when the samples are a parabola's (their third difference small against the second:
    a parabola fitted across a jump, such as a stiff link's unresolved rise, overshoots by a
    fraction of the jump); else `(before, 0)`."""
    second = now - 2.0 * before + before_that
    third = now - 3.0 * before + 3.0 * before_that - earliest
    if before >= before_that and before > now and abs(third) <= 0.5 * abs(second):
        offset = 0.5 * (now - before_that) / -second
        return before + 0.25 * (now - before_that) * offset, offset
    return before, 0.0


@njit(cache=True, inline="always")
def track_end_extreme(extremes, slot, value, x, t):
    if value > extremes[slot]:
        extremes[slot] = value
        extremes[slot + 1] = x
        extremes[slot + 2] = t


# `contract` lets LLVM fuse `a·b + c` into one multiply-add (one rounding instead of two) where the
# CPU has one: each of the two recurrences along the tool then has a single operation a node on its
# critical path. No other fast-math assumption is made (NaN, infinities, reordering): the checks for
# non-finite values rely on that.
@njit(cache=True, fastmath={"contract"})
def advance(
    first, last,
    u, y, grid_lower, grid_upper, node_area, area_mid, uniform,
    p, inv_den, coefficient, coefficient_product, p_product,
    h, tau, r, youngs_modulus, density, end_stiffness_0, end_stiffness_n, end_area_0, end_area_n,
    weight_new, weight_old, centered, end_masses, impedance_ends,
    struck, working, force,
    ends, extremes, energy, contacts,
    history, history_stride, probe_node, probe_weight, probes,
    field_u, field_stress, field_stride,
):
    """Compute layers `first … last` (inclusive; layer 0 is the initial state).

    The interior operator weights layers n+1, n, n−1 by `weight_new`, `1 − weight_new −
    weight_old`, `weight_old`. `centered` centres the boundary terms on layer n (springs
    `(z^{n+1} + z^{n−1})/2`, dampers `(z^{n+1} − z^{n−1})/(2τ)`, the contact quotient between
    δ^{n+1} and δ^{n−1}); otherwise they are the paper's (new layer, `(z^{n+1} − z^n)/τ`).
    `end_masses` gives the end rows the interior's weights (they then carry their half-cell mass
    `node_area·ρh`); massless ends are quasi-static, all on the new layer. `impedance_ends` (the
    explicit scheme at Courant number 1 only) integrates each end's own equations instead (see
    `struck_end_step`).

    `struck` (StruckEnd), `working` (WorkingEnd) and `force` (ForceLaw) are the end conditions.

    What is recorded of a layer is what the scheme applies there: the centred schemes' boundary
    forces are centred on layer n, so a layer is recorded one step after it is computed (the
    caller runs one layer more); the paper's act on the new layer, the ends that integrate their
    own equations have their forces at every instant.

    Writes every `history_stride`-th recorded layer to `history` (a column each) and `probes` (a
    row each) and every `field_stride`-th to `field_u`/`field_stress` (strides ≤ 0 keep nothing),
    from the first of each buffer. `energy[0]` holds the energy terms of the last layer,
    `energy[1]` those of the one before. Returns `(status, layers of history written, rows of
    fields written)`; on a non-finite value it stops with `STATUS_NON_FINITE` and the time in
    `extremes[X_FAILED_TIME]`.
    """
    n = len(node_area) - 1
    striker_mass, striker_velocity = struck.mass, struck.velocity
    c1, alpha, c0, b1 = struck.c1, struck.alpha, struck.c0, struck.b1
    c2, b2 = working.c2, working.b2
    weight_cur = 1.0 - weight_new - weight_old
    inv_tau2 = 1.0 / (tau * tau)
    m1_tau2 = striker_mass * inv_tau2
    mass_0 = density * h * node_area[0] * inv_tau2
    mass_n = density * h * node_area[n] * inv_tau2
    end_weight, spring_weight, damper_factor, back = boundary_weights(
        weight_new, centered, end_masses, tau)
    lag = 1 if centered and not impedance_ends else 0  # the recorded layer is m − lag
    strain_sigma = weight_new if centered else 0.25  # 0.25: strain energy at the midpoint
    e_over_h = youngs_modulus / h
    half_e_over_h = 0.5 * e_over_h
    kinetic_factor = 0.5 * density * h * inv_tau2
    initial_energy = 0.5 * striker_mass * striker_velocity * striker_velocity
    length, head = segment_layout(n)
    explicit = weight_new == 0.0 and weight_old == 0.0
    end_state = np.empty(4)
    far_state = np.empty(2)
    events = np.empty((4, 3))
    n_hist = 0
    n_field = 0

    for m in range(first, last + 1):
        new = m % 3
        cur = (m - 1) % 3
        old = (m - 2) % 3
        t = m * tau
        if m == 0:
            # (5), (6): tool at rest, striker at 0 moving at W1; layer −1 one step before.
            for i in range(n + 1):
                u[new, i] = 0.0
                u[2, i] = 0.0
            y[new] = 0.0
            y[2] = -striker_velocity * tau
            velocity = striker_velocity
            medium_force = 0.0
            ends[S_IN_CONTACT] = 1.0  # δ(0) = 0: contact from the first instant
            ends[S_CONTACT_START] = 0.0
            # Φ(δ⁰) = Φ(0) = 0; the state before impact counts 0 too: no link acts yet.
            ends[S_POTENTIAL_BEFORE] = 0.0
            ends[S_POTENTIAL_BEFORE_THAT] = 0.0
            if impedance_ends:
                contact_force = struck_end_force(0.0, striker_velocity, 0.0, struck)
                ends[S_STRIKER_VELOCITY] = striker_velocity
                energy[0, E_STRIKER_KINETIC] = initial_energy
            else:
                contact_force = b1 * striker_velocity
            rec, t_rec = new, t
            s0 = -contact_force / end_area_0
            sn = 0.0
            low, high = np.inf, -np.inf
            low_block = high_block = 0
        else:
            for k in range(ENERGY_SLOTS):
                energy[1, k] = energy[0, k]
            # Right-hand sides of rows u_N … u_1 over their diagonals, eliminated toward the struck
            # end. The explicit layers enter the operator as one combination
            # v = w_n·u^n + w_{n−1}·u^{n−1}.
            if not impedance_ends:
                ref = (m - back) % 3
                v_right = weight_cur * u[cur, n] + weight_old * u[old, n]
                v_mid = weight_cur * u[cur, n - 1] + weight_old * u[old, n - 1]
                rhs = (mass_n * (2.0 * u[cur, n] - u[old, n]) - c2 * (1.0 - spring_weight) * u[ref, n]
                       + b2 * damper_factor * u[ref, n])
                if end_masses:
                    rhs -= end_stiffness_n * (v_right - v_mid)
                u[new, n] = rhs * inv_den[n]  # Q_i is kept in row `new` until the substitution
            if explicit and uniform:
                # v = u^n, and the interior rows are uncoupled (den_i = 1, nothing carried)
                for i in range(1, n):
                    u[new, i] = (2.0 * u[cur, i] - u[old, i]
                                 + r * (u[cur, i - 1] - 2.0 * u[cur, i] + u[cur, i + 1]))
            elif explicit:
                for i in range(1, n):
                    u[new, i] = (2.0 * u[cur, i] - u[old, i]
                                 + r * (grid_lower[i] * (u[cur, i - 1] - u[cur, i])
                                        + grid_upper[i] * (u[cur, i + 1] - u[cur, i])))
            else:
                for i in range(1, n):
                    v_left = weight_cur * u[cur, i - 1] + weight_old * u[old, i - 1]
                    v_mid = weight_cur * u[cur, i] + weight_old * u[old, i]
                    v_right = weight_cur * u[cur, i + 1] + weight_old * u[old, i + 1]
                    if uniform:
                        lap = v_left - 2.0 * v_mid + v_right
                    else:
                        lap = grid_lower[i] * (v_left - v_mid) + grid_upper[i] * (v_right - v_mid)
                    u[new, i] = (2.0 * u[cur, i] - u[old, i] + r * lap) * inv_den[i]

            if impedance_ends:
                # The waves arriving at the ends over this step, then each end's equations.
                # G_{m−2}, G_{m−1} carried; G_m, G_{m+1} from the layers
                g_before, g_last = ends[S_INCOMING_BEFORE], ends[S_INCOMING]
                g_now = u[cur, 1] - u[old, 0] + g_before
                g_next = u[new, 1] - u[cur, 0] + g_last
                v_in = (g_now - g_last) / tau
                v_slope = limited_slope((g_last - g_before) / tau, v_in, (g_next - g_now) / tau, tau)
                ends[S_INCOMING_BEFORE], ends[S_INCOMING] = g_last, g_now
                h_before, h_last = ends[S_FAR_INCOMING_BEFORE], ends[S_FAR_INCOMING]
                h_now = u[cur, n - 1] - u[old, n] + h_before
                h_next = u[new, n - 1] - u[cur, n] + h_last
                v_far = (h_now - h_last) / tau
                far_slope = limited_slope((h_last - h_before) / tau, v_far, (h_next - h_now) / tau, tau)
                ends[S_FAR_INCOMING_BEFORE], ends[S_FAR_INCOMING] = h_last, h_now

                end_state[0] = y[cur]
                end_state[1] = ends[S_STRIKER_VELOCITY]
                end_state[2] = u[cur, 0]
                end_state[3] = ends[S_FORCE_BEFORE]
                work, dissipated, crossings, f_max, t_max, f_min, t_min = struck_end_step(
                    t - tau, tau, end_state, v_in, v_slope, struck, force, events)
                far_state[0] = u[cur, n]
                far_state[1] = ends[S_MEDIUM_FORCE]
                dissipated_far, g_max, tg_max, g_min, tg_min = working_end_step(
                    tau, far_state, v_far, far_slope, working)
                # the ends' extremes between layers, as their substeps saw them
                if f_max > extremes[X_PEAK_FORCE]:
                    extremes[X_PEAK_FORCE] = f_max
                    extremes[X_PEAK_FORCE_TIME] = t_max
                track_end_extreme(extremes, X_MAX_COMPRESSION, f_max / end_area_0, 0.0, t_max)
                track_end_extreme(extremes, X_MAX_TENSION, -f_min / end_area_0, 0.0, t_min)
                track_end_extreme(extremes, X_MAX_COMPRESSION, g_max / end_area_n, n * h,
                                  t - tau + tg_max)
                track_end_extreme(extremes, X_MAX_TENSION, -g_min / end_area_n, n * h,
                                  t - tau + tg_min)
                if not (abs(end_state[0]) < 1e300 and abs(end_state[2]) < 1e300
                        and abs(far_state[0]) < 1e300):
                    extremes[X_FAILED_TIME] = t
                    return STATUS_NON_FINITE, n_hist, n_field
                y[new] = end_state[0]
                velocity = end_state[1]
                u[new, 0] = end_state[2]
                contact_force = end_state[3]
                u[new, n] = far_state[0]
                medium_force = far_state[1]
                ends[S_STRIKER_VELOCITY] = velocity
                for k in range(crossings):
                    track_contact(ends, extremes, contacts, events[k, 0], events[k, 1],
                                  events[k, 2] > 0.0, tau)
                rec, t_rec = new, t

                # Energy: the ends' terms at layer m, the tool's at m − ½ (the form the explicit
                # scheme conserves); the audit compares them at m − ½.
                delta = y[new] - u[new, 0]
                potential = contact_law(delta, c1, alpha, c0)[1]
                tool_kinetic, tool_strain, low, low_block, high, high_block = tool_energy_and_stresses(
                    u, new, cur, rec, node_area, area_mid, strain_sigma, half_e_over_h)
                energy[0, E_EXTERNAL_WORK] += work
                energy[0, E_DISSIPATED_CONTACT] += dissipated
                energy[0, E_DISSIPATED_MEDIUM] += dissipated_far
                energy[0, E_STRIKER_KINETIC] = 0.5 * striker_mass * velocity * velocity
                energy[0, E_TOOL_KINETIC] = tool_kinetic * kinetic_factor
                energy[0, E_TOOL_STRAIN] = tool_strain * 0.5 * e_over_h
                energy[0, E_CONTACT_POTENTIAL] = potential
                energy[0, E_MEDIUM_POTENTIAL] = 0.5 * c2 * u[new, n] * u[new, n]
                balance = energy[0, E_TOOL_KINETIC] + energy[0, E_TOOL_STRAIN] - initial_energy
                for k in (E_STRIKER_KINETIC, E_CONTACT_POTENTIAL, E_MEDIUM_POTENTIAL,
                          E_DISSIPATED_CONTACT, E_DISSIPATED_MEDIUM):
                    balance += 0.5 * (energy[0, k] + energy[1, k])
                balance -= 0.5 * (energy[0, E_EXTERNAL_WORK] + energy[1, E_EXTERNAL_WORK])
            else:
                y_cur = y[cur]
                delta_cur = y_cur - u[cur, 0]
                delta_old = y[old] - u[old, 0]
                delta_ref = y[ref] - u[ref, 0]
                r_n = external_force((m - 1) * tau, force.kind, force.amplitude, force.omega,
                                     force.start, force.duration)  # R(t_n), explicit in row (11)
                if explicit:
                    q_1, carry_0, carry_1, carry_2, carry_3 = u[new, 1], 0.0, 0.0, 0.0, 0.0
                else:
                    q_1, carry_0, carry_1, carry_2, carry_3 = sweep_toward_struck_end(
                        u, new, coefficient, coefficient_product, length, head)
                # Striker row (11) and struck-end row (9) with u_1 = P_1·u_0 + Q_1:
                # a_y·y = b_y − F and a_0·u_0 = b_0 + F, F the contact force, a scalar equation in δ.
                a_y = m1_tau2
                b_y = m1_tau2 * (2.0 * y_cur - y[old]) + r_n
                a_0 = mass_0 + end_weight * end_stiffness_0 * (1.0 - p[1])
                b_0 = mass_0 * (2.0 * u[cur, 0] - u[old, 0]) + end_weight * end_stiffness_0 * q_1
                if end_masses:
                    b_0 += end_stiffness_0 * ((weight_cur * u[cur, 1] + weight_old * u[old, 1])
                                              - (weight_cur * u[cur, 0] + weight_old * u[old, 0]))
                delta_free = b_y / a_y - b_0 / a_0
                compliance = 1.0 / a_y + 1.0 / a_0
                # Φ of the reference layer, as computed when it was new (0 for the state before impact)
                ref_potential = ends[S_POTENTIAL_BEFORE if back == 1 else S_POTENTIAL_BEFORE_THAT]
                delta = solve_overlap(delta_free, compliance, delta_ref, ref_potential,
                                      2.0 * delta_cur - delta_old, c1, alpha, c0, b1 * damper_factor)
                # the contact force the scheme applies in this step (centred on layer n, or on
                # the new layer for the paper's)
                contact_force = (quotient_force(delta, delta_ref, ref_potential, c1, alpha, c0)[0]
                                 + b1 * damper_factor * (delta - delta_ref))
                y_new = (b_y - contact_force) / a_y
                u0_new = (b_0 + contact_force) / a_0
                if not (abs(y_new) < 1e300 and abs(u0_new) < 1e300):
                    extremes[X_FAILED_TIME] = t
                    return STATUS_NON_FINITE, n_hist, n_field
                y[new] = y_new
                u[new, 0] = u0_new
                if explicit:
                    # P_i = 0 but at a massless working end
                    u[new, n] = p[n] * u[new, n - 1] + u[new, n]
                else:
                    substitute_toward_working_end(u, new, p, coefficient_product, p_product, length,
                                                  head, u0_new, carry_0, carry_1, carry_2, carry_3)
                medium_force = (c2 * (spring_weight * u[new, n] + (1.0 - spring_weight) * u[ref, n])
                                + b2 * damper_factor * (u[new, n] - u[ref, n]))
                # Φ of the new layer from its own overlap, as the next steps' quotients take it
                delta = y_new - u0_new
                potential = contact_law(delta, c1, alpha, c0)[1]
                if lag:
                    rec, t_rec = cur, t - tau
                    velocity = (y_new - y[old]) / (2.0 * tau)
                else:
                    rec, t_rec = new, t
                    velocity = (striker_velocity if m == 1 else
                                (3.0 * y_new - 4.0 * y_cur + y[old]) / (2.0 * tau))

                # Energy at layer m − ½, in the form each scheme conserves (or dissipates).
                dy = y_new - y_cur
                striker_kinetic = 0.5 * striker_mass * dy * dy * inv_tau2
                tool_kinetic, tool_strain, low, low_block, high, high_block = tool_energy_and_stresses(
                    u, new, cur, rec, node_area, area_mid, strain_sigma, half_e_over_h)
                tool_kinetic *= kinetic_factor
                tool_strain *= 0.5 * e_over_h
                contact_pot = spring_weight * potential + (1.0 - spring_weight) * ends[S_POTENTIAL_BEFORE]
                medium_pot = 0.5 * c2 * (spring_weight * u[new, n] * u[new, n]
                                         + (1.0 - spring_weight) * u[cur, n] * u[cur, n])
                energy[0, E_EXTERNAL_WORK] += r_n * 0.5 * (y_new - y[old])
                rate = damper_factor * (delta - delta_ref)
                energy[0, E_DISSIPATED_CONTACT] += b1 * rate * rate * tau
                rate = damper_factor * (u[new, n] - u[ref, n])
                energy[0, E_DISSIPATED_MEDIUM] += b2 * rate * rate * tau
                energy[0, E_STRIKER_KINETIC] = striker_kinetic
                energy[0, E_TOOL_KINETIC] = tool_kinetic
                energy[0, E_TOOL_STRAIN] = tool_strain
                energy[0, E_CONTACT_POTENTIAL] = contact_pot
                energy[0, E_MEDIUM_POTENTIAL] = medium_pot
                balance = (striker_kinetic + tool_kinetic + tool_strain + contact_pot + medium_pot
                           + energy[0, E_DISSIPATED_CONTACT] + energy[0, E_DISSIPATED_MEDIUM]
                           - initial_energy - energy[0, E_EXTERNAL_WORK])
                ends[S_POTENTIAL_BEFORE_THAT] = ends[S_POTENTIAL_BEFORE]
                ends[S_POTENTIAL_BEFORE] = potential

                # Contact intervals: a crossing placed on the parabola through the last overlaps.
                if (delta >= 0.0) != (ends[S_IN_CONTACT] != 0.0):
                    t_cross = t - tau + tau * crossing(delta_old if m >= 2 else np.nan, delta_cur, delta)
                    track_contact(ends, extremes, contacts, t_cross, velocity, delta >= 0.0, tau)

            if not abs(balance) < 1e300:
                extremes[X_FAILED_TIME] = t
                return STATUS_NON_FINITE, n_hist, n_field
            if balance > extremes[X_ENERGY_EXCESS]:
                extremes[X_ENERGY_EXCESS] = balance
            s0 = -contact_force / end_area_0
            sn = -medium_force / end_area_n

        if m < lag:
            continue  # the centred schemes record layer 0 once its forces are known
        m_rec = m - lag

        # Stress extremes along the tool: the layer's extreme node values. Not refined between
        # nodes: next to a kink (a reflected front meeting the peak) a parabola through three
        # nodes overshoots by O(h), where the nodes' own error is O(h²).
        s_low, s_high = min(s0, low, sn), max(s0, high, sn)
        for peak, value, interior, block, slot in (
                (-s_low, s_low, low, low_block, X_MAX_COMPRESSION),
                (s_high, s_high, high, high_block, X_MAX_TENSION)):
            if peak > extremes[slot]:
                # Where, only for a new record (most layers set none): the first node of that
                # stress, from the struck end.
                if value == s0:
                    node = 0
                elif value == interior:
                    node = first_node(u, rec, half_e_over_h, block, value)
                else:
                    node = n
                extremes[slot] = peak
                extremes[slot + 1] = node * h
                extremes[slot + 2] = t_rec
        if contact_force > extremes[X_PEAK_FORCE]:
            extremes[X_PEAK_FORCE] = contact_force
            extremes[X_PEAK_FORCE_TIME] = t_rec
        # Extremes of the end forces between layers: the vertex of the parabola through the last
        # three, so that their error is the scheme's, not the sampling's.
        f1, f2, f3 = ends[S_FORCE_BEFORE], ends[S_FORCE_BEFORE_THAT], ends[S_FORCE_EARLIER]
        g1, g2, g3 = (ends[S_MEDIUM_FORCE], ends[S_MEDIUM_FORCE_BEFORE],
                      ends[S_MEDIUM_FORCE_EARLIER])
        if m_rec >= 3:
            top, offset = vertex(f3, f2, f1, contact_force)
            when = t_rec - tau + offset * tau
            if top > extremes[X_PEAK_FORCE]:
                extremes[X_PEAK_FORCE] = top
                extremes[X_PEAK_FORCE_TIME] = when
            track_end_extreme(extremes, X_MAX_COMPRESSION, top / end_area_0, 0.0, when)
            top, offset = vertex(-f3, -f2, -f1, -contact_force)
            track_end_extreme(extremes, X_MAX_TENSION, top / end_area_0, 0.0,
                              t_rec - tau + offset * tau)
            top, offset = vertex(g3, g2, g1, medium_force)
            track_end_extreme(extremes, X_MAX_COMPRESSION, top / end_area_n, n * h,
                              t_rec - tau + offset * tau)
            top, offset = vertex(-g3, -g2, -g1, -medium_force)
            track_end_extreme(extremes, X_MAX_TENSION, top / end_area_n, n * h,
                              t_rec - tau + offset * tau)
        ends[S_FORCE_EARLIER] = f2
        ends[S_FORCE_BEFORE_THAT] = f1
        ends[S_FORCE_BEFORE] = contact_force
        ends[S_MEDIUM_FORCE_EARLIER] = g2
        ends[S_MEDIUM_FORCE_BEFORE] = g1
        ends[S_MEDIUM_FORCE] = medium_force

        if history_stride > 0 and m_rec % history_stride == 0:
            history[H_TIME, n_hist] = t_rec
            history[H_STRIKER_DISP, n_hist] = y[rec]
            history[H_STRIKER_VEL, n_hist] = velocity
            history[H_STRUCK_END, n_hist] = u[rec, 0]
            history[H_WORKING_END, n_hist] = u[rec, n]
            history[H_CONTACT_FORCE, n_hist] = contact_force
            history[H_OVERLAP, n_hist] = y[rec] - u[rec, 0]
            history[H_MEDIUM_FORCE, n_hist] = medium_force
            history[H_EXTERNAL_FORCE, n_hist] = external_force(
                t_rec, force.kind, force.amplitude, force.omega, force.start, force.duration)
            history[H_EXTERNAL_WORK, n_hist] = energy[0, E_EXTERNAL_WORK]
            history[H_DISSIPATED_CONTACT, n_hist] = energy[0, E_DISSIPATED_CONTACT]
            history[H_DISSIPATED_MEDIUM, n_hist] = energy[0, E_DISSIPATED_MEDIUM]
            if m_rec == 0:
                history[H_STRIKER_KINETIC, n_hist] = initial_energy
                for c in range(H_TOOL_KINETIC, HISTORY_COLUMNS):
                    history[c, n_hist] = 0.0
            else:
                history[H_STRIKER_KINETIC, n_hist] = energy[0, E_STRIKER_KINETIC]
                history[H_TOOL_KINETIC, n_hist] = energy[0, E_TOOL_KINETIC]
                history[H_TOOL_STRAIN, n_hist] = energy[0, E_TOOL_STRAIN]
                history[H_CONTACT_POTENTIAL, n_hist] = energy[0, E_CONTACT_POTENTIAL]
                history[H_MEDIUM_POTENTIAL, n_hist] = energy[0, E_MEDIUM_POTENTIAL]
            for k in range(len(probe_node)):
                j = probe_node[k]
                w = probe_weight[k]
                s = (1.0 - w) * node_stress(u, rec, j, n, e_over_h, s0, sn)
                if w > 0.0:
                    s += w * node_stress(u, rec, j + 1, n, e_over_h, s0, sn)
                probes[n_hist, k] = s
            n_hist += 1
        if field_stride > 0 and m_rec % field_stride == 0:
            for i in range(n + 1):
                field_u[n_field, i] = u[rec, i]
                field_stress[n_field, i] = node_stress(u, rec, i, n, e_over_h, s0, sn)
            n_field += 1
    return STATUS_OK, n_hist, n_field
