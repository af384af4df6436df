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

# Tracker slots (running extremes and contact state)
T_PEAK_FORCE, T_PEAK_FORCE_TIME = 0, 1
T_MAX_COMPRESSION, T_MAX_COMPRESSION_X, T_MAX_COMPRESSION_TIME = 2, 3, 4
T_MAX_TENSION, T_MAX_TENSION_X, T_MAX_TENSION_TIME = 5, 6, 7
T_IN_CONTACT, T_CONTACT_START, T_CONTACTS = 8, 9, 10
T_CO_IMPACT, T_REBOUND_VELOCITY = 11, 12
T_ENERGY_EXCESS = 13  # max over time of (stored + dissipated − input): > 0 means energy created
T_FAILED_TIME = 14
T_MIN_CONTACT_STEPS = 15  # fewest steps any finished contact interval was resolved by
T_FORCE_BEFORE, T_FORCE_BEFORE_THAT = 16, 17  # contact force at layers m−1, m−2
T_POTENTIAL_BEFORE, T_POTENTIAL_BEFORE_THAT = 18, 19  # contact potential Φ at layers m−1, m−2
TRACKER_SLOTS = 20

# Energy slots: running work and dissipation, and the stored terms of the last layer
E_EXTERNAL_WORK, E_DISSIPATED_CONTACT, E_DISSIPATED_MEDIUM = 0, 1, 2
E_STRIKER_KINETIC, E_TOOL_KINETIC, E_TOOL_STRAIN, E_CONTACT_POTENTIAL, E_MEDIUM_POTENTIAL = (
    3, 4, 5, 6, 7)
ENERGY_SLOTS = 8

STATUS_OK, STATUS_NON_FINITE = 0, 1

# Independent chains a recurrence along the tool is split into: enough to hide the multiply-add's
# latency (4 cycles) behind the other chains' work. `sweep_toward_struck_end` and
# `substitute_toward_working_end` are written out for this many.
SEGMENTS = 4
MIN_SEGMENT = 8  # shorter segments are not worth their carries: the tool is swept serially


def new_trackers() -> np.ndarray:
    t = np.zeros(TRACKER_SLOTS)
    t[T_CO_IMPACT] = np.nan
    t[T_REBOUND_VELOCITY] = np.nan
    t[T_FAILED_TIME] = np.nan
    t[T_MIN_CONTACT_STEPS] = np.inf
    return t


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
def contact_spring_stiffness(delta, c1, alpha, c0):
    """Φ''(δ): `(α+1)·c1·δ^α` in contact, `c0` in separation."""
    if delta >= 0.0:
        if alpha == 0.0:
            return c1
        return (alpha + 1.0) * c1 * delta**alpha
    return c0


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
    return (contact_law(mid, c1, alpha, c0)[0],
            0.5 * contact_spring_stiffness(mid, c1, alpha, c0))


@njit(cache=True)
def solve_overlap(free, compliance, ref, ref_potential, guess, c1, alpha, c0, damper):
    """The new overlap δ of `δ + compliance·F(δ) = free`, `F(δ) = quotient(δ, ref) + damper·(δ − ref)`.

    F increases with δ (Φ is convex), so the root is unique and lies between `free` and
    `free − compliance·F(free)`; Newton steps that leave that bracket are replaced by bisection.
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
        if g > 0.0:
            hi = x
        else:
            lo = x
        step = g / (1.0 + compliance * (df + damper))
        x_new = x - step
        if not lo < x_new < hi:
            x_new = 0.5 * (lo + hi)
        if abs(x_new - x) <= scale or hi - lo <= scale:
            return x_new
        x = x_new
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
def tool_energy_and_stresses(u, new, cur, node_area, area_mid, strain_sigma, half_e_over_h):
    """The tool's energy terms and interior stress extremes of the layers in rows `new`, `cur` of
    `u`: `(Σ S_i·(u_i − uc_i)², Σ S_{i+½}·[σ(e_a² + e_b²) + (1 − 2σ)·e_a·e_b], least stress, its
    block, greatest stress, its block)`.

    The sums are twice the kinetic energy times τ²/(ρh) and twice the strain energy times h/E, e
    the cell strains. The stresses are `½·E/h·(u_{i+1} − u_{i−1})` at the interior nodes of the new
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
            s = half_e_over_h * (u[new, i + one] - u[new, i - one])
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
    weight_new, weight_old, centered, end_masses,
    striker_mass, striker_velocity,
    c1, alpha, c0, b1, c2, b2,
    force_kind, force_amplitude, force_omega, force_start, force_duration,
    trackers, energy, contacts,
    history, history_stride, probe_node, probe_weight, probes,
    field_u, field_stress, field_stride,
):
    """Compute layers `first … last` (inclusive; layer 0 is the initial state).

    The interior operator weights layers n+1, n, n−1 by `weight_new`, `1 − weight_new −
    weight_old`, `weight_old`. `centered` centres the boundary terms on layer n (springs
    `(z^{n+1} + z^{n−1})/2`, dampers `(z^{n+1} − z^{n−1})/(2τ)`, the contact quotient between
    δ^{n+1} and δ^{n−1}); otherwise they are the paper's (new layer, `(z^{n+1} − z^n)/τ`).
    `end_masses` gives the end rows the interior's weights (they then carry their half-cell mass
    `node_area·ρh`); massless ends are quasi-static, all on the new layer.

    Writes every `history_stride`-th layer to `history` (a column each) and `probes` (a row each)
    and every `field_stride`-th to `field_u`/`field_stress` (strides ≤ 0 keep nothing), from the
    first of each buffer. Returns `(status, layers of history written, rows of fields written)`;
    on a non-finite value it stops with `STATUS_NON_FINITE` and the time in
    `trackers[T_FAILED_TIME]`.
    """
    n = len(node_area) - 1
    weight_cur = 1.0 - weight_new - weight_old
    inv_tau2 = 1.0 / (tau * tau)
    m1_tau2 = striker_mass * inv_tau2
    mass_0 = density * h * node_area[0] * inv_tau2
    mass_n = density * h * node_area[n] * inv_tau2
    end_weight, spring_weight, damper_factor, back = boundary_weights(
        weight_new, centered, end_masses, tau)
    strain_sigma = weight_new if centered else 0.25  # 0.25: strain energy at the midpoint
    e_over_h = youngs_modulus / h
    half_e_over_h = 0.5 * e_over_h
    kinetic_factor = 0.5 * density * h * inv_tau2
    initial_energy = 0.5 * striker_mass * striker_velocity * striker_velocity
    length, head = segment_layout(n)
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
            contact_force = b1 * striker_velocity
            medium_force = 0.0
            velocity = striker_velocity
            s0 = -contact_force / end_area_0
            sn = 0.0
        else:
            ref = (m - back) % 3
            y_cur = y[cur]
            delta_cur = y_cur - u[cur, 0]
            delta_old = y[old] - u[old, 0]
            delta_ref = y[ref] - u[ref, 0]
            r_n = external_force((m - 1) * tau, force_kind, force_amplitude, force_omega,
                                 force_start, force_duration)  # R(t_n), explicit in row (11)

            # Right-hand sides of rows u_N … u_1 over their diagonals, eliminated toward the struck
            # end. The explicit layers enter the operator as one combination
            # v = w_n·u^n + w_{n−1}·u^{n−1}.
            v_right = weight_cur * u[cur, n] + weight_old * u[old, n]
            v_mid = weight_cur * u[cur, n - 1] + weight_old * u[old, n - 1]
            rhs = (mass_n * (2.0 * u[cur, n] - u[old, n]) - c2 * (1.0 - spring_weight) * u[ref, n]
                   + b2 * damper_factor * u[ref, n])
            if end_masses:
                rhs -= end_stiffness_n * (v_right - v_mid)
            u[new, n] = rhs * inv_den[n]  # Q_i is kept in row `new` until the substitution
            explicit = weight_new == 0.0 and weight_old == 0.0
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
            ref_potential = trackers[T_POTENTIAL_BEFORE if back == 1 else T_POTENTIAL_BEFORE_THAT]
            delta = solve_overlap(delta_free, compliance, delta_ref, ref_potential,
                                  2.0 * delta_cur - delta_old, c1, alpha, c0, b1 * damper_factor)
            force = (quotient_force(delta, delta_ref, ref_potential, c1, alpha, c0)[0]
                     + b1 * damper_factor * (delta - delta_ref))
            y_new = (b_y - force) / a_y
            u0_new = (b_0 + force) / a_0
            if not (abs(y_new) < 1e300 and abs(u0_new) < 1e300):
                trackers[T_FAILED_TIME] = t
                return STATUS_NON_FINITE, n_hist, n_field
            y[new] = y_new
            u[new, 0] = u0_new
            if explicit:
                # P_i = 0 but at a massless working end
                u[new, n] = p[n] * u[new, n - 1] + u[new, n]
            else:
                substitute_toward_working_end(u, new, p, coefficient_product, p_product, length,
                                              head, u0_new, carry_0, carry_1, carry_2, carry_3)
            # The forces at layer m: the contact law with second-order backward rates.
            delta = y_new - u0_new
            if m == 1:
                delta_rate = (delta - delta_cur) / tau
                end_rate = (u[new, n] - u[cur, n]) / tau
                velocity = striker_velocity
            else:
                delta_rate = (3.0 * delta - 4.0 * delta_cur + delta_old) / (2.0 * tau)
                end_rate = (3.0 * u[new, n] - 4.0 * u[cur, n] + u[old, n]) / (2.0 * tau)
                velocity = (3.0 * y_new - 4.0 * y_cur + y[old]) / (2.0 * tau)
            spring, potential = contact_law(delta, c1, alpha, c0)
            contact_force = spring + b1 * delta_rate
            medium_force = c2 * u[new, n] + b2 * end_rate
            s0 = -contact_force / end_area_0
            sn = -medium_force / end_area_n

            # Energy at layer m − ½, in the form each scheme conserves (or dissipates).
            dy = y_new - y_cur
            striker_kinetic = 0.5 * striker_mass * dy * dy * inv_tau2
            tool_kinetic, tool_strain, low, low_block, high, high_block = tool_energy_and_stresses(
                u, new, cur, node_area, area_mid, strain_sigma, half_e_over_h)
            tool_kinetic *= kinetic_factor
            tool_strain *= 0.5 * e_over_h
            contact_pot = spring_weight * potential + (1.0 - spring_weight) * trackers[T_POTENTIAL_BEFORE]
            medium_pot = 0.5 * c2 * (spring_weight * u[new, n] * u[new, n]
                                     + (1.0 - spring_weight) * u[cur, n] * u[cur, n])
            energy[E_EXTERNAL_WORK] += r_n * 0.5 * (y_new - y[old])
            rate = damper_factor * (delta - delta_ref)
            energy[E_DISSIPATED_CONTACT] += b1 * rate * rate * tau
            rate = damper_factor * (u[new, n] - u[ref, n])
            energy[E_DISSIPATED_MEDIUM] += b2 * rate * rate * tau
            energy[E_STRIKER_KINETIC] = striker_kinetic
            energy[E_TOOL_KINETIC] = tool_kinetic
            energy[E_TOOL_STRAIN] = tool_strain
            energy[E_CONTACT_POTENTIAL] = contact_pot
            energy[E_MEDIUM_POTENTIAL] = medium_pot
            balance = (striker_kinetic + tool_kinetic + tool_strain + contact_pot + medium_pot
                       + energy[E_DISSIPATED_CONTACT] + energy[E_DISSIPATED_MEDIUM]
                       - initial_energy - energy[E_EXTERNAL_WORK])
            if not abs(balance) < 1e300:
                trackers[T_FAILED_TIME] = t
                return STATUS_NON_FINITE, n_hist, n_field
            if balance > trackers[T_ENERGY_EXCESS]:
                trackers[T_ENERGY_EXCESS] = balance

            # Stress extremes along the tool: the layer's extreme node values. Not refined between
            # nodes: next to a kink (a reflected front meeting the peak) a parabola through three
            # nodes overshoots by O(h), where the nodes' own error is O(h²).
            s_low, s_high = min(s0, low, sn), max(s0, high, sn)
            for peak, value, interior, block, slot in (
                    (-s_low, s_low, low, low_block, T_MAX_COMPRESSION),
                    (s_high, s_high, high, high_block, T_MAX_TENSION)):
                if peak > trackers[slot]:
                    # Where, only for a new record (most layers set none): the first node of that
                    # stress, from the struck end.
                    if value == s0:
                        node = 0
                    elif value == interior:
                        node = first_node(u, new, half_e_over_h, block, value)
                    else:
                        node = n
                    trackers[slot] = peak
                    trackers[slot + 1] = node * h
                    trackers[slot + 2] = t
            if contact_force > trackers[T_PEAK_FORCE]:
                trackers[T_PEAK_FORCE] = contact_force
                trackers[T_PEAK_FORCE_TIME] = t
            # A maximum between layers: the vertex of the parabola through the last three forces,
            # so the peak's error is the scheme's, not the sampling's.
            f1 = trackers[T_FORCE_BEFORE]
            f2 = trackers[T_FORCE_BEFORE_THAT]
            if m >= 3 and f1 >= f2 and f1 > contact_force:
                curvature = 2.0 * f1 - f2 - contact_force
                offset = 0.5 * (contact_force - f2) / curvature
                vertex = f1 + 0.25 * (contact_force - f2) * offset
                if vertex > trackers[T_PEAK_FORCE]:
                    trackers[T_PEAK_FORCE] = vertex
                    trackers[T_PEAK_FORCE_TIME] = t - tau + offset * tau
            trackers[T_FORCE_BEFORE_THAT] = f1
            trackers[T_FORCE_BEFORE] = contact_force
            trackers[T_POTENTIAL_BEFORE_THAT] = trackers[T_POTENTIAL_BEFORE]
            trackers[T_POTENTIAL_BEFORE] = potential

            # Contact intervals: δ ≥ 0 is contact; crossings are placed by linear interpolation.
            in_contact = trackers[T_IN_CONTACT] != 0.0
            if in_contact and delta < 0.0:
                t_cross = t - tau + tau * crossing(delta_old if m >= 2 else np.nan, delta_cur, delta)
                k = int(trackers[T_CONTACTS])
                if k < contacts.shape[0]:
                    contacts[k, 0] = trackers[T_CONTACT_START]
                    contacts[k, 1] = t_cross
                trackers[T_CONTACTS] = k + 1
                steps = (t_cross - trackers[T_CONTACT_START]) / tau
                if steps < trackers[T_MIN_CONTACT_STEPS]:
                    trackers[T_MIN_CONTACT_STEPS] = steps
                if k == 0:
                    trackers[T_CO_IMPACT] = t_cross
                    trackers[T_REBOUND_VELOCITY] = velocity
                trackers[T_IN_CONTACT] = 0.0
            elif not in_contact and delta >= 0.0:
                trackers[T_IN_CONTACT] = 1.0
                trackers[T_CONTACT_START] = t - tau + tau * crossing(
                    delta_old if m >= 2 else np.nan, delta_cur, delta)

        if m == 0:
            trackers[T_IN_CONTACT] = 1.0  # δ(0) = 0: contact from the first instant
            trackers[T_CONTACT_START] = 0.0
            # Φ(δ⁰) = Φ(0) = 0; the state before impact counts 0 too: no link acts yet.
            trackers[T_POTENTIAL_BEFORE] = 0.0
            trackers[T_POTENTIAL_BEFORE_THAT] = 0.0

        if history_stride > 0 and m % history_stride == 0:
            history[H_TIME, n_hist] = t
            history[H_STRIKER_DISP, n_hist] = y[new]
            history[H_STRIKER_VEL, n_hist] = velocity
            history[H_STRUCK_END, n_hist] = u[new, 0]
            history[H_WORKING_END, n_hist] = u[new, n]
            history[H_CONTACT_FORCE, n_hist] = contact_force
            history[H_OVERLAP, n_hist] = y[new] - u[new, 0]
            history[H_MEDIUM_FORCE, n_hist] = medium_force
            history[H_EXTERNAL_FORCE, n_hist] = external_force(
                t, force_kind, force_amplitude, force_omega, force_start, force_duration)
            history[H_EXTERNAL_WORK, n_hist] = energy[E_EXTERNAL_WORK]
            history[H_DISSIPATED_CONTACT, n_hist] = energy[E_DISSIPATED_CONTACT]
            history[H_DISSIPATED_MEDIUM, n_hist] = energy[E_DISSIPATED_MEDIUM]
            if m == 0:
                history[H_STRIKER_KINETIC, n_hist] = initial_energy
                for c in range(H_TOOL_KINETIC, HISTORY_COLUMNS):
                    history[c, n_hist] = 0.0
            else:
                history[H_STRIKER_KINETIC, n_hist] = energy[E_STRIKER_KINETIC]
                history[H_TOOL_KINETIC, n_hist] = energy[E_TOOL_KINETIC]
                history[H_TOOL_STRAIN, n_hist] = energy[E_TOOL_STRAIN]
                history[H_CONTACT_POTENTIAL, n_hist] = energy[E_CONTACT_POTENTIAL]
                history[H_MEDIUM_POTENTIAL, n_hist] = energy[E_MEDIUM_POTENTIAL]
            for k in range(len(probe_node)):
                j = probe_node[k]
                w = probe_weight[k]
                s = (1.0 - w) * node_stress(u, new, j, n, e_over_h, s0, sn)
                if w > 0.0:
                    s += w * node_stress(u, new, j + 1, n, e_over_h, s0, sn)
                probes[n_hist, k] = s
            n_hist += 1
        if field_stride > 0 and m % field_stride == 0:
            for i in range(n + 1):
                field_u[n_field, i] = u[new, i]
                field_stress[n_field, i] = node_stress(u, new, i, n, e_over_h, s0, sn)
            n_field += 1
    return STATUS_OK, n_hist, n_field
