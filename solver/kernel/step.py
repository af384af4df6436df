"""The step: `advance` runs a chunk of steps, each its phases in order; a blow's start and the
striker's launch.
"""

from __future__ import annotations

import numpy as np
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic

from ..compiled import compiled
from ..layout import (
    E_ANVIL_KINETIC,
    E_BETWEEN_BLOWS,
    E_CONTACT_POTENTIAL,
    E_GRAVITY_WORK,
    E_LAUNCHED,
    E_MEDIUM_AT_REST,
    E_MEDIUM_PLASTIC,
    E_MEDIUM_POTENTIAL,
    E_STORED_AT_REST,
    E_STRIKER_KINETIC,
    E_STRIKER_STRAIN,
    E_TOOL_KINETIC,
    E_TOOL_STRAIN,
    E_WITHDRAWN,
    ENERGY_SLOTS,
    X_FAILED_TIME,
    X_MAX_PENETRATION,
    X_SET,
)
from .audit import audit_impedance_energy, audit_scheme_energy, tool_energy_and_stresses, track_energy_excess
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
    FACE_INCOMING,
    FAR_INCOMING,
    INCOMING,
    MEDIUM_BILINEAR,
    MEDIUM_SLOTS,
    MEDIUM_STATE,
    NOT_DRIVEN,
    S_ANVIL_CONTACT_DEEPEST,
    S_ANVIL_DISP,
    S_ANVIL_FORCE,
    S_ANVIL_VELOCITY,
    S_BACK_ENERGY,
    S_BACK_MEAN,
    S_BACK_MEAN_BEFORE,
    S_BACK_SLOPE,
    S_BACK_SLOPE_BEFORE,
    S_BLOW_START,
    S_CONTACT_DEEPEST,
    S_CONTACT_START,
    S_FORCE_BEFORE,
    S_IMPULSE,
    S_IN_CONTACT,
    S_INCOMING,
    S_INCOMING_BEFORE,
    S_LAUNCH_VELOCITY,
    S_MEDIUM_FORCE,
    S_MEDIUM_FORCE_BEFORE,
    S_MEDIUM_FORCE_EARLIER,
    S_MEDIUM_SET,
    S_POTENTIAL_BEFORE,
    S_POTENTIAL_BEFORE_THAT,
    S_STRIKER_VELOCITY,
    S_TRANSFERRED,
    STATUS_NON_FINITE,
    STATUS_OK,
    STRUCK_END_STATE,
    WORK_DISP,
    WORK_FORCE,
    WORK_MEDIUM,
    WORKING_END_STATE,
    Layers,
    Overlaps,
    Recorded,
    StepConstants,
    StrikerEnd,
    boundary_weights,
)
from .contact import contact_law, external_force, launched_at, pressed_to
from .driven_end import driven_end_step, driven_force, piece
from .gravity import gravity_work
from .recording import (
    between,
    layer_at_end,
    record_fields,
    record_history,
    record_probes,
    track_contact,
    track_end_forces,
    track_ends_between_layers,
    track_overlap,
    track_stress_extremes,
    track_stresses_at_end,
    track_transferred,
)
from .rows import back_substitute, explicit_interior, right_hand_sides, segment_layout, sweep
from .shaft import record_shaft, shaft_on_rows
from .struck_end import free_back_end, incoming_wave, mean_velocity, solve_struck_end, struck_end_step, struck_forces
from .working_end import fresh_rock, medium_energy, medium_state, working_end_force, working_end_row, working_end_step

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
            state.striker_increments[i] = velocity * tau
        for last, before, earlier in (FACE_INCOMING, BACK_INCOMING):
            ends[last] = 0.0  # G of the layer in `row` (only its differences count)
            ends[before] = -0.5 * velocity * tau
            ends[earlier] = -velocity * tau  # the same wave the step before
        for mean, slope in ((S_BACK_MEAN, S_BACK_SLOPE), (S_BACK_MEAN_BEFORE, S_BACK_SLOPE_BEFORE)):
            ends[mean] = 0.5 * velocity
            ends[slope] = 0.0
        ends[S_BACK_ENERGY] = striker.back_impedance * 0.25 * velocity * velocity * striker.back_delay


@compiled(inline="always")
def rest_anvil(state, row, anvil):
    """Under gravity a helmet (the anvil) rests on the tool between blows: it is set, still, on
    its contact pressed by its weight, `Φ'(δ) = c1·δ^(α+1) = m_a·g`; what it had (its energy and
    its contact's) is withdrawn, what it has at rest launched."""
    u, ends, energy = state.u, state.ends, state.energy
    end = anvil.contact
    before = contact_law(ends[S_ANVIL_DISP] - u[row, 0], pressed_to(end, ends[S_ANVIL_CONTACT_DEEPEST]))[1]
    overlap = (anvil.weight / end.stiffness) ** (1.0 / (end.exponent + 1.0))
    ends[S_ANVIL_DISP] = u[row, 0] + overlap
    ends[S_ANVIL_CONTACT_DEEPEST] = overlap
    ends[S_ANVIL_FORCE] = anvil.weight
    after = contact_law(overlap, pressed_to(end, overlap))[1]
    energy[0, E_WITHDRAWN] += before
    energy[0, E_LAUNCHED] += after
    energy[0, E_CONTACT_POTENTIAL] += after - before


@compiled()
def rest_tool(m, state, contact, anvil):
    """Between a hammer's blows the tool comes to rest on the medium, its leftover waves spent
    (as the feed that holds a drill's rod to the rock spends them in the flight): every node of
    layer m and the two before at the medium's set, still and unstrained, the medium unloaded
    there (`fresh_rock` then meets the next blow from it), an anvil on the struck end with no
    overlap, pushing back a striker it would overlap. What the tool, the medium's spring and the
    contacts held then (the striker's, as the struck end moved), is `E_BETWEEN_BLOWS`. Held so, the tool
    had no weight or shaft to keep forces in it (`Case._a_hammer_at_work`)."""
    u, y, ends, energy = state.u, state.y, state.ends, state.energy
    row = m % 3
    at = ends[S_MEDIUM_SET]
    pressed = pressed_to(contact, ends[S_CONTACT_DEEPEST])
    struck = ends[S_ANVIL_DISP] if anvil.present else u[row, 0]
    contacts_before = contact_law(y[row] - struck, pressed)[1]
    if anvil.present:
        end = anvil.contact
        contacts_before += contact_law(struck - u[row, 0], pressed_to(end, ends[S_ANVIL_CONTACT_DEEPEST]))[1]
        ends[S_ANVIL_DISP] = at
        ends[S_ANVIL_CONTACT_DEEPEST] = 0.0
        ends[S_ANVIL_FORCE] = 0.0
    # the tool, settling, pushes back a striker it would overlap: it starts its flight touching
    behind = y[row] - at
    if behind > 0.0:
        y[:] -= behind
        state.striker[:, :] -= behind
    contacts_after = contact_law(y[row] - at, pressed)[1]
    energy[0, E_BETWEEN_BLOWS] += (
        energy[0, E_TOOL_KINETIC]
        + energy[0, E_TOOL_STRAIN]
        + energy[0, E_MEDIUM_POTENTIAL]
        + contacts_before
        - contacts_after
    )
    energy[0, E_TOOL_KINETIC] = energy[0, E_TOOL_STRAIN] = energy[0, E_MEDIUM_POTENTIAL] = 0.0
    energy[0, E_CONTACT_POTENTIAL] += contacts_after - contacts_before
    u[:, :] = at
    state.increments[:] = 0.0
    for last, before, earlier in (INCOMING, FAR_INCOMING):  # no wave arrives at either end
        ends[last] = ends[before] = ends[earlier] = 0.0
    ends[S_MEDIUM_FORCE] = ends[S_MEDIUM_FORCE_BEFORE] = ends[S_MEDIUM_FORCE_EARLIER] = 0.0


@compiled()
def start_blow(m, state, observed, contact, striker, anvil, medium, tau, velocity):
    """The next blow, from layer m (the last one computed): the striker, withdrawn with what it
    had left (its energy and the contact's, `E_WITHDRAWN`), is launched again at `velocity` (W1,
    or what a hammer's drive gave it) where it
    strikes (the struck end, or the anvil, which stays where it is and starts again at its own
    velocity, or under gravity rests on the tool: `rest_anvil`) (`E_LAUNCHED`); a contact still
    open closes at t_m and the new one opens there; a history driving the struck end starts
    again. Rock meets the blow fresh (`fresh_rock`)."""
    u, y, ends, energy = state.u, state.y, state.ends, state.energy
    if medium.kind == MEDIUM_BILINEAR:
        rock = fresh_rock(u[m % 3, u.shape[1] - 1], medium_state(ends), medium)
        for k in range(MEDIUM_STATE):
            ends[MEDIUM_SLOTS[k]] = rock[k]
    row, row_before = m % 3, (m - 1) % 3
    t = m * tau
    if anvil.weight > 0.0:
        rest_anvil(state, row, anvil)
    struck = ends[S_ANVIL_DISP] if anvil.present else u[row, 0]
    potential = contact_law(y[row] - struck, pressed_to(contact, ends[S_CONTACT_DEEPEST]))[1]
    ends[S_CONTACT_DEEPEST] = 0.0  # the new striker meets its cushion unpressed
    ends[S_TRANSFERRED] = 0.0  # each blow's transferred energy its own
    energy[0, E_WITHDRAWN] += (
        energy[0, E_STRIKER_KINETIC] + energy[0, E_STRIKER_STRAIN] + potential + energy[0, E_ANVIL_KINETIC]
    )
    if ends[S_IN_CONTACT] != 0.0:  # open where the blow's duration ended: closed there
        track_contact(
            ends,
            observed,
            min(t, observed.until),
            mean_velocity(ends[S_IMPULSE], launched_at(contact, ends[S_LAUNCH_VELOCITY]), striker)
            if striker.elastic
            else ends[S_STRIKER_VELOCITY],
            np.nan,  # withdrawn, not parted
            False,
            tau,
        )
    launch_striker(state, row, row_before, struck, launched_at(contact, velocity), striker, tau)
    ends[S_LAUNCH_VELOCITY] = velocity  # an elastic striker's mean velocity counts from this blow's
    ends[S_BLOW_START] = t
    launched = 0.5 * contact.striker_mass * velocity * velocity
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
    ends[S_IN_CONTACT] = 1.0 if striker.driver == NOT_DRIVEN else 0.0
    ends[S_CONTACT_START] = t


@compiled(inline="always")
def start_impact(state, observed, layer, t, tool, rod, weights, contact, striker, anvil, medium, step):
    """Layer 0 by (5), (6): the tool at rest (layers 0 and −1, rows 0 and 2, as the state holds
    them: unloaded, or under gravity as `gravity.start_at_rest` set them), the striker moving at
    W1 where it strikes, δ(0) = 0 (in contact from the first instant), an anvil there between
    them moving at its own velocity; and the energy the state at rest stores (`E_STORED_AT_REST`,
    the medium's share `E_MEDIUM_AT_REST`). Returns layer 0 as recorded."""
    u, ends, energy = state.u, state.ends, state.energy
    striker_velocity = contact.striker_velocity
    u0 = u[layer.new, 0]
    struck = ends[S_ANVIL_DISP] if anvil.present else u0
    launch_striker(state, layer.new, 2, struck, contact, striker, rod.time_step)
    ends[S_LAUNCH_VELOCITY] = striker_velocity
    ends[S_IN_CONTACT] = 1.0 if striker.driver == NOT_DRIVEN else 0.0
    ends[S_CONTACT_START] = 0.0
    ends[S_BLOW_START] = 0.0
    # Φ(δ⁰) = Φ(0) = 0; the state before impact counts 0 too: no link acts yet.
    ends[S_POTENTIAL_BEFORE] = 0.0
    ends[S_POTENTIAL_BEFORE_THAT] = 0.0
    ends[S_ANVIL_VELOCITY] = anvil.velocity
    energy[0, E_ANVIL_KINETIC] = step.anvil_energy
    stored, plastic = medium_energy(u[layer.new, step.n], medium_state(ends), medium)
    resting = 0.0  # the anvil's contact, pressed by its weight
    if anvil.present:
        resting = contact_law(ends[S_ANVIL_DISP] - u0, pressed_to(anvil.contact, ends[S_ANVIL_CONTACT_DEEPEST]))[1]
    # the tool at rest: its interior's stresses count for no extreme (`AT_REST`)
    strain = tool_energy_and_stresses(
        u,
        layer.new,
        2,
        layer.new,
        tool.node_area,
        tool.area_mid,
        step.strain_sigma,
        step.half_e_over_h,
        tool.stress_chunks,
        observed.envelope,
        False,
    )[1]
    energy[0, E_MEDIUM_POTENTIAL] = stored
    energy[0, E_MEDIUM_PLASTIC] = plastic
    energy[0, E_CONTACT_POTENTIAL] = resting
    energy[0, E_STORED_AT_REST] = strain * 0.5 * step.e_over_h + stored + plastic + resting
    energy[0, E_MEDIUM_AT_REST] = stored + plastic
    if weights.impedance_ends:
        # the waves a static strain sends to the struck end (`gravity.start_at_rest`)
        resting_wave = (ends[S_INCOMING] - ends[S_INCOMING_BEFORE]) / rod.time_step
        if striker.driver == NOT_DRIVEN:
            contact_force, end_force = struck_forces(
                (struck, striker_velocity, struck, anvil.velocity, u0),
                resting_wave,
                0.5 * striker_velocity,
                contact,
                striker,
                anvil,
            )
        else:
            inside, value, _ = piece(0.0, striker)
            contact_force = end_force = driven_force(inside, value, resting_wave, contact.impedance, striker)[0]
        energy[0, E_STRIKER_KINETIC] = step.initial_energy
    else:
        contact_force = end_force = contact.damping * striker_velocity
    ends[S_ANVIL_FORCE] = end_force
    return Recorded(
        row=layer.new,
        time=t,
        velocity=striker_velocity,
        contact_force=contact_force,
        medium_force=ends[S_MEDIUM_FORCE],
        struck_end_stress=-end_force / tool.struck_end_area,
        working_end_stress=-ends[S_MEDIUM_FORCE] / tool.working_end_area,
    )


@compiled(inline="always")
def integrate_ends(state, observed, layer, t, tool, rod, contact, striker, anvil, medium, force, scratch, step):
    """The ends that integrate their own equations, over the step to `t`: the waves arriving at
    them, then the striker, the anvil and the struck end (`struck_end_step`), an elastic striker's
    back end (`free_back_end`) and the working end (`working_end_step`), with the contacts and the
    end forces' extremes their substeps see. Returns whether the new ends are finite (they are
    written to the new layer only then), the striker's velocity, the contact force, the force on
    the tool's struck end (the anvil's, or the contact's), the medium's, and `(work of R,
    dissipated by the contacts, by the medium, work of the striker's and the anvil's weights)`
    over the step. `scratch`: room for the struck
    end's and the working end's states and the events."""
    u, y, ends, striker_u = state.u, state.y, state.ends, state.striker
    new, cur, _, _ = layer
    n, tau = step.n, rod.time_step
    end_state, far_state, events = scratch
    contact = launched_at(contact, ends[S_LAUNCH_VELOCITY])  # an elastic striker's mean velocity counts from it
    v_in, v_slope = incoming_wave(u, layer, 1, 0, ends, INCOMING, tau)
    v_far, far_slope = incoming_wave(u, layer, n - 1, n, ends, FAR_INCOMING, tau)
    face_in, face_slope = 0.0, 0.0
    if striker.elastic:
        face_in, face_slope = incoming_wave(striker_u, layer, 1, 0, ends, FACE_INCOMING, tau)
    lifted_from = striker.weight * y[cur] + anvil.weight * ends[S_ANVIL_DISP]
    end_state[END_STRIKER_DISP] = y[cur]
    end_state[END_STRIKER_VELOCITY] = ends[S_STRIKER_VELOCITY]
    end_state[END_TOOL_DISP] = u[cur, 0]
    end_state[END_CONTACT_FORCE] = ends[S_FORCE_BEFORE]
    end_state[END_IMPULSE] = ends[S_IMPULSE]
    end_state[END_IN_CONTACT] = ends[S_IN_CONTACT]
    end_state[END_ANVIL_DISP] = ends[S_ANVIL_DISP]
    end_state[END_ANVIL_VELOCITY] = ends[S_ANVIL_VELOCITY]
    end_state[END_ANVIL_FORCE] = ends[S_ANVIL_FORCE]
    end_state[END_CONTACT_DEEPEST] = ends[S_CONTACT_DEEPEST]
    end_state[END_ANVIL_CONTACT_DEEPEST] = ends[S_ANVIL_CONTACT_DEEPEST]
    if striker.driver == NOT_DRIVEN:
        striker_end = StrikerEnd(
            elastic=striker.elastic, impedance=striker.impedance, mass=striker.mass, weight=striker.weight
        )
        work, dissipated, crossings, contact_range, end_range = struck_end_step(
            t - tau, tau, end_state, (v_in, v_slope, face_in, face_slope), contact, striker_end, anvil, force, events
        )
    else:
        work, dissipated, crossings, contact_range, end_range = driven_end_step(
            t - tau, tau, end_state, v_in, v_slope, contact, striker, ends[S_BLOW_START]
        )
    far_state[WORK_DISP] = u[cur, n]
    far_state[WORK_FORCE] = ends[S_MEDIUM_FORCE]
    for k in range(MEDIUM_STATE):
        far_state[WORK_MEDIUM[k]] = ends[MEDIUM_SLOTS[k]]
    dissipated_far, working_range = working_end_step(tau, far_state, v_far, far_slope, medium)
    track_ends_between_layers(observed, contact_range, end_range, working_range, t, tool, rod, step)
    # the weights' work on the lumped striker and the anvil, as they moved under it
    lifted = striker.weight * end_state[END_STRIKER_DISP] + anvil.weight * end_state[END_ANVIL_DISP] - lifted_from
    flows = (work, dissipated, dissipated_far, lifted)
    if not (
        abs(end_state[END_STRIKER_DISP]) < 1e300
        and abs(end_state[END_TOOL_DISP]) < 1e300
        and abs(end_state[END_ANVIL_DISP]) < 1e300
        and abs(far_state[WORK_DISP]) < 1e300
    ):
        return False, 0.0, 0.0, 0.0, 0.0, flows
    y[new] = end_state[END_STRIKER_DISP]
    u[new, 0] = end_state[END_TOOL_DISP]
    u[new, n] = far_state[WORK_DISP]
    for k in range(MEDIUM_STATE):
        ends[MEDIUM_SLOTS[k]] = far_state[WORK_MEDIUM[k]]
    ends[S_STRIKER_VELOCITY] = end_state[END_STRIKER_VELOCITY]
    ends[S_IMPULSE] = end_state[END_IMPULSE]
    ends[S_ANVIL_DISP] = end_state[END_ANVIL_DISP]
    ends[S_ANVIL_VELOCITY] = end_state[END_ANVIL_VELOCITY]
    ends[S_ANVIL_FORCE] = end_state[END_ANVIL_FORCE]
    ends[S_CONTACT_DEEPEST] = end_state[END_CONTACT_DEEPEST]
    ends[S_ANVIL_CONTACT_DEEPEST] = end_state[END_ANVIL_CONTACT_DEEPEST]
    velocity = end_state[END_STRIKER_VELOCITY]
    if striker.elastic:
        striker_u[new, 0] = y[new]
        free_back_end(striker_u, layer, ends, striker, tau)
        velocity = mean_velocity(end_state[END_IMPULSE], contact, striker)
    for k in range(crossings):
        track_contact(ends, observed, events[k, 0], events[k, 1], events[k, 3], events[k, 2] > 0.0, tau)
    return True, velocity, end_state[END_CONTACT_FORCE], end_state[END_ANVIL_FORCE], far_state[WORK_FORCE], flows


# `contract` lets LLVM fuse `a·b + c` into one multiply-add (one rounding instead of two) where the
# CPU has one: each of the two recurrences along the tool then has a single operation a node on its
# critical path. No other fast-math assumption is made (NaN, infinities, reordering): the checks for
# non-finite values rely on that.
AT_REST = (np.inf, 0, -np.inf, 0)  # the tool's interior at rest: only the end stresses count


@compiled(inline="always")
def recorded_at(row, time, velocity, contact_force, end_force, medium_force, tool):
    """What a layer records: its row and time, the striker's velocity, the contact's and the
    medium's forces, and the stresses the end forces make at the tool's ends."""
    return Recorded(
        row=row,
        time=time,
        velocity=velocity,
        contact_force=contact_force,
        medium_force=medium_force,
        struck_end_stress=-end_force / tool.struck_end_area,
        working_end_stress=-medium_force / tool.working_end_area,
    )


@compiled(inline="always")
def impedance_ends_step(state, observed, layer, t, tool, rod, contact, striker, anvil, medium, force, scratch, step):
    """The ends that integrate their own equations, then the energy audit: whether all stayed
    finite, what the layer records, the interior's stress extremes and the energy balance."""
    finite, velocity, contact_force, end_force, medium_force, flows = integrate_ends(
        state, observed, layer, t, tool, rod, contact, striker, anvil, medium, force, uncounted(scratch), step
    )
    recorded = recorded_at(layer.new, t, velocity, contact_force, end_force, medium_force, tool)
    if not finite:
        return False, recorded, AT_REST, 0.0
    balance, interior = audit_impedance_energy(
        state,
        layer,
        flows,
        velocity,
        contact,
        striker,
        anvil,
        medium,
        tool,
        step,
        (observed.envelope, t <= observed.until),
    )
    return True, recorded, interior, balance


@compiled(inline="always")
def scheme_ends_step(state, observed, layer, m, t, tool, rows, rod, weights, contact, medium, force, step):
    """The paper's rows at the ends: the sweep, the striker and struck-end rows with the contact
    law, the substitution and the medium's force, then the energy audit and the contact's
    tracking; returns as `impedance_ends_step` does."""
    u, y, ends = state.u, state.y, state.ends
    new, cur, old, ref = layer
    tau = rod.time_step
    overlaps = Overlaps(cur=y[cur] - u[cur, 0], old=y[old] - u[old, 0], ref=y[ref] - u[ref, 0])
    r_n = external_force((m - 1) * tau, force)  # R(t_n), explicit in row (11)
    q_1, carries = sweep(u, layer, rows, step)
    y_new, u0_new, contact_force = solve_struck_end(
        state, layer, overlaps, (rows.p[1], q_1), r_n, contact, rod, weights, step
    )
    if not (abs(y_new) < 1e300 and abs(u0_new) < 1e300):
        return False, recorded_at(new, t, 0.0, 0.0, 0.0, 0.0, tool), AT_REST, 0.0
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
        velocity = contact.striker_velocity if m == 1 else (3.0 * y_new - 4.0 * y[cur] + y[old]) / (2.0 * tau)
    balance, interior = audit_scheme_energy(
        state,
        layer,
        rec,
        r_n,
        overlaps,
        potential,
        contact,
        medium,
        tool,
        rod,
        step,
        (observed.envelope, t_rec <= observed.until),
    )
    ends[S_POTENTIAL_BEFORE_THAT] = ends[S_POTENTIAL_BEFORE]
    ends[S_POTENTIAL_BEFORE] = potential
    track_overlap(ends, observed, overlaps, (y_new, u0_new), m, t, velocity, tau)
    return True, recorded_at(rec, t_rec, velocity, contact_force, contact_force, medium_force, tool), interior, balance


@compiled(inline="always")
def record_layer(
    state,
    observed,
    recorders,
    recorded,
    interior,
    m_rec,
    n_hist,
    n_field,
    tool,
    rod,
    striker,
    anvil,
    force,
    shaft,
    step,
):
    """The recorded layer's extremes, and its history, probes and fields when their strides take
    it: returns the rows of history and of fields written so far.

    A blow's extremes are those of its duration (`observed.until`): its last layer can lie up to a
    step beyond, where a quantity still rising would be read too high, and on every grid of a
    doubling ladder at the same instant. Past it, they see the layer at the duration's end."""
    u, ends, extremes, until = state.u, state.ends, observed.extremes, observed.until
    seen, weight = recorded, 1.0
    if recorded.time <= until:
        track_stress_extremes(observed, u, recorded, interior, tool, rod, step)
        extremes[X_MAX_PENETRATION] = max(extremes[X_MAX_PENETRATION], u[recorded.row, step.n])
        extremes[X_SET] = ends[S_MEDIUM_SET]
    else:
        weight = 1.0 - (recorded.time - until) / rod.time_step
        seen = layer_at_end(recorded, ends, weight, until, tool)
        track_stresses_at_end(observed, u, seen, weight, tool, rod, step)
        reached = between(u[(recorded.row + 2) % 3, step.n], u[recorded.row, step.n], weight)
        extremes[X_MAX_PENETRATION] = max(extremes[X_MAX_PENETRATION], reached)
        extremes[X_SET] = between(extremes[X_SET], ends[S_MEDIUM_SET], weight)  # the layer before's, then
    track_end_forces(extremes, ends, recorded, seen, until, m_rec, tool, rod, step, not anvil.present)
    track_transferred(extremes, ends, recorded, u, m_rec, tool, weight)
    column = frame = -1
    if recorders.history_stride > 0 and m_rec % recorders.history_stride == 0:
        record_history(recorders, n_hist, state, recorded, m_rec, force, anvil, step)
        record_probes(recorders, n_hist, u, recorded, step)
        column, n_hist = n_hist, n_hist + 1
    if recorders.field_stride > 0 and m_rec % recorders.field_stride == 0:
        record_fields(recorders, n_field, state, recorded, striker, step)
        frame, n_field = n_field, n_field + 1
    if (column >= 0 or frame >= 0) and shaft.last >= shaft.first:
        record_shaft(
            recorders.shaft_share,
            recorders.shaft_span,
            recorders.shaft_history,
            recorders.shaft_field,
            column,
            frame,
            state,
            recorded.row,
            shaft,
            rod.time_step,
        )
    return n_hist, n_field


@compiled(fastmath={"contract"})
def advance(
    first, last, tool, rows, rod, weights, contact, striker, anvil, medium, force, shaft, state, observed, recorders
):
    """Compute layers `first … last` (inclusive; layer 0 is the initial state).

    The `Tool` with its rows factored (`ToolRows`), the `Rod`'s constants and the scheme's
    `Weights`; the ends: the `Contact` at the struck end, the `Striker` when it is a rod, the
    `Medium` (at the working end), and R(t) on the striker (`ForceLaw`); the `Shaft`, the soil along
    the tool's side. The `State` carries the layers from call to call, the `Observed` extremes and
    contacts accumulate, and the `Recorders` take the layers this call records, from the first of
    each buffer.

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
    tool, rows, striker, shaft, state, observed, recorders = uncounted(
        (tool, rows, striker, shaft, state, observed, recorders)
    )
    step = step_constants(tool, rod, weights, contact, anvil)
    u, energy, striker_u = state.u, state.energy, state.striker
    extremes = observed.extremes
    tau = rod.time_step
    # the ends' states and the struck end's events within a step (`integrate_ends`), lent to each
    # step `uncounted`: `scratch` holds them through the loop
    scratch = (np.empty(STRUCK_END_STATE), np.empty(WORKING_END_STATE), np.empty((4, 4)))
    n_hist = 0
    n_field = 0

    for m in range(first, last + 1):
        layer = Layers(new=m % 3, cur=(m - 1) % 3, old=(m - 2) % 3, ref=(m - step.boundary.back) % 3)
        t = m * tau
        if m == 0:
            recorded = start_impact(
                state, observed, layer, t, tool, rod, weights, contact, striker, anvil, medium, step
            )
            interior = AT_REST
        else:
            for slot in range(ENERGY_SLOTS):
                energy[1, slot] = energy[0, slot]
            # Right-hand sides of rows u_N … u_1 over their diagonals; Q_i is kept in row `new`
            # until the substitution.
            if not weights.impedance_ends:
                working_end_row(u, layer, rows, rod, weights, medium, step)
            right_hand_sides(u, state.increments, layer, tool, rows, rod, weights, step)
            # the explicit scheme's interior rows are final here (none has a shaft otherwise); the
            # soil's and the weight's loops are calls of their own, made only where they have nodes
            if shaft.last >= shaft.first:
                shaft_on_rows(u, state.increments, layer, shaft, state.shaft_sets, energy, tau)
            if tool.gravity.last >= tool.gravity.first:
                energy[0, E_GRAVITY_WORK] += gravity_work(u, layer, tool.gravity)
            if striker.elastic:
                explicit_interior(striker_u, state.striker_increments, layer, striker.tool, 1.0, striker_u.shape[1] - 1)
                if striker.tool.gravity.last >= striker.tool.gravity.first:
                    energy[0, E_GRAVITY_WORK] += gravity_work(striker_u, layer, striker.tool.gravity)
            if weights.impedance_ends:
                finite, recorded, interior, balance = impedance_ends_step(
                    state, observed, layer, t, tool, rod, contact, striker, anvil, medium, force, scratch, step
                )
            else:
                finite, recorded, interior, balance = scheme_ends_step(
                    state, observed, layer, m, t, tool, rows, rod, weights, contact, medium, force, step
                )
            if not (finite and track_energy_excess(extremes, balance)):
                extremes[X_FAILED_TIME] = t
                return STATUS_NON_FINITE, n_hist, n_field
        if m >= step.lag:  # the centred schemes record layer 0 once its forces are known
            n_hist, n_field = record_layer(
                state,
                observed,
                recorders,
                recorded,
                interior,
                m - step.lag,
                n_hist,
                n_field,
                tool,
                rod,
                striker,
                anvil,
                force,
                shaft,
                step,
            )
    return STATUS_OK, n_hist, n_field
