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

`advance` takes named bundles: the `Tool` on its grid and its `ToolRows` factored once, the
`Rod`'s constants, the scheme's `Weights`, the `Contact` at the struck end, the `Medium` at the
working end and the `ForceLaw` on the striker; the `State` it carries from step to step and call to
call (the layers, the ends' slots `S_…`, the energy terms), what it has `Observed` (the extremes
`X_…` and the contact intervals, which the summary reads) and the `Recorders` of a call. A step is
a sequence of named phases, each a function inlined into `advance`: the right-hand sides, the
sweep, the struck end's solve, the back-substitution, the working end's force, the energy audit,
the extremes and the contacts, the recording.

The ends are where the tool meets what strikes it and what it strikes. Their laws enter a step's
solve only through these functions, one end at a time, so that another medium or striker replaces
them and leaves the tool's rows alone:
- the working end (the medium, c2, b2): `working_end_diagonal`, its share of row u_N's diagonal,
  factored once with the tool's rows; `working_end_row`, the row's right-hand side;
  `working_end_force`, its force on the new layer;
- the struck end (the striker m1 and the contact c1, α, c0, b1): `solve_struck_end`, the striker
  row (11) and the struck-end row (9) solved with the contact law; they see the tool only through
  its link `u_1 = P_1·u_0 + Q_1`, which the sweep gives;
- ends that integrate their own equations: `struck_end_step` and `working_end_step`. They see
  the tool only through the waves arriving at its ends, so they take what the paper's rows do not:
  media that yield (`yielding_end_step`), an elastic striker on its own grid (`free_back_end` for
  its back end), and an anvil between the striker and the tool: each implicit stage of the struck
  end is then two contacts' balance (`stage_forces`, `anvil_balance`), the bodies' motion around
  them linear (`body_rates`).
A medium linear in u_N (any c2, b2) is its three functions. The ends' energy terms (the contacts'
Φ, the medium's stored and plastic work, the anvil's kinetic energy, what the dampers dissipate)
are the energy audit's: a new law brings its own.

All arrays are float64. Layers n−1, n, n+1 of the tool live in rows `(n−1)%3, n%3, (n+1)%3` of
`u` (3 × (N+1)) and of the striker's `y` (3), so the layers carry no state between chunks but the
layer index. Layer −1 (row 2) is the state one step before the impact, `z − τ·z'`, so the first
step is an ordinary step of the scheme. The layers are indexed as `u[row, i]`, never through a row
view: Numba counts a view's references with atomic instructions, and three views a step cost about
0.4 ns a node-step on 100 cells, a sixth of the step (for the same reason the phases take the
bundles `uncounted`). Where LLVM cannot prove an index non-negative, it is unsigned: Numba wraps
negative indices around, and that check on every load keeps loops from vectorising.
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np
from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic

from .compiled import compiled
from .layout import (
    E_ANVIL_KINETIC,
    E_CONTACT_POTENTIAL,
    E_DISSIPATED_CONTACT,
    E_DISSIPATED_MEDIUM,
    E_EXTERNAL_WORK,
    E_LAUNCHED,
    E_MEDIUM_PLASTIC,
    E_MEDIUM_POTENTIAL,
    E_STRIKER_KINETIC,
    E_STRIKER_STRAIN,
    E_TOOL_KINETIC,
    E_TOOL_STRAIN,
    E_WITHDRAWN,
    ENERGY_SLOTS,
    H_ANVIL_DISP,
    H_ANVIL_FORCE,
    H_ANVIL_KINETIC,
    H_ANVIL_VEL,
    H_CONTACT_FORCE,
    H_CONTACT_POTENTIAL,
    H_DISSIPATED_CONTACT,
    H_DISSIPATED_MEDIUM,
    H_EXTERNAL_FORCE,
    H_EXTERNAL_WORK,
    H_LAUNCHED,
    H_MEDIUM_FORCE,
    H_MEDIUM_PLASTIC,
    H_MEDIUM_POTENTIAL,
    H_OVERLAP,
    H_PERMANENT_PENETRATION,
    H_STRIKER_DISP,
    H_STRIKER_KINETIC,
    H_STRIKER_STRAIN,
    H_STRIKER_VEL,
    H_STRUCK_END,
    H_TIME,
    H_TOOL_KINETIC,
    H_TOOL_STRAIN,
    H_WITHDRAWN,
    H_WORKING_END,
    X_CO_IMPACT,
    X_CONTACTS,
    X_ENERGY_EXCESS,
    X_FAILED_TIME,
    X_MAX_COMPRESSION,
    X_MAX_PENETRATION,
    X_MAX_TENSION,
    X_MIN_CONTACT_STEPS,
    X_PEAK_FORCE,
    X_PEAK_FORCE_TIME,
    X_REBOUND_VELOCITY,
    new_extremes,
)

# Force kinds (`force_kind`)
FORCE_NONE, FORCE_SINE, FORCE_ABS_SINE, FORCE_PULSE = 0, 1, 2, 3
# Medium kinds (`Medium.kind`)
MEDIUM_LINEAR, MEDIUM_BILINEAR, MEDIUM_SMITH = 0, 1, 2

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
# A medium that yields: its permanent penetration (the set) and, for rock, the deepest penetration
# of the present loading, the surface it started from and the plastic work of the loadings before
S_MEDIUM = 15  # 15 … 18: set, deepest, surface, spent (`MEDIUM_STATE` slots)
MEDIUM_STATE = 4
S_MEDIUM_SET = S_MEDIUM
# An elastic striker: the incoming waves' displacements G at its face and at its back end (layers
# m−1, m−2), the back end's incoming rate over the last two steps (mean and slope of each: the
# free end returns it after the `back_delay`), and the contact's impulse so far
S_FACE_INCOMING, S_FACE_INCOMING_BEFORE, S_BACK_INCOMING, S_BACK_INCOMING_BEFORE = 19, 20, 21, 22
S_BACK_RATE = 23  # 23, 24: mean, slope of step m−1; 25, 26: of step m−2
S_IMPULSE = 27
S_BACK_ENERGY = 28  # the energy of the waves beyond the striker's last node, at layer m − ½
# An anvil: its displacement and velocity, and its force on the tool's end, at layer m − 1
S_ANVIL_DISP, S_ANVIL_VELOCITY, S_ANVIL_FORCE = 29, 30, 31
END_SLOTS = 32

STATUS_OK, STATUS_NON_FINITE = 0, 1

# What `advance` takes, as named bundles. Numba passes a namedtuple's fields as separate values and
# reads them as registers: a bundle costs nothing in the step (typing them all costs about 3 µs a
# call of `advance`, against ~10 ms of steps a call). Build them by keyword, as `solver.controller`
# does: a bundle of another kind in the place of one does not compile.
Tool = namedtuple("Tool", "lower upper node_area area_mid uniform struck_end_area working_end_area")
"""The tool on its grid (`solver.grid.Grid`): the operator's weights `lower_i`, `upper_i` of the
neighbours (all 1 when `uniform`), the nodes' areas S̄_i (`node_area·ρh` is a node's mass: half a
cell at the ends, 0 at a massless end), the cells' areas S_{i+½} and the areas at the struck and
working ends (their stresses are the end forces over them)."""
ToolRows = namedtuple("ToolRows", "p inv_den coefficient coefficient_product p_product")
"""The tool's rows u_1 … u_N eliminated once (`factor_tool_rows`)."""
Rod = namedtuple(
    "Rod", "cell_length time_step courant_squared youngs_modulus density struck_end_stiffness working_end_stiffness"
)
"""The rod's constants: h, τ, r = (a·τ/h)², E, ρ and the end cells' stiffness k_0, k_N = S·E/h."""
Weights = namedtuple("Weights", "new old centered end_masses impedance_ends")
"""The scheme (`solver.schemes.Scheme`): the weights of layers n+1 and n−1 in the tool's operator
(γ and 0 for the paper's, σ and σ for the σ-scheme, 0 and 0 explicit; layer n has the rest),
whether the boundary terms are centred on layer n, whether the ends carry their half-cell masses,
and whether each end integrates its own equations (the explicit scheme at Courant number 1)."""
Contact = namedtuple("Contact", "striker_mass striker_velocity stiffness exponent tension_stiffness damping impedance")
"""The struck end: the striker (m1, W1 at impact), the contact's spring `Φ'(δ) = c1·δ^(α+1)` in
contact and `c0·δ` in separation (c1, α, c0), its damper (b1), and the impedance ρ·a·S of the
tool's end cell (N·s/m)."""
Medium = namedtuple("Medium", "kind stiffness damping impedance unloading_stiffness ultimate_resistance damping_factor")
"""The working end: the medium's `MEDIUM_…` kind, its loading stiffness (c2, rock's k, or soil's
R_u/q; 0 for a free end) and damper (b2), the impedance of the tool's end cell, rock's unloading
stiffness k_u, soil's ultimate resistance R_u and Smith damping J (s/m)."""
ForceLaw = namedtuple("ForceLaw", "kind amplitude omega start duration")
"""R(t) on the striker: a `FORCE_…` kind and its parameters."""
Striker = namedtuple("Striker", "elastic tool rod impedance back_impedance mass back_delay")
"""The striker as a rod (when `elastic`): its `Tool` and `Rod` on its own grid (node 0 its impact
face, at Courant number 1 with the tool's time step), the impedances ρ·a·S of its face and back
cells, its mass, and `back_delay`: the time a wave takes there and back over the part of the striker beyond
its last node, less than 2τ (its length is rarely a whole number of cells)."""
Anvil = namedtuple("Anvil", "present mass velocity contact")
"""A lumped body between the striker and the tool (when `present`): its mass m_a, its velocity at
impact and its `Contact` with the tool (the anvil as that contact's striker, the tool's end
impedance); the case's `Contact` is then the striker's with the anvil."""
State = namedtuple("State", "u y ends energy striker")
"""What a step carries to the next: the tool's layers `u` (3 × (N+1)) and the striker's face `y`
(3), the ends' slots (`S_…`), the energy terms (`energy[0, E_…]` at the last layer, `energy[1]` at
the one before) and an elastic striker's layers (3 × (N_s+1); its node 0 is `y`)."""
Observed = namedtuple("Observed", "extremes contacts")
"""What a run reports beyond its recordings: the extremes (`X_…`) and the finished contact
intervals (start, end; one row each, those beyond its rows counted only)."""
Recorders = namedtuple(
    "Recorders",
    "history history_stride probe_node probe_weight probes field_u field_stress field_stride striker_u striker_stress",
)
"""Where a call records its layers: every `history_stride`-th to `history` (a column each) and
`probes` (a row each: the stress at each probe, linear between the node `probe_node` and the next
with its weight `probe_weight`), every `field_stride`-th to `field_u`/`field_stress` (a row each)
and an elastic striker's to `striker_u`/`striker_stress`; strides ≤ 0 keep nothing."""

# Within a step
Layers = namedtuple("Layers", "new cur old ref")
"""The rows of `u` and `y` holding layers n+1, n, n−1, and the boundary terms' reference layer."""
Overlaps = namedtuple("Overlaps", "cur old ref")
"""The overlap δ = y − u_0 of layers n and n−1 and of the reference layer."""
Boundary = namedtuple("Boundary", "end_weight spring_weight damper_factor back")
"""How the end rows and the boundary terms weight the layers (`boundary_weights`)."""
StepConstants = namedtuple(
    "StepConstants",
    "n weight_cur inv_tau2 m1_tau2 mass_0 mass_n boundary "
    "lag strain_sigma e_over_h half_e_over_h "
    "kinetic_factor initial_energy anvil_energy segments "
    "explicit",
)
"""What every step derives from the bundles (`step_constants`): `initial_energy` the striker's at
impact, `anvil_energy` the anvil's; `segments` is `segment_layout`'s."""
Recorded = namedtuple("Recorded", "row time velocity contact_force medium_force struck_end_stress working_end_stress")
"""A layer as it is recorded: its row of `u`, its time, the striker's velocity, the end forces the
scheme applies there and the stresses they make at the ends (tension +)."""

# Independent chains a recurrence along the tool is split into: enough to hide the multiply-add's
# latency (4 cycles) behind the other chains' work. `sweep_toward_struck_end` and
# `substitute_toward_working_end` are written out for this many.
SEGMENTS = 4
MIN_SEGMENT = 8  # shorter segments are not worth their carries: the tool is swept serially


def new_state(cells: int, striker_cells: int = 0) -> State:
    """The state before a run on `cells` cells, with an elastic striker on `striker_cells`
    (`advance` sets layer 0 and the one before)."""
    return State(
        u=np.zeros((3, cells + 1)),
        y=np.zeros(3),
        ends=np.zeros(END_SLOTS),
        energy=np.zeros((2, ENERGY_SLOTS)),
        striker=np.zeros((3, striker_cells + 1)),
    )


def new_observed(max_contacts: int) -> Observed:
    """Nothing observed yet, with room for `max_contacts` contact intervals."""
    return Observed(extremes=new_extremes(), contacts=np.zeros((max_contacts, 2)))


@compiled()
def boundary_weights(weights, tau):
    """How the end rows and the boundary terms of the scheme (`Weights`) weight the layers.

    Returns `Boundary(end_weight, spring_weight, damper_factor, back)`: the end rows' weight of the
    new layer in the tool's own stiffness (the interior's with end masses; 1 for quasi-static
    massless ends); the boundary springs' weight of the new layer (the rest on the reference
    layer); the dampers' rate factor (`1/(2τ)` centred, `1/τ` backward); how many layers before
    the new one the boundary terms' reference layer lies (2: n−1 centred; 1: n for the paper).
    """
    end_weight = weights.new if weights.end_masses else 1.0
    if weights.centered:
        return Boundary(end_weight=end_weight, spring_weight=0.5, damper_factor=0.5 / tau, back=2)
    return Boundary(end_weight=end_weight, spring_weight=1.0, damper_factor=1.0 / tau, back=1)


@compiled()
def segment_layout(n):
    """`(length, head)`: nodes `1 … head` are swept serially, nodes `head+1 … n` as `SEGMENTS`
    segments of `length` nodes (none when the tool is too short for them)."""
    length = n // SEGMENTS if n >= SEGMENTS * MIN_SEGMENT else 0
    return length, n - SEGMENTS * length


@compiled()
def factor_tool_rows(tool, rod, weights, medium):
    """Eliminate rows u_N … u_1 once (`ToolRows`): `P`, `1/den`, the coefficient `c` of `Q_{i+1}`
    in `Q_i = rhs_i/den_i + c_i·Q_{i+1}`, and the segments' multiples of their carries: for node i
    of a segment `b … e` (`segment_layout`), `Π c_j` over `i … e` and `Π P_j` over `b … i`.

    Row u_N: `working_end_diagonal·u_N − θ·k_N·u_{N−1} = rhs`, θ the end rows' weight of
    `boundary_weights`.
    Rows u_i: `−w·r·lower_i·u_{i−1} + (1 + w·r·(lower_i + upper_i))·u_i − w·r·upper_i·u_{i+1} = rhs_i`.
    """
    end_weight = boundary_weights(weights, rod.time_step).end_weight
    weight_new, r = weights.new, rod.courant_squared
    grid_lower, grid_upper = tool.lower, tool.upper
    n = len(tool.node_area) - 1
    p = np.zeros(n + 1)
    inv_den = np.zeros(n + 1)
    carry = weight_new * r * grid_upper
    diag_n = working_end_diagonal(tool, rod, weights, medium)
    p[n] = end_weight * rod.working_end_stiffness / diag_n
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
    return ToolRows(
        p=p, inv_den=inv_den, coefficient=coefficient, coefficient_product=coefficient_product, p_product=p_product
    )


@compiled(inline="always")
def segment_starts(length, head):
    """The segments' length and first nodes, unsigned (`segment_layout`)."""
    size = np.uint64(length)
    b0 = np.uint64(head + 1)
    return size, b0, b0 + size, b0 + np.uint64(2) * size, b0 + np.uint64(3) * size


@compiled(inline="always")
def sweep_toward_struck_end(u, row, rows, length, head):
    """`Q_i = a_i + c_i·Q_{i+1}` for i = n … 1, row `row` of `u` holding `a_i` on entry, with the
    factors `rows` (`ToolRows`) and the segments of `segment_layout`.

    Returns `Q_1` and the true Q carried into each segment (`Q_{e+1}`, e its last node). On return
    the row holds the segments' chains, started from 0 (true: chain + `Π c`·carry), and the head's
    true values.
    """
    coefficient, coefficient_product = rows.coefficient, rows.coefficient_product
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
    return first, (carry_0, carry_1, carry_2, carry_3)


@compiled(inline="always")
def substitute_toward_working_end(u, row, rows, length, head, x_0, carries):
    """`u_i = P_i·u_{i−1} + Q_i` for i = 1 … n from `u_0 = x_0`, row `row` of `u` holding what
    `sweep_toward_struck_end` left, with its carries: the true Q are made on the way."""
    p, coefficient_product, p_product = rows.p, rows.coefficient_product, rows.p_product
    carry_0, carry_1, carry_2, carry_3 = carries
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


@compiled(inline="always")
def external_force(t, force):
    """`R(t)` of the `ForceLaw`: P·sin(ωt), P·|sin(ωt)|, or P on [t1, t1 + Δt]."""
    kind, amplitude, omega, start, duration = force
    if kind == FORCE_SINE:
        return amplitude * np.sin(omega * t)
    if kind == FORCE_ABS_SINE:
        return amplitude * abs(np.sin(omega * t))
    if kind == FORCE_PULSE:
        if start <= t <= start + duration:
            return amplitude
    return 0.0


@compiled(inline="always")
def contact_law(delta, contact):
    """`(Φ'(δ), Φ(δ))`: the spring force G(δ)·δ of (7), `c1·δ^(α+1)` in contact and `c0·δ` in
    separation, and the energy Φ the contact stores, `c1·δ^(α+2)/(α+2)` or `c0·δ²/2`; one power
    for both, as on a small grid the contact solve is a large part of a step."""
    c1, alpha, c0 = contact.stiffness, contact.exponent, contact.tension_stiffness
    if delta >= 0.0:
        force = c1 * delta ** (alpha + 1.0)
        return force, force * delta / (alpha + 2.0)
    return c0 * delta, 0.5 * c0 * delta * delta


@compiled(inline="always")
def contact_spring(delta, contact):
    """`(Φ'(δ), Φ''(δ))`: the contact's spring force G(δ)·δ and its stiffness; the common
    exponents without a power."""
    c1, alpha, c0 = contact.stiffness, contact.exponent, contact.tension_stiffness
    if delta >= 0.0:
        if alpha == 0.0:
            return c1 * delta, c1
        if alpha == 0.5:
            root = math.sqrt(delta)
            return c1 * delta * root, 1.5 * c1 * root
        power = delta**alpha
        return c1 * delta * power, (alpha + 1.0) * c1 * power
    return c0 * delta, c0


@compiled(inline="always")
def quotient_force(delta, ref, ref_potential, contact):
    """`(Φ(δ) − Φ_ref)/(δ − ref)` and its derivative in δ (the midpoint values when δ ≈ ref).

    `Φ_ref` is Φ(ref) but for the state before impact, where no link acts yet and it is 0.
    """
    diff = delta - ref
    if abs(diff) > 1e-7 * (abs(delta) + abs(ref)):
        spring, potential = contact_law(delta, contact)
        inverse = 1.0 / diff
        f = (potential - ref_potential) * inverse
        return f, (spring - f) * inverse
    mid = 0.5 * (delta + ref)
    spring, stiffness = contact_spring(mid, contact)
    return spring, 0.5 * stiffness


@compiled(inline="always")
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


@compiled()
def solve_overlap(free, compliance, ref, ref_potential, guess, contact, damper):
    """The new overlap δ of `δ + compliance·F(δ) = free`, `F(δ) = quotient(δ, ref) + damper·(δ − ref)`.

    F increases with δ (Φ is convex), so the root is unique and lies between `free` and
    `free − compliance·F(free)`, where `bracketed_newton_step` finds it.
    """
    f_free = quotient_force(free, ref, ref_potential, contact)[0] + damper * (free - ref)
    other = free - compliance * f_free
    lo, hi = min(free, other), max(free, other)
    if lo == hi:
        return free
    x = min(max(guess, lo), hi)
    scale = 1e-15 * (abs(lo) + abs(hi))
    for _ in range(100):
        f, df = quotient_force(x, ref, ref_potential, contact)
        g = x + compliance * (f + damper * (x - ref)) - free
        if g == 0.0:
            return x
        x, lo, hi, done = bracketed_newton_step(x, g, 1.0 + compliance * (df + damper), lo, hi, scale)
        if done:
            return x
    return x


@compiled(inline="always")
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


@compiled(inline="always")
def node_stress(u, recorded, i, step):
    """`σ_i = E·∂u/∂x` (tension +) at node i of the `Recorded` layer: central inside; at the ends
    the end force over the area."""
    if i == 0:
        return recorded.struck_end_stress
    if i == step.n:
        return recorded.working_end_stress
    return 0.5 * step.e_over_h * (u[recorded.row, i + 1] - u[recorded.row, i - 1])


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
# An overlap within this fraction of the ends' displacements is rounding: it changes no contact
GRAZING = 1e-12
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
    """δ with `δ + compliance·Φ'(δ) = target`: Φ' increases, so the root is unique and lies between
    `target` and `target − compliance·Φ'(target)`, where `bracketed_newton_step` finds it (on one
    linear branch, directly)."""
    c1, alpha, c0 = contact.stiffness, contact.exponent, contact.tension_stiffness
    other = target - compliance * contact_spring(target, contact)[0]
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
        spring, stiffness = contact_spring(x, contact)
        g = x + compliance * spring - target
        if g == 0.0:
            return x
        x, lo, hi, done = bracketed_newton_step(x, g, 1.0 + compliance * stiffness, lo, hi, scale)
        if done:
            return x
    return x


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
    `m1·w' = R − F1`, or an elastic striker's face `y' = 2·v_face − F1/Z_s`; the anvil's
    `m_a·w_a' = F1 − F2`; `u_0' = F2/Z + 2·v_in`."""
    _, w, _, w_a, _ = x
    if striker.elastic:
        w_rate = 0.0
        y_rate = 2.0 * v_face - force / striker.impedance
    else:
        w_rate = (r - force) / contact.striker_mass
        y_rate = w + g * w_rate
    ya_rate = wa_rate = 0.0
    impedance = contact.impedance
    if anvil.present:
        wa_rate = (force - end_force) / anvil.mass
        ya_rate = w_a + g * wa_rate
        impedance = anvil.contact.impedance
    return y_rate, w_rate, ya_rate, wa_rate, end_force / impedance + 2.0 * v_in


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
    give = compliance * contact.damping / g
    delta = solve_spring_balance((free + give * base) / (1.0 + give), compliance / (1.0 + give), guess, contact)
    return contact_spring(delta, contact)[0] + contact.damping * (delta - base) / g, delta


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
    d1, d2 = contact.damping / g, end.damping / g
    k11 = (b + t) / det_c + d1
    k12 = b / det_c
    k22 = (a + b) / det_c + d2
    r1 = ((b + t) * free[0] + b * free[1]) / det_c + d1 * base[0]
    r2 = (b * free[0] + (a + b) * free[1]) / det_c + d2 * base[1]
    least_slope = ((1.0 + d1 * (a + b) + d2 * (b + t)) / det_c + d1 * d2) / k11
    delta1, delta2 = guess
    lo = hi = scale = 0.0
    for k in range(100):
        delta1 = solve_spring_balance((r1 - k12 * delta2) / k11, 1.0 / k11, delta1, contact)
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
            delta1 = solve_spring_balance((r1 - k12 * delta2) / k11, 1.0 / k11, delta1, contact)
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
    if striker.elastic:
        y_free, give = x[0] + 2.0 * g * v_face, g / striker.impedance
    else:
        m1 = contact.striker_mass
        y_free, give = x[0] + g * (x[1] + g * r / m1), g * g / m1
    u_free = x[4] + 2.0 * g * v_in
    if not anvil.present:
        force, delta = spring_stage(y_free - u_free, x[0] - x[4], give + g / contact.impedance, g, guess[0], contact)
        return force, force, delta, 0.0
    ya_free = x[2] + g * x[3]
    return anvil_balance(
        (y_free - ya_free, ya_free - u_free),
        (x[0] - x[2], x[2] - x[4]),
        (give, g * g / anvil.mass, g / anvil.contact.impedance),
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


@compiled(inline="always")
def limited_slope(before, now, after, tau):
    """The slope within a step of a rate whose means over it and its neighbours are given: the
    smaller of the two one-sided slopes, 0 where they disagree in sign (minmod)."""
    left, right = now - before, after - now
    if left * right <= 0.0:
        return 0.0
    return (left if abs(left) < abs(right) else right) / tau


@compiled(inline="always")
def struck_substeps(x, end_force, span, v_in, contact, striker, anvil, tau):
    """Substeps over a stretch of `span` for the struck end's links: each contact relaxing against
    what gives way to it, at its stiffness at the overlap the stretch may reach, and an anvil's
    oscillation between its two contacts (capped at `ANVIL_SUBSTEPS`: an anvil too light to
    follow is relaxed to its quasi-static state, as a stiff link is)."""
    y, w, y_a, w_a, u0 = x
    b1 = contact.damping
    end = anvil.contact if anvil.present else contact
    z = end.impedance
    end_rate = end_force / z + 2.0 * v_in
    if not anvil.present:
        reach = abs(y - u0) + span * abs(w - end_rate)
        stiffness = max(contact_spring(reach, contact)[1], contact.tension_stiffness)
        if striker.elastic:
            z_both = 1.0 / (1.0 / z + 1.0 / striker.impedance)
            return substeps(stiffness / (z_both + b1), span, SDIRK_MONOTONE)
        limit = min(SDIRK_MONOTONE, STIFF_RISE_STEPS * (z + b1) / contact.striker_mass * tau)
        return substeps(stiffness / (z + b1), span, limit)
    k1 = max(contact_spring(abs(y - y_a) + span * abs(w - w_a), contact)[1], contact.tension_stiffness)
    k2 = max(contact_spring(abs(y_a - u0) + span * abs(w_a - end_rate), end)[1], end.tension_stiffness)
    b2 = end.damping
    count = substeps(k2 / (z + b2), span, min(SDIRK_MONOTONE, STIFF_RISE_STEPS * (z + b2) / anvil.mass * tau))
    omega2 = (k1 + k2) / anvil.mass
    if striker.elastic:
        count = max(count, substeps(k1 / (striker.impedance + b1), span, SDIRK_MONOTONE))
    else:
        omega2 += k1 / contact.striker_mass
    return max(count, min(ANVIL_SUBSTEPS, substeps(math.sqrt(omega2), span, ANVIL_PHASE)))


@compiled()
def struck_end_step(t0, tau, state, waves, contact, striker, anvil, force, events):
    """Advance the striker, the anvil and the struck end over [t0, t0 + τ] under the incoming
    waves' rates `waves` = (mean, slope) at the struck end and at an elastic striker's face, each
    `v(t) = mean + slope·(t − t0 − τ/2)`; split where R jumps or kinks.

    `state` = (y, w, u_0, F1, I, in contact, y_a, w_a, F2) at t0 on entry, at t0 + τ on return:
    w the striker's velocity (its face's when elastic), F1 the contact's force, I its impulse,
    y_a, w_a the anvil's displacement and velocity, F2 the force on the tool's end (F1 without an
    anvil). Returns the work of R and what the contacts' dampers dissipated over the step, the
    number of changes of sign of δ1 (the contact's overlap), each written to `events` (time,
    striker velocity, +1 into contact or −1 out of it; at most `events.shape[0]`; an elastic
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
    x = (state[0], state[1], state[6], state[7], state[2])
    impulse = state[4]
    in_contact = state[5] != 0.0
    v_start = v_mean - 0.5 * tau * v_slope
    face_start = face_mean - 0.5 * tau * face_slope
    # under the waves arriving now: the forces can jump at t0
    f, f_end = struck_forces(x, v_start, face_start, contact, striker, anvil)
    if striker.elastic:
        x = (x[0], 2.0 * face_start - f / striker.impedance, x[2], x[3], x[4])
    f_max, t_max = f, t0
    e_max, te_max, e_min, te_min = f_end, t0, f_end, t0
    overlaps = (x[0] - (x[2] if anvil.present else x[4]), x[2] - x[4])
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
        f1, e1, d1, a1 = stage_forces(x, g, r1, v1, face1, overlaps, contact, striker, anvil)
        k1 = body_rates(x, g, f1, e1, r1, v1, face1, contact, striker, anvil)
        base = moved(x, (1.0 - gamma) * span, k1, striker)
        f2, e2, d2, a2 = stage_forces(base, g, r2, v2, face2, (d1, a1), contact, striker, anvil)
        k2 = body_rates(base, g, f2, e2, r2, v2, face2, contact, striker, anvil)
        x2 = moved(base, g, k2, striker)
        rate1, end_rate1 = overlap_rates(k1, anvil)
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
        edge = GRAZING * (abs(x[0]) + abs(x[2] if anvil.present else x[4]))
        if not in_contact:
            edge *= 2.0
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
            s = hermite_root(overlaps[0] - edge, d2 - edge, overlap_rates(k_a, anvil)[0], rate2, span)
            in_contact = not in_contact
            events[count, 0] = t_a + s * span
            if striker.elastic:
                events[count, 1] = mean_velocity(impulse + s * (impulse_b - impulse), contact, striker)
            else:
                events[count, 1] = hermite(x[1], x2[1], k_a[1], k2[1], span, s)
            events[count, 2] = 1.0 if in_contact else -1.0
            count += 1
        x, f, f_end, impulse, overlaps = x2, f2, e2, impulse_b, (d2, a2)
        t_a = t_b
        if f > f_max:
            f_max, t_max = f, t_a
        if f_end > e_max:
            e_max, te_max = f_end, t_a
        if f_end < e_min:
            e_min, te_min = f_end, t_a
    state[0], state[1], state[2], state[3], state[4] = x[0], x[1], x[4], f, impulse
    state[6], state[7], state[8] = x[2], x[3], f_end
    return work, dissipated, count, (f_max, t_max), (e_max, te_max, e_min, te_min)


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
    u = state[0]
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
    state[0] = u
    state[1] = c2 * u + b2 * k2
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
    return ends[S_MEDIUM], ends[S_MEDIUM + 1], ends[S_MEDIUM + 2], ends[S_MEDIUM + 3]


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
    u = state[0]
    held = (state[2], state[3], state[4], state[5])
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
    state[0], state[1] = u, f
    state[2], state[3], state[4], state[5] = held
    return dissipated, (f_max, t_max, f_min, t_min)


def _llvm_binary(name):
    """A Numba function `(float64, float64) → float64` that is the LLVM intrinsic `name`."""

    @intrinsic
    def call(typingctx, a, b):
        def codegen(context, builder, signature, args):
            double = ir.DoubleType()
            fn = cgutils.get_or_insert_function(builder.module, ir.FunctionType(double, [double, double]), name)
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
@compiled(fastmath={"contract", "reassoc", "nnan", "nsz"})
def tool_energy_and_stresses(u, new, cur, stressed, node_area, area_mid, strain_sigma, half_e_over_h):
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


@compiled(fastmath={"nnan"})
def first_node(u, row, half_e_over_h, start, value):
    """The first node of the block from `start` where the stress is `value` (its last if none)."""
    one = np.uint64(1)
    last = min(start + STRESS_BLOCK, u.shape[1] - 1) - 1
    first = last
    for i in range(np.uint64(start), np.uint64(last + 1)):
        found = half_e_over_h * (u[row, i + one] - u[row, i - one]) == value
        first = min(first, np.int64(i) if found else last)
    return first


@compiled(inline="always")
def track_contact(ends, observed, t_cross, velocity, into_contact, tau):
    """A change of the overlap's sign at `t_cross`: opens or closes a contact interval (δ ≥ 0 is
    contact); the first one to close sets the co-impact time and the rebound velocity."""
    extremes, contacts = observed
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


@compiled(inline="always")
def track_overlap(ends, observed, overlaps, delta, m, t, velocity, tau):
    """The contact intervals from the new overlap `delta` (layer m at `t`) and the layers'
    `Overlaps`: a change of sign placed on the parabola through the last three overlaps."""
    if (delta >= 0.0) != (ends[S_IN_CONTACT] != 0.0):
        t_cross = t - tau + tau * crossing(overlaps.old if m >= 2 else np.nan, overlaps.cur, delta)
        track_contact(ends, observed, t_cross, velocity, delta >= 0.0, tau)


@compiled(inline="always")
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


@compiled(inline="always")
def track_end_extreme(extremes, slot, value, x, t):
    if value > extremes[slot]:
        extremes[slot] = value
        extremes[slot + 1] = x
        extremes[slot + 2] = t


# --- A step's phases ------------------------------------------------------------------------------
#
# `advance` is the loop over layers; each phase of a step is one of the functions below. They are
# `inline="always"`: Numba puts them into `advance` before typing it, so that they are compiled
# with its fast-math flags and make the same multiply-adds as had they been written there. (As
# functions of their own, called, they would have their own flags, and LLVM does not inline them.)
#
# Each array an inlined function takes, alone or in a bundle, is a new reference, which Numba
# counts with atomic instructions (the module's docstring says what they cost); LLVM removes few of
# those counts where a phase has loops or calls, and with the bundles counted a step of the paper's
# scheme on 100 cells cost 70% more. `advance` holds its arguments for the whole call, so it hands
# the phases bundles whose arrays are `uncounted`: the same arrays, without the meminfo that
# Numba's counting goes through.


def _uncounted_value(context, builder, typ, value):
    if isinstance(typ, types.Array):
        view = context.make_array(typ)(context, builder, value=value)
        view.meminfo = cgutils.get_null_value(view.meminfo.type)
        return view._getvalue()
    if isinstance(typ, types.BaseTuple):
        for k, member in enumerate(typ):
            item = builder.extract_value(value, k)
            value = builder.insert_value(value, _uncounted_value(context, builder, member, item), k)
    return value


@intrinsic
def uncounted(typingctx, bundle):
    """The bundle (or array) with the same arrays, whose references are not counted: for use
    while something else holds them."""

    def codegen(context, builder, signature, args):
        return _uncounted_value(context, builder, bundle, args[0])

    return bundle(bundle), codegen


@compiled(inline="always")
def step_constants(tool, rod, weights, contact, anvil):
    """What every step derives from the bundles (`StepConstants`)."""
    n = len(tool.node_area) - 1
    h, tau, density = rod.cell_length, rod.time_step, rod.density
    striker_mass, striker_velocity = contact.striker_mass, contact.striker_velocity
    inv_tau2 = 1.0 / (tau * tau)
    e_over_h = rod.youngs_modulus / h
    lag = 1 if weights.centered and not weights.impedance_ends else 0  # recorded: layer m − lag
    strain_sigma = weights.new if weights.centered else 0.25  # 0.25: strain energy at the midpoint
    anvil_energy = 0.5 * anvil.mass * anvil.velocity * anvil.velocity if anvil.present else 0.0
    explicit = weights.new == 0.0 and weights.old == 0.0
    return StepConstants(
        n=n,
        weight_cur=1.0 - weights.new - weights.old,
        inv_tau2=inv_tau2,
        m1_tau2=striker_mass * inv_tau2,
        mass_0=density * h * tool.node_area[0] * inv_tau2,
        mass_n=density * h * tool.node_area[n] * inv_tau2,
        boundary=boundary_weights(weights, tau),
        lag=lag,
        strain_sigma=strain_sigma,
        e_over_h=e_over_h,
        half_e_over_h=0.5 * e_over_h,
        kinetic_factor=0.5 * density * h * inv_tau2,
        initial_energy=0.5 * striker_mass * striker_velocity * striker_velocity,
        anvil_energy=anvil_energy,
        segments=segment_layout(n),
        explicit=explicit,
    )


@compiled(inline="always")
def launch_striker(state, row, row_before, at, contact, striker, tau):
    """The striker at `at` in the layer in `row`, moving at W1 in it and in the layer before
    (`row_before`), unstrained: an elastic striker's incoming waves each carry W1/2."""
    y, ends, striker_u = state.y, state.ends, state.striker
    velocity = contact.striker_velocity
    y[row] = at
    y[row_before] = at - velocity * tau
    ends[S_STRIKER_VELOCITY] = velocity
    ends[S_IMPULSE] = 0.0
    if striker.elastic:
        for i in range(striker_u.shape[1]):
            striker_u[row, i] = at
            striker_u[row_before, i] = at - velocity * tau
        for slot in (S_FACE_INCOMING, S_BACK_INCOMING):
            ends[slot] = 0.0  # G of the layer in `row` (only its differences count)
            ends[slot + 1] = -0.5 * velocity * tau
        for slot in (S_BACK_RATE, S_BACK_RATE + 2):
            ends[slot] = 0.5 * velocity
            ends[slot + 1] = 0.0
        ends[S_BACK_ENERGY] = striker.back_impedance * 0.25 * velocity * velocity * striker.back_delay


@compiled()
def start_blow(m, state, observed, contact, striker, anvil, medium, tau):
    """The next blow, from layer m (the last one computed): the striker, withdrawn with what it
    had left (its energy and the contact's, `E_WITHDRAWN`), is launched again at W1 where it
    strikes (the struck end, or the anvil, which stays where it is and starts again at its own
    velocity) (`E_LAUNCHED`); a contact still open closes at t_m and the new one opens there.
    Rock meets the blow fresh (`fresh_rock`)."""
    u, y, ends, energy, _ = state
    if medium.kind == MEDIUM_BILINEAR:
        rock = fresh_rock(u[m % 3, u.shape[1] - 1], medium_state(ends), medium)
        for k in range(MEDIUM_STATE):
            ends[S_MEDIUM + k] = rock[k]
    row, row_before = m % 3, (m - 1) % 3
    t = m * tau
    struck = ends[S_ANVIL_DISP] if anvil.present else u[row, 0]
    potential = contact_law(y[row] - struck, contact)[1]
    energy[0, E_WITHDRAWN] += (
        energy[0, E_STRIKER_KINETIC] + energy[0, E_STRIKER_STRAIN] + potential + energy[0, E_ANVIL_KINETIC]
    )
    if ends[S_IN_CONTACT] != 0.0:
        track_contact(
            ends,
            observed,
            t,
            mean_velocity(ends[S_IMPULSE], contact, striker) if striker.elastic else ends[S_STRIKER_VELOCITY],
            False,
            tau,
        )
    launch_striker(state, row, row_before, struck, contact, striker, tau)
    launched = 0.5 * contact.striker_mass * contact.striker_velocity * contact.striker_velocity
    # an elastic striker's share beyond its last node is counted with its strain (the audit's form)
    beyond = ends[S_BACK_ENERGY] if striker.elastic else 0.0
    anvil_energy = 0.0
    if anvil.present:
        ends[S_ANVIL_VELOCITY] = anvil.velocity
        anvil_energy = 0.5 * anvil.mass * anvil.velocity * anvil.velocity
    energy[0, E_LAUNCHED] += launched + anvil_energy
    energy[0, E_STRIKER_KINETIC] = launched - beyond
    energy[0, E_STRIKER_STRAIN] = beyond
    energy[0, E_ANVIL_KINETIC] = anvil_energy
    energy[0, E_CONTACT_POTENTIAL] -= potential  # the anvil's with the tool stays
    ends[S_IN_CONTACT] = 1.0
    ends[S_CONTACT_START] = t


@compiled(inline="always")
def start_impact(state, layer, t, tool, rod, weights, contact, striker, anvil, step):
    """Layer 0 by (5), (6): the tool at rest, the striker at 0 moving at W1, δ(0) = 0 (in contact
    from the first instant), an anvil at 0 between them moving at its own velocity; and layer −1
    (row 2) one step before. Returns layer 0 as recorded."""
    u, y, ends, energy, striker_u = state
    striker_velocity = contact.striker_velocity
    for i in range(step.n + 1):
        u[layer.new, i] = 0.0
        u[2, i] = 0.0
    launch_striker(state, layer.new, 2, 0.0, contact, striker, rod.time_step)
    ends[S_IN_CONTACT] = 1.0
    ends[S_CONTACT_START] = 0.0
    # Φ(δ⁰) = Φ(0) = 0; the state before impact counts 0 too: no link acts yet.
    ends[S_POTENTIAL_BEFORE] = 0.0
    ends[S_POTENTIAL_BEFORE_THAT] = 0.0
    ends[S_ANVIL_DISP] = 0.0
    ends[S_ANVIL_VELOCITY] = anvil.velocity
    energy[0, E_ANVIL_KINETIC] = step.anvil_energy
    if weights.impedance_ends:
        contact_force, end_force = struck_forces(
            (0.0, striker_velocity, 0.0, anvil.velocity, 0.0), 0.0, 0.5 * striker_velocity, contact, striker, anvil
        )
        energy[0, E_STRIKER_KINETIC] = step.initial_energy
    else:
        contact_force = end_force = contact.damping * striker_velocity
    ends[S_ANVIL_FORCE] = end_force
    return Recorded(
        row=layer.new,
        time=t,
        velocity=striker_velocity,
        contact_force=contact_force,
        medium_force=0.0,
        struck_end_stress=-end_force / tool.struck_end_area,
        working_end_stress=0.0,
    )


@compiled(inline="always")
def known_layers(u, layer, i, weight_cur, weight_old):
    """The known layers' combination `v = w_n·u^n + w_{n−1}·u^{n−1}` at nodes i − 1, i, i + 1."""
    _, cur, old, _ = layer
    return (
        weight_cur * u[cur, i - 1] + weight_old * u[old, i - 1],
        weight_cur * u[cur, i] + weight_old * u[old, i],
        weight_cur * u[cur, i + 1] + weight_old * u[old, i + 1],
    )


@compiled(inline="always")
def right_hand_sides(u, layer, tool, rows, rod, weights, step):
    """Right-hand sides of the tool's rows u_1 … u_{N−1} over their diagonals, into row `new` of
    `u` (the sweep turns them into the Q_i there). The known layers enter the operator as one
    combination v (`known_layers`). Each case has a loop of its own: a loop that tests `uniform`
    at every node, as LLVM leaves it, costs about 4% of a step of the paper's scheme on 2000 cells."""
    new, cur, old, _ = layer
    n, r, weight_cur, weight_old = step.n, rod.courant_squared, step.weight_cur, weights.old
    grid_lower, grid_upper, inv_den = tool.lower, tool.upper, rows.inv_den
    if step.explicit:
        explicit_interior(u, layer, tool, r, n)
    elif tool.uniform:
        for i in range(1, n):
            v_left, v_mid, v_right = known_layers(u, layer, i, weight_cur, weight_old)
            lap = v_left - 2.0 * v_mid + v_right
            u[new, i] = (2.0 * u[cur, i] - u[old, i] + r * lap) * inv_den[i]
    else:
        for i in range(1, n):
            v_left, v_mid, v_right = known_layers(u, layer, i, weight_cur, weight_old)
            lap = grid_lower[i] * (v_left - v_mid) + grid_upper[i] * (v_right - v_mid)
            u[new, i] = (2.0 * u[cur, i] - u[old, i] + r * lap) * inv_den[i]


@compiled(inline="always")
def explicit_interior(u, layer, tool, r, n):
    """The explicit scheme's interior nodes 1 … n−1 of the new layer: uncoupled (den_i = 1)."""
    new, cur, old, _ = layer
    grid_lower, grid_upper = tool.lower, tool.upper
    if tool.uniform:
        for i in range(1, n):
            u[new, i] = 2.0 * u[cur, i] - u[old, i] + r * (u[cur, i - 1] - 2.0 * u[cur, i] + u[cur, i + 1])
    else:
        for i in range(1, n):
            u[new, i] = (
                2.0 * u[cur, i]
                - u[old, i]
                + r * (grid_lower[i] * (u[cur, i - 1] - u[cur, i]) + grid_upper[i] * (u[cur, i + 1] - u[cur, i]))
            )


NO_CARRIES = (0.0, 0.0, 0.0, 0.0)


@compiled(inline="always")
def sweep(u, layer, rows, step):
    """The sweep toward the struck end: `(Q_1, carries)`, Q_1 the tool's link to the struck end
    `u_1 = P_1·u_0 + Q_1` (`sweep_toward_struck_end`). The explicit scheme's rows are uncoupled:
    Q_1 is row 1's own right-hand side and nothing is carried."""
    if step.explicit:
        return u[layer.new, 1], NO_CARRIES
    length, head = step.segments
    return sweep_toward_struck_end(u, layer.new, rows, length, head)


@compiled(inline="always")
def back_substitute(u, layer, u_0, carries, rows, step):
    """The substitution toward the working end from the new `u_0`: the new layer in row `new`."""
    if step.explicit:
        n = step.n
        # P_i = 0 but at a massless working end
        u[layer.new, n] = rows.p[n] * u[layer.new, n - 1] + u[layer.new, n]
    else:
        length, head = step.segments
        substitute_toward_working_end(u, layer.new, rows, length, head, u_0, carries)


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


@compiled(inline="always")
def solve_struck_end(state, layer, overlaps, link, r_n, contact, rod, weights, step):
    """The striker row (11) and the struck end's row (9) of the step, solved with the contact.

    The struck end sees the tool only through its link `u_1 = P_1·u_0 + Q_1` (`link` = (P_1, Q_1),
    from the sweep). With it the rows are `a_y·y = b_y − F` and `a_0·u_0 = b_0 + F`, F the contact
    force: a scalar equation in the new overlap δ (`solve_overlap`), from the layers' `Overlaps`;
    R(t_n) = `r_n` is explicit in row (11). Returns `(y, u_0, F)` of the new layer, F the force the
    scheme applies in the step (centred on layer n, or on the new layer for the paper's).
    """
    u, y, ends, _, _ = state
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
def integrate_ends(state, observed, layer, t, tool, rod, contact, striker, anvil, medium, force, scratch, step):
    """The ends that integrate their own equations, over the step to `t`: the waves arriving at
    them, then the striker, the anvil and the struck end (`struck_end_step`), an elastic striker's
    back end (`free_back_end`) and the working end (`working_end_step`), with the contacts and the
    end forces' extremes their substeps see. Returns whether the new ends are finite (they are
    written to the new layer only then), the striker's velocity, the contact force, the force on
    the tool's struck end (the anvil's, or the contact's), the medium's, and `(work of R,
    dissipated by the contacts, by the medium)` over the step. `scratch`: room for the struck
    end's and the working end's states and the events."""
    u, y, ends, _, striker_u = state
    new, cur, _, _ = layer
    n, tau = step.n, rod.time_step
    end_state, far_state, events = scratch
    v_in, v_slope = incoming_wave(u, layer, 1, 0, ends, S_INCOMING, tau)
    v_far, far_slope = incoming_wave(u, layer, n - 1, n, ends, S_FAR_INCOMING, tau)
    face_in, face_slope = 0.0, 0.0
    if striker.elastic:
        face_in, face_slope = incoming_wave(striker_u, layer, 1, 0, ends, S_FACE_INCOMING, tau)
    end_state[0] = y[cur]
    end_state[1] = ends[S_STRIKER_VELOCITY]
    end_state[2] = u[cur, 0]
    end_state[3] = ends[S_FORCE_BEFORE]
    end_state[4] = ends[S_IMPULSE]
    end_state[5] = ends[S_IN_CONTACT]
    end_state[6] = ends[S_ANVIL_DISP]
    end_state[7] = ends[S_ANVIL_VELOCITY]
    end_state[8] = ends[S_ANVIL_FORCE]
    work, dissipated, crossings, contact_range, end_range = struck_end_step(
        t - tau, tau, end_state, (v_in, v_slope, face_in, face_slope), contact, striker, anvil, force, events
    )
    far_state[0] = u[cur, n]
    far_state[1] = ends[S_MEDIUM_FORCE]
    for k in range(MEDIUM_STATE):
        far_state[2 + k] = ends[S_MEDIUM + k]
    dissipated_far, working_range = working_end_step(tau, far_state, v_far, far_slope, medium)
    track_ends_between_layers(observed.extremes, contact_range, end_range, working_range, t, tool, rod, step)
    flows = (work, dissipated, dissipated_far)
    if not (
        abs(end_state[0]) < 1e300
        and abs(end_state[2]) < 1e300
        and abs(end_state[6]) < 1e300
        and abs(far_state[0]) < 1e300
    ):
        return False, 0.0, 0.0, 0.0, 0.0, flows
    y[new] = end_state[0]
    u[new, 0] = end_state[2]
    u[new, n] = far_state[0]
    for k in range(MEDIUM_STATE):
        ends[S_MEDIUM + k] = far_state[2 + k]
    ends[S_STRIKER_VELOCITY] = end_state[1]
    ends[S_IMPULSE] = end_state[4]
    ends[S_ANVIL_DISP] = end_state[6]
    ends[S_ANVIL_VELOCITY] = end_state[7]
    ends[S_ANVIL_FORCE] = end_state[8]
    velocity = end_state[1]
    if striker.elastic:
        striker_u[new, 0] = y[new]
        free_back_end(striker_u, layer, ends, striker, tau)
        velocity = mean_velocity(end_state[4], contact, striker)
    for k in range(crossings):
        track_contact(ends, observed, events[k, 0], events[k, 1], events[k, 2] > 0.0, tau)
    return True, velocity, end_state[3], end_state[8], far_state[1], flows


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
    return (now, (ends[S_BACK_RATE], ends[S_BACK_RATE + 1]), (ends[S_BACK_RATE + 2], ends[S_BACK_RATE + 3]))


@compiled(inline="always")
def free_back_end(striker_u, layer, ends, striker, tau):
    """An elastic striker's back end, free, `back_delay` beyond its last node: the node moves at
    the wave arriving at it plus that wave as the free end returns it, `back_delay` later:
    `y_N' = v_b(t) + v_b(t − d)`, integrated over the step exactly for rates linear in each step."""
    new, cur, _, _ = layer
    n_s = striker_u.shape[1] - 1
    now = incoming_wave(striker_u, layer, n_s - 1, n_s, ends, S_BACK_INCOMING, tau)
    d = striker.back_delay
    rates = back_rates(ends, now)
    returned = rate_integral(rates, tau, -d, tau - d, 1)
    striker_u[new, n_s] = striker_u[cur, n_s] + tau * now[0] + returned
    # each wave there carries Z·v² of power, the arriving one for the last d/2, the returned one
    # for the d/2 before: Z·∫v_b² over [t − d, t], at the step's middle as the grid's energy is
    ends[S_BACK_ENERGY] = striker.back_impedance * rate_integral(rates, tau, 0.5 * tau - d, 0.5 * tau, 2)
    ends[S_BACK_RATE + 2], ends[S_BACK_RATE + 3] = ends[S_BACK_RATE], ends[S_BACK_RATE + 1]
    ends[S_BACK_RATE], ends[S_BACK_RATE + 1] = now


@compiled(inline="always")
def incoming_wave(u, layer, inner, edge, ends, slot, tau):
    """For the ends that integrate their own equations: the mean rate over this step of the wave
    arriving at the end node `edge` (its neighbour `inner`) and its slope within the step. Its
    displacement `G_m = u_inner^{m−1} − u_edge^{m−2} + G_{m−2}`: G_{m−1}, G_{m−2} are carried in
    `ends[slot]`, `ends[slot + 1]`; G_m, G_{m+1} come from the layers."""
    new, cur, old, _ = layer
    g_before, g_last = ends[slot + 1], ends[slot]
    g_now = u[cur, inner] - u[old, edge] + g_before
    g_next = u[new, inner] - u[cur, edge] + g_last
    rate = (g_now - g_last) / tau
    slope = limited_slope((g_last - g_before) / tau, rate, (g_next - g_now) / tau, tau)
    ends[slot + 1], ends[slot] = g_last, g_now
    return rate, slope


# --- Energy audit, extremes, recording ------------------------------------------------------------


@compiled(inline="always")
def audit_scheme_energy(state, layer, rec, r_n, overlaps, potential, contact, medium, tool, rod, step):
    """The energy terms of the new layer at m − ½, in the form each scheme conserves (or
    dissipates), into `energy[0]`; returns the balance (stored + dissipated − input: > 0 is energy
    created) and the interior stress extremes of the layer in row `rec` (the one recorded), which
    the same pass along the tool finds (`tool_energy_and_stresses`). `r_n`: R(t_n) of the step;
    `overlaps`: the layers' before it; `potential`: Φ of the new layer."""
    u, y, ends, energy, _ = state
    new, cur, old, ref = layer
    delta = y[new] - u[new, 0]
    n, tau = step.n, rod.time_step
    _, spring_weight, damper_factor, _ = step.boundary
    dy = y[new] - y[cur]
    striker_kinetic = 0.5 * contact.striker_mass * dy * dy * step.inv_tau2
    tool_kinetic, tool_strain, low, low_block, high, high_block = tool_energy_and_stresses(
        u, new, cur, rec, tool.node_area, tool.area_mid, step.strain_sigma, step.half_e_over_h
    )
    tool_kinetic *= step.kinetic_factor
    tool_strain *= 0.5 * step.e_over_h
    contact_pot = spring_weight * potential + (1.0 - spring_weight) * ends[S_POTENTIAL_BEFORE]
    medium_pot = (
        0.5 * medium.stiffness * (spring_weight * u[new, n] * u[new, n] + (1.0 - spring_weight) * u[cur, n] * u[cur, n])
    )
    energy[0, E_EXTERNAL_WORK] += r_n * 0.5 * (y[new] - y[old])
    rate = damper_factor * (delta - overlaps.ref)
    energy[0, E_DISSIPATED_CONTACT] += contact.damping * rate * rate * tau
    rate = damper_factor * (u[new, n] - u[ref, n])
    energy[0, E_DISSIPATED_MEDIUM] += medium.damping * rate * rate * tau
    energy[0, E_STRIKER_KINETIC] = striker_kinetic
    energy[0, E_TOOL_KINETIC] = tool_kinetic
    energy[0, E_TOOL_STRAIN] = tool_strain
    energy[0, E_CONTACT_POTENTIAL] = contact_pot
    energy[0, E_MEDIUM_POTENTIAL] = medium_pot
    balance = (
        striker_kinetic
        + tool_kinetic
        + tool_strain
        + contact_pot
        + medium_pot
        + energy[0, E_DISSIPATED_CONTACT]
        + energy[0, E_DISSIPATED_MEDIUM]
        - step.initial_energy
        - energy[0, E_EXTERNAL_WORK]
    )
    return balance, (low, low_block, high, high_block)


@compiled(inline="always")
def audit_impedance_energy(state, layer, flows, velocity, contact, striker, anvil, medium, tool, step):
    """As `audit_scheme_energy` for the ends that integrate their own equations: the ends' terms
    at layer m (`flows`: the work of R and what the dampers b1, b2 dissipated over the step), the
    tool's and an elastic striker's at m − ½ (the form the explicit scheme conserves); the balance
    compares them at m − ½."""
    u, y, ends, energy, striker_u = state
    new, cur, _, _ = layer
    n = step.n
    work, dissipated, dissipated_far = flows
    if anvil.present:
        anvil_at = ends[S_ANVIL_DISP]
        velocity_a = ends[S_ANVIL_VELOCITY]
        potential = contact_law(y[new] - anvil_at, contact)[1] + contact_law(anvil_at - u[new, 0], anvil.contact)[1]
        energy[0, E_ANVIL_KINETIC] = 0.5 * anvil.mass * velocity_a * velocity_a
    else:
        potential = contact_law(y[new] - u[new, 0], contact)[1]
    stored, plastic = medium_energy(u[new, n], medium_state(ends), medium)
    tool_kinetic, tool_strain, low, low_block, high, high_block = tool_energy_and_stresses(
        u, new, cur, new, tool.node_area, tool.area_mid, step.strain_sigma, step.half_e_over_h
    )
    energy[0, E_EXTERNAL_WORK] += work
    energy[0, E_DISSIPATED_CONTACT] += dissipated
    energy[0, E_DISSIPATED_MEDIUM] += dissipated_far
    energy[0, E_TOOL_KINETIC] = tool_kinetic * step.kinetic_factor
    energy[0, E_TOOL_STRAIN] = tool_strain * 0.5 * step.e_over_h
    energy[0, E_CONTACT_POTENTIAL] = potential
    energy[0, E_MEDIUM_POTENTIAL] = stored
    energy[0, E_MEDIUM_PLASTIC] = plastic
    balance = (
        energy[0, E_TOOL_KINETIC]
        + energy[0, E_TOOL_STRAIN]
        - step.initial_energy
        - step.anvil_energy
        + energy[0, E_WITHDRAWN]
        - energy[0, E_LAUNCHED]
    )
    if striker.elastic:
        s_tool, s_rod = striker.tool, striker.rod
        e_over_h = s_rod.youngs_modulus / s_rod.cell_length
        kinetic, strain, _, _, _, _ = tool_energy_and_stresses(
            striker_u, new, cur, new, s_tool.node_area, s_tool.area_mid, step.strain_sigma, 0.5 * e_over_h
        )
        energy[0, E_STRIKER_KINETIC] = kinetic * 0.5 * s_rod.density * s_rod.cell_length * step.inv_tau2
        energy[0, E_STRIKER_STRAIN] = strain * 0.5 * e_over_h + ends[S_BACK_ENERGY]
        balance += energy[0, E_STRIKER_KINETIC] + energy[0, E_STRIKER_STRAIN]
    else:
        energy[0, E_STRIKER_KINETIC] = 0.5 * contact.striker_mass * velocity * velocity
        balance += 0.5 * (energy[0, E_STRIKER_KINETIC] + energy[1, E_STRIKER_KINETIC])
    for slot in (
        E_CONTACT_POTENTIAL,
        E_MEDIUM_POTENTIAL,
        E_MEDIUM_PLASTIC,
        E_ANVIL_KINETIC,
        E_DISSIPATED_CONTACT,
        E_DISSIPATED_MEDIUM,
    ):
        balance += 0.5 * (energy[0, slot] + energy[1, slot])
    balance -= 0.5 * (energy[0, E_EXTERNAL_WORK] + energy[1, E_EXTERNAL_WORK])
    return balance, (low, low_block, high, high_block)


@compiled(inline="always")
def track_energy_excess(extremes, balance):
    """Whether the energy balance is finite; the largest energy the scheme created so far."""
    if not abs(balance) < 1e300:
        return False
    if balance > extremes[X_ENERGY_EXCESS]:
        extremes[X_ENERGY_EXCESS] = balance
    return True


@compiled(inline="always")
def track_ends_between_layers(extremes, contact_range, end_range, working_range, t, tool, rod, step):
    """The end forces' extremes within the step, as the ends' substeps saw them: `contact_range`
    (largest contact force, its time), `end_range` (the force on the tool's struck end: largest,
    its time, least, its time) and `working_range` (the medium force's, with their offsets from
    the step's start)."""
    f_max, t_max = contact_range
    e_max, te_max, e_min, te_min = end_range
    g_max, tg_max, g_min, tg_min = working_range
    n, h, tau = step.n, rod.cell_length, rod.time_step
    end_area_0, end_area_n = tool.struck_end_area, tool.working_end_area
    if f_max > extremes[X_PEAK_FORCE]:
        extremes[X_PEAK_FORCE] = f_max
        extremes[X_PEAK_FORCE_TIME] = t_max
    track_end_extreme(extremes, X_MAX_COMPRESSION, e_max / end_area_0, 0.0, te_max)
    track_end_extreme(extremes, X_MAX_TENSION, -e_min / end_area_0, 0.0, te_min)
    track_end_extreme(extremes, X_MAX_COMPRESSION, g_max / end_area_n, n * h, t - tau + tg_max)
    track_end_extreme(extremes, X_MAX_TENSION, -g_min / end_area_n, n * h, t - tau + tg_min)


@compiled(inline="always")
def track_stress_extremes(extremes, u, recorded, interior, rod, step):
    """The recorded layer's extreme stresses along the tool (`interior`: its interior nodes' least
    and greatest stress with their blocks, `tool_energy_and_stresses`) against the records.

    Not refined between nodes: next to a kink (a reflected front meeting the peak) a parabola
    through three nodes overshoots by O(h), where the nodes' own error is O(h²)."""
    low, low_block, high, high_block = interior
    s0, sn = recorded.struck_end_stress, recorded.working_end_stress
    s_low, s_high = min(s0, low, sn), max(s0, high, sn)
    for peak, value, inside, block, slot in (
        (-s_low, s_low, low, low_block, X_MAX_COMPRESSION),
        (s_high, s_high, high, high_block, X_MAX_TENSION),
    ):
        if peak > extremes[slot]:
            # Where, only for a new record (most layers set none): the first node of that
            # stress, from the struck end.
            if value == s0:
                node = 0
            elif value == inside:
                node = first_node(u, recorded.row, step.half_e_over_h, block, value)
            else:
                node = step.n
            extremes[slot] = peak
            extremes[slot + 1] = node * rod.cell_length
            extremes[slot + 2] = recorded.time


@compiled(inline="always")
def track_end_forces(extremes, ends, recorded, m_rec, tool, rod, step, struck_vertex):
    """The peak contact force and the end stresses' extremes between layers, from the recorded
    layer's end forces and those of the three layers before it (carried in `ends`); at the struck
    end only when the contact force is the force on it (`struck_vertex`: not with an anvil,
    whose substeps' extremes are all there is)."""
    contact_force, medium_force = recorded.contact_force, recorded.medium_force
    t_rec, n, h, tau = recorded.time, step.n, rod.cell_length, rod.time_step
    end_area_0, end_area_n = tool.struck_end_area, tool.working_end_area
    if contact_force > extremes[X_PEAK_FORCE]:
        extremes[X_PEAK_FORCE] = contact_force
        extremes[X_PEAK_FORCE_TIME] = t_rec
    # Extremes of the end forces between layers: the vertex of the parabola through the last
    # three, so that their error is the scheme's, not the sampling's.
    f1, f2, f3 = ends[S_FORCE_BEFORE], ends[S_FORCE_BEFORE_THAT], ends[S_FORCE_EARLIER]
    g1, g2, g3 = ends[S_MEDIUM_FORCE], ends[S_MEDIUM_FORCE_BEFORE], ends[S_MEDIUM_FORCE_EARLIER]
    if m_rec >= 3 and struck_vertex:
        top, offset = vertex(f3, f2, f1, contact_force)
        when = t_rec - tau + offset * tau
        if top > extremes[X_PEAK_FORCE]:
            extremes[X_PEAK_FORCE] = top
            extremes[X_PEAK_FORCE_TIME] = when
        track_end_extreme(extremes, X_MAX_COMPRESSION, top / end_area_0, 0.0, when)
        top, offset = vertex(-f3, -f2, -f1, -contact_force)
        track_end_extreme(extremes, X_MAX_TENSION, top / end_area_0, 0.0, t_rec - tau + offset * tau)
    if m_rec >= 3:
        top, offset = vertex(g3, g2, g1, medium_force)
        track_end_extreme(extremes, X_MAX_COMPRESSION, top / end_area_n, n * h, t_rec - tau + offset * tau)
        top, offset = vertex(-g3, -g2, -g1, -medium_force)
        track_end_extreme(extremes, X_MAX_TENSION, top / end_area_n, n * h, t_rec - tau + offset * tau)
    ends[S_FORCE_EARLIER] = f2
    ends[S_FORCE_BEFORE_THAT] = f1
    ends[S_FORCE_BEFORE] = contact_force
    ends[S_MEDIUM_FORCE_EARLIER] = g2
    ends[S_MEDIUM_FORCE_BEFORE] = g1
    ends[S_MEDIUM_FORCE] = medium_force


@compiled(inline="always")
def record_history(recorders, column, state, recorded, m_rec, force, anvil, step):
    """The recorded layer into `column` of the history (its energy terms as `energy[0]` holds
    them; none yet for layer 0, whose energy is all the striker's)."""
    history = recorders.history
    u, y, _, energy, _ = state
    rec, t_rec = recorded.row, recorded.time
    history[H_TIME, column] = t_rec
    history[H_STRIKER_DISP, column] = y[rec]
    history[H_STRIKER_VEL, column] = recorded.velocity
    history[H_STRUCK_END, column] = u[rec, 0]
    history[H_WORKING_END, column] = u[rec, step.n]
    history[H_CONTACT_FORCE, column] = recorded.contact_force
    struck = state.ends[S_ANVIL_DISP] if anvil.present else u[rec, 0]  # what the striker meets
    history[H_OVERLAP, column] = y[rec] - struck
    history[H_MEDIUM_FORCE, column] = recorded.medium_force
    history[H_EXTERNAL_FORCE, column] = external_force(t_rec, force)
    history[H_EXTERNAL_WORK, column] = energy[0, E_EXTERNAL_WORK]
    history[H_DISSIPATED_CONTACT, column] = energy[0, E_DISSIPATED_CONTACT]
    history[H_DISSIPATED_MEDIUM, column] = energy[0, E_DISSIPATED_MEDIUM]
    history[H_PERMANENT_PENETRATION, column] = state.ends[S_MEDIUM_SET]
    history[H_STRIKER_STRAIN, column] = energy[0, E_STRIKER_STRAIN]
    history[H_ANVIL_DISP, column] = state.ends[S_ANVIL_DISP]
    history[H_ANVIL_VEL, column] = state.ends[S_ANVIL_VELOCITY]
    history[H_ANVIL_FORCE, column] = state.ends[S_ANVIL_FORCE]
    history[H_ANVIL_KINETIC, column] = energy[0, E_ANVIL_KINETIC]
    history[H_LAUNCHED, column] = energy[0, E_LAUNCHED]
    history[H_WITHDRAWN, column] = energy[0, E_WITHDRAWN]
    if m_rec == 0:
        history[H_STRIKER_KINETIC, column] = step.initial_energy
        for c in (H_TOOL_KINETIC, H_TOOL_STRAIN, H_CONTACT_POTENTIAL, H_MEDIUM_POTENTIAL, H_MEDIUM_PLASTIC):
            history[c, column] = 0.0
    else:
        history[H_STRIKER_KINETIC, column] = energy[0, E_STRIKER_KINETIC]
        history[H_TOOL_KINETIC, column] = energy[0, E_TOOL_KINETIC]
        history[H_TOOL_STRAIN, column] = energy[0, E_TOOL_STRAIN]
        history[H_CONTACT_POTENTIAL, column] = energy[0, E_CONTACT_POTENTIAL]
        history[H_MEDIUM_POTENTIAL, column] = energy[0, E_MEDIUM_POTENTIAL]
        history[H_MEDIUM_PLASTIC, column] = energy[0, E_MEDIUM_PLASTIC]


@compiled(inline="always")
def record_probes(recorders, row, u, recorded, step):
    """The stress at each probe into `row` of `probes`: linear between its two nodes."""
    for k in range(len(recorders.probe_node)):
        j = recorders.probe_node[k]
        w = recorders.probe_weight[k]
        s = (1.0 - w) * node_stress(u, recorded, j, step)
        if w > 0.0:
            s += w * node_stress(u, recorded, j + 1, step)
        recorders.probes[row, k] = s


@compiled(inline="always")
def record_fields(recorders, row, state, recorded, striker, step):
    """The displacement and the stress along the tool into `row` of the fields, and along an
    elastic striker: its x runs from its face away from the tool, so its stress is `−E·∂u/∂x`
    (tension +; the contact force at its face, one-sided at its last node)."""
    u, rec = state.u, recorded.row
    for i in range(step.n + 1):
        recorders.field_u[row, i] = u[rec, i]
        recorders.field_stress[row, i] = node_stress(u, recorded, i, step)
    if striker.elastic:
        s_u, stress = state.striker, recorders.striker_stress
        n_s = s_u.shape[1] - 1
        e_over_h = striker.rod.youngs_modulus / striker.rod.cell_length
        for i in range(n_s + 1):
            recorders.striker_u[row, i] = s_u[rec, i]
        stress[row, 0] = -recorded.contact_force / striker.tool.struck_end_area
        for i in range(1, n_s):
            stress[row, i] = -0.5 * e_over_h * (s_u[rec, i + 1] - s_u[rec, i - 1])
        stress[row, n_s] = -e_over_h * (s_u[rec, n_s] - s_u[rec, n_s - 1])


# `contract` lets LLVM fuse `a·b + c` into one multiply-add (one rounding instead of two) where the
# CPU has one: each of the two recurrences along the tool then has a single operation a node on its
# critical path. No other fast-math assumption is made (NaN, infinities, reordering): the checks for
# non-finite values rely on that.
@compiled(fastmath={"contract"})
def advance(first, last, tool, rows, rod, weights, contact, striker, anvil, medium, force, state, observed, recorders):
    """Compute layers `first … last` (inclusive; layer 0 is the initial state).

    The `Tool` with its rows factored (`ToolRows`), the `Rod`'s constants and the scheme's
    `Weights`; the ends: the `Contact` at the struck end, the `Striker` when it is a rod, the
    `Medium` (at the working end), and R(t) on the striker (`ForceLaw`). The `State` carries the layers from call to
    call, the `Observed` extremes and contacts accumulate, and the `Recorders` take the layers
    this call records, from the first of each buffer.

    The interior operator weights layers n+1, n, n−1 by `weights.new`, `1 − new − old`,
    `weights.old`. `weights.centered` centres the boundary terms on layer n (springs
    `(z^{n+1} + z^{n−1})/2`, dampers `(z^{n+1} − z^{n−1})/(2τ)`, the contact quotient between
    δ^{n+1} and δ^{n−1}); otherwise they are the paper's (new layer, `(z^{n+1} − z^n)/τ`).
    `weights.end_masses` gives the end rows the interior's weights (they then carry their half-cell
    mass `node_area·ρh`); massless ends are quasi-static, all on the new layer.
    `weights.impedance_ends` (the explicit scheme at Courant number 1 only) integrates each end's
    own equations instead (`integrate_ends`).

    What is recorded of a layer is what the scheme applies there: the centred schemes' boundary
    forces are centred on layer n, so a layer is recorded one step after it is computed (the
    caller runs one layer more); the paper's act on the new layer, the ends that integrate their
    own equations have their forces at every instant.

    Returns `(status, layers of history written, rows of fields written)`; on a non-finite value
    it stops with `STATUS_NON_FINITE` and the time in `extremes[X_FAILED_TIME]`.
    """
    tool, rows, striker, state, observed, recorders = uncounted((tool, rows, striker, state, observed, recorders))
    step = step_constants(tool, rod, weights, contact, anvil)
    u, y, ends, energy, striker_u = state
    extremes = observed.extremes
    tau = rod.time_step
    # the ends' states and the struck end's events within a step (`integrate_ends`), lent to each
    # step `uncounted`: `scratch` holds them through the loop
    scratch = (np.empty(9), np.empty(6), np.empty((4, 3)))
    n_hist = 0
    n_field = 0

    for m in range(first, last + 1):
        layer = Layers(new=m % 3, cur=(m - 1) % 3, old=(m - 2) % 3, ref=(m - step.boundary.back) % 3)
        new, cur, old, ref = layer
        t = m * tau
        if m == 0:
            recorded = start_impact(state, layer, t, tool, rod, weights, contact, striker, anvil, step)
            interior = (np.inf, 0, -np.inf, 0)  # the tool at rest: only the end stresses count
        else:
            for slot in range(ENERGY_SLOTS):
                energy[1, slot] = energy[0, slot]
            # Right-hand sides of rows u_N … u_1 over their diagonals; Q_i is kept in row `new`
            # until the substitution.
            if not weights.impedance_ends:
                working_end_row(u, layer, rows, rod, weights, medium, step)
            right_hand_sides(u, layer, tool, rows, rod, weights, step)
            if striker.elastic:
                explicit_interior(striker_u, layer, striker.tool, 1.0, striker_u.shape[1] - 1)

            if weights.impedance_ends:
                finite, velocity, contact_force, end_force, medium_force, flows = integrate_ends(
                    state,
                    observed,
                    layer,
                    t,
                    tool,
                    rod,
                    contact,
                    striker,
                    anvil,
                    medium,
                    force,
                    uncounted(scratch),
                    step,
                )
                if not finite:
                    extremes[X_FAILED_TIME] = t
                    return STATUS_NON_FINITE, n_hist, n_field
                rec, t_rec = new, t
                balance, interior = audit_impedance_energy(
                    state, layer, flows, velocity, contact, striker, anvil, medium, tool, step
                )
            else:
                overlaps = Overlaps(cur=y[cur] - u[cur, 0], old=y[old] - u[old, 0], ref=y[ref] - u[ref, 0])
                r_n = external_force((m - 1) * tau, force)  # R(t_n), explicit in row (11)
                q_1, carries = sweep(u, layer, rows, step)
                y_new, u0_new, contact_force = solve_struck_end(
                    state, layer, overlaps, (rows.p[1], q_1), r_n, contact, rod, weights, step
                )
                end_force = contact_force
                if not (abs(y_new) < 1e300 and abs(u0_new) < 1e300):
                    extremes[X_FAILED_TIME] = t
                    return STATUS_NON_FINITE, n_hist, n_field
                y[new] = y_new
                u[new, 0] = u0_new
                back_substitute(u, layer, u0_new, carries, rows, step)
                medium_force = working_end_force(u, layer, medium, step)
                # Φ of the new layer from its own overlap, as the next steps' quotients take it
                delta = y_new - u0_new
                potential = contact_law(delta, contact)[1]
                if step.lag:
                    rec, t_rec = cur, t - tau
                    velocity = (y_new - y[old]) / (2.0 * tau)
                else:
                    rec, t_rec = new, t
                    velocity = (
                        contact.striker_velocity if m == 1 else (3.0 * y_new - 4.0 * y[cur] + y[old]) / (2.0 * tau)
                    )
                balance, interior = audit_scheme_energy(
                    state, layer, rec, r_n, overlaps, potential, contact, medium, tool, rod, step
                )
                ends[S_POTENTIAL_BEFORE_THAT] = ends[S_POTENTIAL_BEFORE]
                ends[S_POTENTIAL_BEFORE] = potential
                track_overlap(ends, observed, overlaps, delta, m, t, velocity, tau)

            if not track_energy_excess(extremes, balance):
                extremes[X_FAILED_TIME] = t
                return STATUS_NON_FINITE, n_hist, n_field
            recorded = Recorded(
                row=rec,
                time=t_rec,
                velocity=velocity,
                contact_force=contact_force,
                medium_force=medium_force,
                struck_end_stress=-end_force / tool.struck_end_area,
                working_end_stress=-medium_force / tool.working_end_area,
            )

        if m < step.lag:
            continue  # the centred schemes record layer 0 once its forces are known
        m_rec = m - step.lag
        track_stress_extremes(extremes, u, recorded, interior, rod, step)
        extremes[X_MAX_PENETRATION] = max(extremes[X_MAX_PENETRATION], u[recorded.row, step.n])
        track_end_forces(extremes, ends, recorded, m_rec, tool, rod, step, not anvil.present)
        if recorders.history_stride > 0 and m_rec % recorders.history_stride == 0:
            record_history(recorders, n_hist, state, recorded, m_rec, force, anvil, step)
            record_probes(recorders, n_hist, u, recorded, step)
            n_hist += 1
        if recorders.field_stride > 0 and m_rec % recorders.field_stride == 0:
            record_fields(recorders, n_field, state, recorded, striker, step)
            n_field += 1
    return STATUS_OK, n_hist, n_field
