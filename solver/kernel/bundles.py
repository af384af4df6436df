"""What a step takes and carries, by name: the force and medium kinds, the ends' slots
(`S_…`), the named bundles `advance` takes (`Tool`, `ToolRows`, `Rod`, `Weights`, `Contact`,
`Medium`, `ForceLaw`, `Striker`, `Anvil`, `State`, `Observed`, `Recorders`) and those within a
step, and the state before a run.
"""

from __future__ import annotations

from collections import namedtuple

import numpy as np

from ..compiled import compiled
from ..layout import ENERGY_SLOTS, ENVELOPE_BINS, new_extremes

# Medium kinds (`Medium.kind`); R(t)'s kinds are `laws.FORCE_…`
MEDIUM_LINEAR, MEDIUM_BILINEAR, MEDIUM_SMITH = 0, 1, 2

# End slots (`ends[S_…]`): what the next step needs of the ends beyond the layers. Whether the
# striker is in contact and since when; the end forces and the contact potential at the last
# recorded layers (m−1, m−2, m−3); for the ends that integrate their own equations, the
# striker's velocity and the incoming waves' displacements G at the struck end and at the
# working end, at layers m−1, m−2 (m−3 below)
S_IN_CONTACT, S_CONTACT_START = 0, 1
S_FORCE_BEFORE, S_FORCE_BEFORE_THAT, S_FORCE_EARLIER = 2, 3, 4  # the contact force
S_MEDIUM_FORCE, S_MEDIUM_FORCE_BEFORE, S_MEDIUM_FORCE_EARLIER = 5, 6, 7
S_POTENTIAL_BEFORE, S_POTENTIAL_BEFORE_THAT = 8, 9  # contact potential Φ at layers m−1, m−2
S_STRIKER_VELOCITY = 10
S_INCOMING, S_INCOMING_BEFORE, S_FAR_INCOMING, S_FAR_INCOMING_BEFORE = 11, 12, 13, 14
# A medium that yields: its permanent penetration (the set) and, for rock, the deepest penetration
# of the present loading, the surface it started from and the plastic work of the loadings before
S_MEDIUM_SET, S_MEDIUM_DEEPEST, S_MEDIUM_SURFACE, S_MEDIUM_SPENT = 15, 16, 17, 18
MEDIUM_SLOTS = (S_MEDIUM_SET, S_MEDIUM_DEEPEST, S_MEDIUM_SURFACE, S_MEDIUM_SPENT)  # `medium_state`'s order
MEDIUM_STATE = len(MEDIUM_SLOTS)
# An elastic striker: the incoming waves' displacements G at its face and at its back end (layers
# m−1, m−2), the back end's incoming rate over the last two steps (mean and slope of each: the
# free end returns it after the `back_delay`), and the contact's impulse so far
S_FACE_INCOMING, S_FACE_INCOMING_BEFORE, S_BACK_INCOMING, S_BACK_INCOMING_BEFORE = 19, 20, 21, 22
# The rate of the wave arriving at the back end: its mean and slope over step m−1, and over m−2
S_BACK_MEAN, S_BACK_SLOPE, S_BACK_MEAN_BEFORE, S_BACK_SLOPE_BEFORE = 23, 24, 25, 26
S_IMPULSE = 27
S_BACK_ENERGY = 28  # the energy of the waves beyond the striker's last node, at layer m − ½
# An anvil: its displacement and velocity, and its force on the tool's end, at layer m − 1
S_ANVIL_DISP, S_ANVIL_VELOCITY, S_ANVIL_FORCE = 29, 30, 31
# The deepest overlap a cushion was pressed to in this contact: the striker's, the anvil's
S_CONTACT_DEEPEST, S_ANVIL_CONTACT_DEEPEST = 32, 33
# The work done on the tool through its struck end in this blow, and its end force and
# displacement at the layer recorded last (`track_transferred`)
S_TRANSFERRED, S_TRANSFER_FORCE, S_TRANSFER_DISP = 34, 35, 36
S_BLOW_START = 37  # when the present blow started: a driving history's time counts from it
S_LAUNCH_VELOCITY = 38  # the present blow's striker was launched at (W1, or what a drive gave it)
# The incoming waves' displacements G at layer m−3, at each end as above: whether the wave was
# quiet before a jump (`limited_slope`)
S_INCOMING_EARLIER, S_FAR_INCOMING_EARLIER, S_FACE_INCOMING_EARLIER, S_BACK_INCOMING_EARLIER = 39, 40, 41, 42
END_SLOTS = 43
# The waves arriving at an end: the slots of their displacements G_{m−1}, G_{m−2} and G_{m−3}
INCOMING = (S_INCOMING, S_INCOMING_BEFORE, S_INCOMING_EARLIER)  # at the tool's struck end
FAR_INCOMING = (S_FAR_INCOMING, S_FAR_INCOMING_BEFORE, S_FAR_INCOMING_EARLIER)  # at its working end
FACE_INCOMING = (S_FACE_INCOMING, S_FACE_INCOMING_BEFORE, S_FACE_INCOMING_EARLIER)  # at an elastic striker's face
BACK_INCOMING = (S_BACK_INCOMING, S_BACK_INCOMING_BEFORE, S_BACK_INCOMING_EARLIER)  # at its back end

# The ends' own state over one step, where they integrate their own equations (`integrate_ends`
# fills it from the layer and the slots, the ends advance it, the new layer takes it back).
# The struck end's (`struck_end_step`): the striker's displacement and velocity, the tool's end,
# the contact force, the striker's impulse, whether in contact, the anvil's displacement, velocity
# and force on the tool, and the contacts' deepest overlaps (a cushion's).
(
    END_STRIKER_DISP,
    END_STRIKER_VELOCITY,
    END_TOOL_DISP,
    END_CONTACT_FORCE,
    END_IMPULSE,
    END_IN_CONTACT,
    END_ANVIL_DISP,
    END_ANVIL_VELOCITY,
    END_ANVIL_FORCE,
    END_CONTACT_DEEPEST,
    END_ANVIL_CONTACT_DEEPEST,
) = range(11)
STRUCK_END_STATE = 11
# The working end's (`working_end_step`): its displacement u_N, the medium's force F_m, then the
# medium's state in `medium_state`'s order.
WORK_DISP, WORK_FORCE, WORK_SET, WORK_DEEPEST, WORK_SURFACE, WORK_SPENT = range(6)
WORK_MEDIUM = (WORK_SET, WORK_DEEPEST, WORK_SURFACE, WORK_SPENT)
WORKING_END_STATE = 6

STATUS_OK, STATUS_NON_FINITE = 0, 1

# What drives the struck end (`Striker.driver`): a striker, or a given force or velocity history
NOT_DRIVEN, DRIVEN_BY_FORCE, DRIVEN_BY_VELOCITY = 0, 1, 2

# What `advance` takes, as named bundles. Numba passes a namedtuple's fields as separate values and
# reads them as registers: a bundle costs nothing in the step (typing them all costs about 3 µs a
# call of `advance`, against ~10 ms of steps a call). Build them by keyword, as `solver.controller`
# does: a bundle of another kind in the place of one does not compile.
Gravity = namedtuple("Gravity", "first last lift weight")
"""The weight of a rod's nodes from `first` to `last` (interior nodes; none when `last` < `first`):
each node's weight W_i (N) and the lift τ²·W_i/m_i it adds to the node's explicit row (`gravity.py`)."""
Tool = namedtuple(
    "Tool", "lower upper node_area area_mid uniform struck_end_area working_end_area gravity stress_chunks"
)
"""The tool on its grid (`solver.grid.Grid`): the operator's weights `lower_i`, `upper_i` of the
neighbours (all 1 when `uniform`), the nodes' areas S̄_i (`node_area·ρh` is a node's mass: half a
cell at the ends, 0 at a massless end), the cells' areas S_{i+½}, the areas at the struck and
working ends (their stresses are the end forces over them), its nodes' weight (`Gravity`) and its
interior nodes in chunks, each within one stretch of its stress envelope (`audit.stress_chunks`)."""
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
Contact = namedtuple(
    "Contact",
    "striker_mass striker_velocity stiffness exponent tension_stiffness damping impedance restitution deepest",
)
"""The struck end: the striker (m1, W1 at impact), the contact's spring `Φ'(δ) = c1·δ^(α+1)` in
contact and `c0·δ` in separation (c1, α, c0), its damper (b1), the impedance ρ·a·S of the
tool's end cell (N·s/m), and a cushion's restitution e (1: none) with the deepest overlap it was
pressed to (`laws.contact_law`; 0 as built, the struck end's state in a step)."""
Medium = namedtuple("Medium", "kind stiffness damping impedance unloading_stiffness ultimate_resistance damping_factor")
"""The working end: the medium's `MEDIUM_…` kind, its loading stiffness (c2, rock's k, or soil's
R_u/q; 0 for a free end) and damper (b2), the impedance of the tool's end cell, rock's unloading
stiffness k_u, soil's ultimate resistance R_u and Smith damping J (s/m)."""
ForceLaw = namedtuple("ForceLaw", "kind amplitude omega start duration")
"""R(t) on the striker: a `laws.FORCE_…` kind and its parameters."""
Striker = namedtuple(
    "Striker", "elastic tool rod impedance back_impedance mass back_delay weight driver signal_time signal_values"
)
"""The striker as a rod (when `elastic`): its `Tool` and `Rod` on its own grid (node 0 its impact
face, at Courant number 1 with the tool's time step), the impedances ρ·a·S of its face and back
cells, its mass, and `back_delay`: the time a wave takes there and back over the part of the striker beyond
its last node, less than 2τ (its length is rarely a whole number of cells). Under gravity a lumped
striker's `weight` m1·g (N; 0 otherwise; an elastic one's nodes carry theirs, its `Tool`'s). With
no striker a history drives the struck end (`struck_end`): `driver` (`DRIVEN_BY_…`; `NOT_DRIVEN`
with a striker), the history's instants (s from the blow's start) and values, linear between them."""
StrikerEnd = namedtuple("StrikerEnd", "elastic impedance mass weight")
"""What the struck end's integration reads of the `Striker`: its scalars alone, so that the call
passes no arrays."""
Anvil = namedtuple("Anvil", "present mass velocity contact weight")
"""A lumped body between the striker and the tool (when `present`): its mass m_a, its velocity at
impact and its `Contact` with the tool (the anvil as that contact's striker, the tool's end
impedance); the case's `Contact` is then the striker's with the anvil. Its `weight` m_a·g (N; 0
without gravity)."""
Shaft = namedtuple("Shaft", "first last resistance stiffness damping_factor inv_mass")
"""The soil along the tool's side, node by node from `first` to `last` (interior nodes; none when
`last` < `first`): each node's ultimate resistance r_i (N), its stiffness r_i/q_i (N/m), Smith's damping
factor J_i (s/m) and τ²/m_i, m_i the node's mass (`shaft.py`)."""
State = namedtuple("State", "u y ends energy striker shaft_sets increments striker_increments")
"""What a step carries to the next: the tool's layers `u` (3 × (N+1)) and the striker's face `y`
(3), the ends' slots (`S_…`), the energy terms (`energy[0, E_…]` at the last layer, `energy[1]` at
the one before), an elastic striker's layers (3 × (N_s+1); its node 0 is `y`), the shaft's sets
along the tool (N+1: each node's permanent displacement against its soil), and the explicit
scheme's increments `u^m − u^{m−1}` of the tool's and the striker's interior nodes, kept apart from
the layers (`rows.explicit_interior`)."""
Observed = namedtuple("Observed", "extremes contacts until envelope")
"""What a blow reports beyond its recordings: the extremes (`X_…`) over its duration, up to the
time `until`, the finished contact intervals (start, end; one row each, those beyond its rows
counted only), and the stress envelope: the greatest compression (row 0, as −σ) and tension
(row 1) in each stretch of the tool (`layout.ENVELOPE_BINS`), −inf where it has no node."""
Recorders = namedtuple(
    "Recorders",
    "history history_stride probe_node probe_weight probes field_u field_stress field_stride striker_u striker_stress "
    "shaft_share shaft_span shaft_history shaft_field",
)
"""Where a call records its layers: every `history_stride`-th to `history` (a column each) and
`probes` (a row each: the stress at each probe, linear between the node `probe_node` and the next
with its weight `probe_weight`), every `field_stride`-th to `field_u`/`field_stress` (a row each)
and an elastic striker's to `striker_u`/`striker_stress`; strides ≤ 0 keep nothing. The shaft's
force on each of its segments goes to `shaft_history` (a row a segment), node i's share of
segment k being `shaft_share[k, i]`, nonzero only from node `shaft_span[k, 0]` to
`shaft_span[k, 1]`, and its force on each node to `shaft_field`."""

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
        shaft_sets=np.zeros(cells + 1),
        increments=np.zeros(cells + 1),
        striker_increments=np.zeros(striker_cells + 1),
    )


def new_observed(max_contacts: int, until: float = np.inf) -> Observed:
    """Nothing observed yet, with room for `max_contacts` contact intervals, over a blow whose
    duration ends at `until` (s, the kernel's time)."""
    return Observed(
        extremes=new_extremes(),
        contacts=np.zeros((max_contacts, 2)),
        until=float(until),
        envelope=np.full((2, ENVELOPE_BINS), -np.inf),
    )


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
