"""The soil along the tool's side (`shaft`): Smith's law at each section, a term along the tool.

Each interior node i carries the soil of its share of the shaft (`grid.shaft_nodes`): an
ultimate resistance r_i, a quake q_i (its stiffness k_i = r_i/q_i) and a damping factor J_i. The
soil's force on the node, against its displacement, is

    F_i = F_s + J_i·|F_s|·u_i',    F_s = k_i·(u_i − p_i) within ±r_i,

p_i its permanent displacement (its set), which moves when |F_s| would pass r_i: the soil slips
both ways, and keeps its set from blow to blow (residual stresses). This is the toe's law
(`medium.kind = 'smith'`) made two-sided, its damping against the motion either way.

It enters the explicit scheme's interior rows as a force of layer n, which each node's own row
solves for (the rows are uncoupled): F_s at the mean of layers n ± 1 and the damper at the centred
rate `(u^{n+1} − u^{n−1})/(2τ)`, its factor J·|F_s| at layer n. A spring at layer n alone would
push the sawtooth mode past its stability limit at Courant number 1 (the tool then rings up
within a few thousand steps); at the mean of n ± 1 it stores `k/4·((u^{n+1})² + (u^n)²)`, and
the step stays stable at any stiffness. Its work over the step, `F_i·(u^{n+1} − u^{n−1})/2`, is
the term the scheme's energy identity takes, so the audit closes with it (`E_TO_SHAFT`: what the
soil took, stored, slipped and damped). The shares of the end half-cells are carried by the nodes
next to them, which keeps the ends' own equations as they are.
"""

from __future__ import annotations

import numpy as np

from ..compiled import compiled
from ..layout import E_TO_SHAFT
from .bundles import Shaft


def no_shaft() -> Shaft:
    """A tool with no soil on its side."""
    empty = np.zeros(0)
    return Shaft(first=1, last=0, resistance=empty, stiffness=empty, damping_factor=empty, inv_mass=empty)


# A function of its own, written to be vectorised: unsigned indices (a signed one is checked for
# wrapping around from the end), both of a node's outcomes computed and one selected, divisions
# left to IEEE arithmetic as in all the kernel (`compiled()`; here the one divisor that can be
# zero, a node without soil's k, only enters the outcome not selected), and its work summed in any
# order (`reassoc`, a change of rounding only). A step on a pile's shaft costs about a quarter of
# what it did node by node.
@compiled(fastmath={"contract", "reassoc"})
def shaft_on_rows(u, increments, layer, shaft, sets, energy, tau):
    """The soil's force on each interior node of layer n in the explicit rows of row `new` of `u`
    (which hold the new layer without it), each node's set `sets[i]` moved where it slips; its
    work over the step added to `E_TO_SHAFT`."""
    new, cur, old, _ = layer
    half_rate = 0.5 / tau
    work = 0.0
    for i in range(np.uint64(shaft.first), np.uint64(shaft.last + 1)):
        r, k, c = shaft.resistance[i], shaft.stiffness[i], shaft.inv_mass[i]
        before, set_, row = u[old, i], sets[i], u[new, i]
        # the damper's factor J·|F_s| at layer n; its rate, centred, is the new layer's
        damper = shaft.damping_factor[i] * min(r, abs(k * (u[cur, i] - set_))) * c * half_rate
        # u^{n+1} = A − c·(F_s + d·(u^{n+1} − u^{n−1})/(2τ)), A the row without the soil, F_s at
        # the mean of layers n ± 1: elastic, unless that passes ±r, then slipping at ±r
        elastic = 0.5 * c * k
        after = (row - c * k * (0.5 * before - set_) + damper * before) / (1.0 + elastic + damper)
        static = k * (0.5 * (after + before) - set_)
        slipping = abs(static) > r
        limit = r if static > 0.0 else -r
        slipped = (row - c * limit + damper * before) / (1.0 + damper)
        after = slipped if slipping else after
        static = limit if slipping else static
        sets[i] = 0.5 * (after + before) - static / k if slipping else set_
        u[new, i] = after
        increments[i] += after - row
        work += (static + damper / c * (after - before)) * 0.5 * (after - before)
    energy[0, E_TO_SHAFT] += work


@compiled(inline="always")
def shaft_force_at(u, row, before, i, shaft, sets, tau):
    """The soil's force on node i at the layer in `row` of `u` (`before`: the row of the layer
    before it), as recorded: F_s there, its damper at the rate from the layer before."""
    r, k = shaft.resistance[i], shaft.stiffness[i]
    static = max(-r, min(r, k * (u[row, i] - sets[i])))
    return static + shaft.damping_factor[i] * abs(static) * (u[row, i] - u[before, i]) / tau


# Each segment is summed over its own nodes only, in a function of its own so that the sum is free
# to be reordered (`reassoc`, a change of the recorded force's rounding only): every node for every
# segment, in order, cost a pile's recorded step on 512 cells 2 µs. It takes the arrays it writes,
# not the `Recorders`: a call is passed its arguments' every field, and the whole bundle cost each
# recorded layer 70 ns.
@compiled(fastmath={"contract", "reassoc"})
def record_shaft(shares, spans, history, field, column, frame, state, row, shaft, tau):
    """The soil's force on each segment into `column` of `history` (when ≥ 0; node i's share of
    segment k `shares[k, i]`, nonzero from node `spans[k, 0]` to `spans[k, 1]`) and on each node
    into row `frame` of `field` (when ≥ 0), of the layer in `row`."""
    u, sets = state.u, state.shaft_sets
    before = (row + 2) % 3
    if column >= 0:
        for k in range(shares.shape[0]):
            total = 0.0
            for i in range(np.uint64(spans[k, 0]), np.uint64(spans[k, 1] + 1)):
                total += shares[k, i] * shaft_force_at(u, row, before, i, shaft, sets, tau)
            history[k, column] = total
    if frame >= 0:
        for i in range(shaft.first, shaft.last + 1):
            field[frame, i] = shaft_force_at(u, row, before, i, shaft, sets, tau)
