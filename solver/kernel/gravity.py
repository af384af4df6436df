"""Gravity (`gravity`): the weight of a rod's nodes, a term along the tool (and an elastic striker).

Node i carries the weight W_i of its half cells, the ends' with nodes 1 and N − 1
(`grid.node_weights`: the ends keep their own equations). It enters the node's explicit row as
the lift `τ²·W_i/m_i` of the new layer, before the soil's force, which each node's row solves
with it (`shaft_on_rows`). Its work over the step, `W_i·(u^{n+1} − u^{n−1})/2`, is the form the
scheme's energy identity takes: it goes to `E_GRAVITY_WORK`, as the lumped striker's and the
anvil's weights' work does (`struck_end_step` moves them under it). The run starts at rest under
the weight (`solver.rest`, which `start_at_rest` writes into the state).
"""

from __future__ import annotations

import numpy as np

from ..compiled import compiled
from .bundles import (
    FAR_INCOMING,
    INCOMING,
    MEDIUM_SLOTS,
    S_ANVIL_CONTACT_DEEPEST,
    S_ANVIL_DISP,
    S_ANVIL_FORCE,
    S_MEDIUM_FORCE,
    Gravity,
)


def no_gravity() -> Gravity:
    """A rod without weight."""
    empty = np.zeros(0)
    return Gravity(first=1, last=0, lift=empty, weight=empty)


# The loops run over unsigned indices: a signed one makes Numba check each for wrapping around
# from the end, which keeps LLVM from vectorising them.


@compiled(inline="always")
def weigh_rows(u, increments, new, gravity):
    """The weight's lift on each node's explicit row, in row `new` of `u` and in the node's
    increment."""
    for i in range(np.uint64(gravity.first), np.uint64(gravity.last + 1)):
        u[new, i] += gravity.lift[i]
        increments[i] += gravity.lift[i]


# A function of its own, its sum free to be reordered (`reassoc`, a change of rounding only): as a
# chain of additions it cost a pile's step more than its tool's own rows.
@compiled(fastmath={"contract", "reassoc"})
def gravity_work(u, layer, gravity):
    """The weight's work over the step, `Σ W_i·(u^{n+1} − u^{n−1})/2`, the new layer final."""
    new, _, old, _ = layer
    work = 0.0
    for i in range(np.uint64(gravity.first), np.uint64(gravity.last + 1)):
        work += gravity.weight[i] * (u[new, i] - u[old, i])
    return 0.5 * work


def start_at_rest(state, rest) -> None:
    """The state before a run (`new_state`'s) at the rest `rest` (`solver.rest.Rest`): layers 0
    and −1 (rows 0 and 2) at its displacements, the shaft's sets, the medium's force and state,
    the anvil on its contact, and the waves arriving at each end as a static strain sends them
    (`incoming_wave`: G_{−1} = 0, G_0 half the end cell's stretch and G_{−2} minus that, so an
    end at rest stays there).
    `start_impact` counts the energy it stores."""
    u, ends = state.u, state.ends
    u[0] = rest.u
    u[2] = rest.u
    state.shaft_sets[:] = rest.shaft_sets
    ends[S_MEDIUM_FORCE] = rest.medium_force
    for slot, value in zip(MEDIUM_SLOTS, rest.medium_state):
        ends[slot] = value
    ends[S_ANVIL_DISP] = rest.anvil_displacement
    ends[S_ANVIL_FORCE] = rest.anvil_force
    ends[S_ANVIL_CONTACT_DEEPEST] = rest.anvil_overlap
    for (last, before, earlier), stretch in (
        (INCOMING, rest.u[1] - rest.u[0]),
        (FAR_INCOMING, rest.u[-2] - rest.u[-1]),
    ):
        ends[earlier] = -0.5 * stretch
        ends[before] = 0.0
        ends[last] = 0.5 * stretch
