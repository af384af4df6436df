"""The energy audit: the tool's energy and stresses in one vectorised pass, the scheme's and the
impedance ends' energy terms, and the largest energy the scheme made.
"""

from __future__ import annotations

import numpy as np
from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic

from ..compiled import compiled
from ..layout import (
    E_ANVIL_KINETIC,
    E_BETWEEN_BLOWS,
    E_CONTACT_POTENTIAL,
    E_DISSIPATED_CONTACT,
    E_DISSIPATED_MEDIUM,
    E_EXTERNAL_WORK,
    E_GRAVITY_WORK,
    E_LAUNCHED,
    E_MEDIUM_PLASTIC,
    E_MEDIUM_POTENTIAL,
    E_STORED_AT_REST,
    E_STRIKER_KINETIC,
    E_STRIKER_STRAIN,
    E_TO_SHAFT,
    E_TOOL_KINETIC,
    E_TOOL_STRAIN,
    E_WITHDRAWN,
    ENVELOPE_BINS,
    X_ENERGY_EXCESS,
)
from .bundles import (
    S_ANVIL_CONTACT_DEEPEST,
    S_ANVIL_DISP,
    S_ANVIL_VELOCITY,
    S_BACK_ENERGY,
    S_CONTACT_DEEPEST,
    S_POTENTIAL_BEFORE,
)
from .contact import contact_law, pressed_to
from .working_end import medium_energy, medium_state


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

# Nodes a chunk at most: enough for a chunk's vector reduction to pay, few for searching one to be
# cheap
STRESS_BLOCK = 64


def stress_chunks(cells: int, bins: int = ENVELOPE_BINS) -> np.ndarray:
    """The interior nodes 1 … N−1 (N = `cells`) in chunks of at most `STRESS_BLOCK` nodes, none
    across two of the `bins` stretches: row 0 each chunk's first node, then N; row 1 its stretch."""
    starts, stretches = [], []
    for b in range(bins):
        first, end = max(1, -(-b * cells // bins)), min(cells, -(-(b + 1) * cells // bins))
        for start in range(first, end, STRESS_BLOCK):
            starts.append(start)
            stretches.append(b)
    return np.array([starts + [cells], stretches + [bins]], dtype=np.int64)


@compiled(inline="always")
def widen(envelope, stretch, low, high):
    """Raise the envelope's `stretch` to a least stress `low` (its compression, −low) and a
    greatest `high` (its tension)."""
    envelope[0, stretch] = max(envelope[0, stretch], -low)
    envelope[1, stretch] = max(envelope[1, stretch], high)


# One pass for the energy and the stresses, in one vectorised loop; its fast-math flags:
# - `reassoc`: sums of N terms may be reordered, which changes them by rounding only;
# - `nnan`, `nsz`: min/max are plain vector instructions, without NaN or signed-zero fix-ups (LLVM
#   vectorises them beside the sums only with both). Sound: a non-finite displacement makes the
#   kinetic energy non-finite, which `advance` checks before it uses the stresses, and a stress of
#   −0 or +0 is the same record.
@compiled(fastmath={"contract", "reassoc", "nnan", "nsz"})
def tool_energy_and_stresses(
    u, new, cur, stressed, node_area, area_mid, strain_sigma, half_e_over_h, chunks, envelope, enveloped
):
    """The tool's energy terms between the layers in rows `new`, `cur` of `u` and the interior
    stress extremes of the layer in row `stressed`: `(Σ S_i·(u_i − uc_i)², Σ S_{i+½}·[σ(e_a² +
    e_b²) + (1 − 2σ)·e_a·e_b], least stress, its chunk, greatest stress, its chunk)`.

    The sums are twice the kinetic energy times τ²/(ρh) and twice the strain energy times h/E, e
    the cell strains. The stresses are `½·E/h·(u_{i+1} − u_{i−1})` at the interior nodes of that
    layer (±inf when it has none), each with the first chunk (`stress_chunks`) that holds it: a
    loop that carries an extreme's index does not vectorise, so `first_node` finds the node in the
    chunk, when it is wanted. When `enveloped`, each chunk's greatest compression and tension
    raise its stretch's in `envelope` (rows 0 and 1).
    """
    n = u.shape[1] - 1
    one = np.uint64(1)
    strain_cross = 1.0 - 2.0 * strain_sigma
    du = u[new, 0] - u[cur, 0]
    kinetic = node_area[0] * du * du
    strain = 0.0
    low, high = np.inf, -np.inf
    low_chunk = high_chunk = 0
    for k in range(chunks.shape[1] - 1):
        lo, hi = np.inf, -np.inf
        for i in range(np.uint64(chunks[0, k]), np.uint64(chunks[0, k + 1])):
            du = u[new, i] - u[cur, i]
            kinetic += node_area[i] * du * du
            ea = u[new, i] - u[new, i - one]
            eb = u[cur, i] - u[cur, i - one]
            strain += area_mid[i - one] * (strain_sigma * (ea * ea + eb * eb) + strain_cross * ea * eb)
            s = half_e_over_h * (u[stressed, i + one] - u[stressed, i - one])
            lo = fmin(lo, s)
            hi = fmax(hi, s)
        if lo < low:
            low, low_chunk = lo, k
        if hi > high:
            high, high_chunk = hi, k
        if enveloped:
            widen(envelope, chunks[1, k], lo, hi)
    du = u[new, n] - u[cur, n]
    kinetic += node_area[n] * du * du
    ea = u[new, n] - u[new, n - 1]
    eb = u[cur, n] - u[cur, n - 1]
    strain += area_mid[n - 1] * (strain_sigma * (ea * ea + eb * eb) + strain_cross * ea * eb)
    return kinetic, strain, low, low_chunk, high, high_chunk


@compiled(fastmath={"nnan"})
def first_node(u, row, half_e_over_h, chunks, chunk, value):
    """The first node of chunk `chunk` (`stress_chunks`) where the stress is `value` (its last if
    none)."""
    one = np.uint64(1)
    start, last = chunks[0, chunk], chunks[0, chunk + 1] - 1
    first = last
    for i in range(np.uint64(start), np.uint64(last + 1)):
        found = half_e_over_h * (u[row, i + one] - u[row, i - one]) == value
        first = min(first, np.int64(i) if found else last)
    return first


# --- Energy audit, extremes, recording ------------------------------------------------------------


@compiled(inline="always")
def audit_scheme_energy(state, layer, rec, r_n, overlaps, potential, contact, medium, tool, rod, step, envelope):
    """The energy terms of the new layer at m − ½, in the form each scheme conserves (or
    dissipates), into `energy[0]`; returns the balance (stored + dissipated − input: > 0 is energy
    created) and the interior stress extremes of the layer in row `rec` (the one recorded), which
    the same pass along the tool finds (`tool_energy_and_stresses`), raising the stretches of
    `envelope` = (the stress envelope, whether this layer counts). `r_n`: R(t_n) of the step;
    `overlaps`: the layers' before it; `potential`: Φ of the new layer."""
    u, y, ends, energy = state.u, state.y, state.ends, state.energy
    new, cur, old, ref = layer
    delta = y[new] - u[new, 0]
    n, tau = step.n, rod.time_step
    _, spring_weight, damper_factor, _ = step.boundary
    dy = y[new] - y[cur]
    striker_kinetic = 0.5 * contact.striker_mass * dy * dy * step.inv_tau2
    tool_kinetic, tool_strain, low, low_chunk, high, high_chunk = tool_energy_and_stresses(
        u,
        new,
        cur,
        rec,
        tool.node_area,
        tool.area_mid,
        step.strain_sigma,
        step.half_e_over_h,
        tool.stress_chunks,
        *envelope,
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
        + energy[0, E_TO_SHAFT]
        - step.initial_energy
        - energy[0, E_EXTERNAL_WORK]
    )
    return balance, (low, low_chunk, high, high_chunk)


@compiled(inline="always")
def audit_impedance_energy(state, layer, flows, velocity, contact, striker, anvil, medium, tool, step, envelope):
    """As `audit_scheme_energy` for the ends that integrate their own equations: the ends' terms
    at layer m (`flows`: the work of R, what the dampers b1, b2 dissipated and the work of the
    striker's and the anvil's weights over the step), the
    tool's and an elastic striker's at m − ½ (the form the explicit scheme conserves); the balance
    compares them at m − ½."""
    u, y, ends, energy, striker_u = state.u, state.y, state.ends, state.energy, state.striker
    new, cur, _, _ = layer
    n = step.n
    work, dissipated, dissipated_far, lifted = flows
    if anvil.present:
        anvil_at = ends[S_ANVIL_DISP]
        velocity_a = ends[S_ANVIL_VELOCITY]
        potential = (
            contact_law(y[new] - anvil_at, pressed_to(contact, ends[S_CONTACT_DEEPEST]))[1]
            + contact_law(anvil_at - u[new, 0], pressed_to(anvil.contact, ends[S_ANVIL_CONTACT_DEEPEST]))[1]
        )
        energy[0, E_ANVIL_KINETIC] = 0.5 * anvil.mass * velocity_a * velocity_a
    else:
        potential = contact_law(y[new] - u[new, 0], pressed_to(contact, ends[S_CONTACT_DEEPEST]))[1]
    stored, plastic = medium_energy(u[new, n], medium_state(ends), medium)
    tool_kinetic, tool_strain, low, low_chunk, high, high_chunk = tool_energy_and_stresses(
        u,
        new,
        cur,
        new,
        tool.node_area,
        tool.area_mid,
        step.strain_sigma,
        step.half_e_over_h,
        tool.stress_chunks,
        *envelope,
    )
    energy[0, E_EXTERNAL_WORK] += work
    energy[0, E_GRAVITY_WORK] += lifted
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
        + energy[0, E_TO_SHAFT]  # at m − ½, as the tool's
        - step.initial_energy
        - step.anvil_energy
        - energy[0, E_STORED_AT_REST]
        # the tool's weights' work at m − ½, the striker's and the anvil's at m: half a step back
        - energy[0, E_GRAVITY_WORK]
        + 0.5 * lifted
        + energy[0, E_WITHDRAWN]
        + energy[0, E_BETWEEN_BLOWS]
        - energy[0, E_LAUNCHED]
    )
    if striker.elastic:
        s_tool, s_rod = striker.tool, striker.rod
        e_over_h = s_rod.youngs_modulus / s_rod.cell_length
        kinetic, strain, _, _, _, _ = tool_energy_and_stresses(
            striker_u,
            new,
            cur,
            new,
            s_tool.node_area,
            s_tool.area_mid,
            step.strain_sigma,
            0.5 * e_over_h,
            s_tool.stress_chunks,
            envelope[0],
            False,  # the tool's envelope only
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
    return balance, (low, low_chunk, high, high_chunk)


@compiled(inline="always")
def track_energy_excess(extremes, balance):
    """Whether the energy balance is finite; the largest energy the scheme created so far."""
    if not abs(balance) < 1e300:
        return False
    if balance > extremes[X_ENERGY_EXCESS]:
        extremes[X_ENERGY_EXCESS] = balance
    return True
