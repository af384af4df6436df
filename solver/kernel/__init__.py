"""The time-stepping kernel: every scheme of `schemes.py` as one tridiagonal solve a step.

A package of modules, each with one job: `bundles` (what a step takes and carries, by name),
`rows` (the tool's rows and their sweep), `contact` (the contact law and R(t)), `struck_end` and
`working_end` (what the tool touches: the striker, an anvil, the media), `shaft` (the soil along
the tool's side, a term along the tool), `gravity` (the weight of the tool's nodes, another), `audit` (the energy), `recording` (the extremes,
contacts, histories, probes and fields) and `step` (`advance`: the phases of a step in order). This module names what the controller, the tests and the benches
use.

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

from ..laws import FORCE_ABS_SINE, FORCE_NONE, FORCE_PULSE, FORCE_SINE
from ..layout import (
    E_CONTACT_POTENTIAL,
    E_DISSIPATED_CONTACT,
    E_DISSIPATED_MEDIUM,
    E_EXTERNAL_WORK,
    E_MEDIUM_POTENTIAL,
    E_STRIKER_KINETIC,
    E_TOOL_KINETIC,
    E_TOOL_STRAIN,
    X_CO_IMPACT,
    X_CONTACTS,
    X_ENERGY_EXCESS,
    X_MAX_COMPRESSION,
    X_MAX_TENSION,
    X_PEAK_FORCE,
    X_PEAK_FORCE_TIME,
    X_REBOUND_VELOCITY,
)
from .audit import first_node, stress_chunks, tool_energy_and_stresses
from .bundles import (
    DRIVEN_BY_FORCE,
    DRIVEN_BY_VELOCITY,
    MEDIUM_BILINEAR,
    MEDIUM_LINEAR,
    MEDIUM_SMITH,
    MIN_SEGMENT,
    NOT_DRIVEN,
    S_ANVIL_DISP,
    S_CONTACT_START,
    S_FORCE_BEFORE,
    S_FORCE_BEFORE_THAT,
    S_IMPULSE,
    S_IN_CONTACT,
    S_LAUNCH_VELOCITY,
    S_MEDIUM_SET,
    S_STRIKER_VELOCITY,
    SEGMENTS,
    STATUS_NON_FINITE,
    STATUS_OK,
    Anvil,
    Contact,
    ForceLaw,
    Gravity,
    Medium,
    Observed,
    Recorders,
    Rod,
    Shaft,
    State,
    Striker,
    Tool,
    ToolRows,
    Weights,
    boundary_weights,
    new_observed,
    new_state,
)
from .gravity import no_gravity, start_at_rest
from .rows import factor_tool_rows, segment_layout, substitute_toward_working_end, sweep_toward_struck_end
from .shaft import no_shaft
from .step import advance, rest_tool, start_blow
from .struck_end import struck_end_step

__all__ = [
    "DRIVEN_BY_FORCE",
    "DRIVEN_BY_VELOCITY",
    "NOT_DRIVEN",
    "Anvil",
    "Contact",
    "E_CONTACT_POTENTIAL",
    "E_DISSIPATED_CONTACT",
    "E_DISSIPATED_MEDIUM",
    "E_EXTERNAL_WORK",
    "E_MEDIUM_POTENTIAL",
    "E_STRIKER_KINETIC",
    "E_TOOL_KINETIC",
    "E_TOOL_STRAIN",
    "FORCE_ABS_SINE",
    "FORCE_NONE",
    "FORCE_PULSE",
    "FORCE_SINE",
    "ForceLaw",
    "Gravity",
    "MEDIUM_BILINEAR",
    "MEDIUM_LINEAR",
    "MEDIUM_SMITH",
    "MIN_SEGMENT",
    "Medium",
    "Observed",
    "Recorders",
    "Rod",
    "SEGMENTS",
    "STATUS_NON_FINITE",
    "STATUS_OK",
    "S_CONTACT_START",
    "S_FORCE_BEFORE",
    "S_FORCE_BEFORE_THAT",
    "S_IN_CONTACT",
    "S_MEDIUM_SET",
    "S_ANVIL_DISP",
    "S_IMPULSE",
    "S_LAUNCH_VELOCITY",
    "S_STRIKER_VELOCITY",
    "Shaft",
    "State",
    "Striker",
    "Tool",
    "ToolRows",
    "Weights",
    "X_CONTACTS",
    "X_CO_IMPACT",
    "X_ENERGY_EXCESS",
    "X_MAX_COMPRESSION",
    "X_MAX_TENSION",
    "X_PEAK_FORCE",
    "X_PEAK_FORCE_TIME",
    "X_REBOUND_VELOCITY",
    "advance",
    "boundary_weights",
    "factor_tool_rows",
    "first_node",
    "new_observed",
    "new_state",
    "no_gravity",
    "no_shaft",
    "segment_layout",
    "start_at_rest",
    "rest_tool",
    "start_blow",
    "stress_chunks",
    "struck_end_step",
    "substitute_toward_working_end",
    "sweep_toward_struck_end",
    "tool_energy_and_stresses",
]
