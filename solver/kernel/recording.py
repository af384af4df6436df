"""What a run observes and keeps: the contact intervals, the extremes (forces, stresses, between
layers at the ends), the history, probes and fields.
"""

from __future__ import annotations

import numpy as np

from ..compiled import compiled
from ..layout import (
    COMPRESSION,
    E_ANVIL_KINETIC,
    E_BETWEEN_BLOWS,
    E_CONTACT_POTENTIAL,
    E_DISSIPATED_CONTACT,
    E_DISSIPATED_MEDIUM,
    E_EXTERNAL_WORK,
    E_LAUNCHED,
    E_MEDIUM_PLASTIC,
    E_MEDIUM_POTENTIAL,
    E_STRIKER_KINETIC,
    E_STRIKER_STRAIN,
    E_TO_SHAFT,
    E_TOOL_KINETIC,
    E_TOOL_STRAIN,
    E_WITHDRAWN,
    H_ANVIL_DISP,
    H_ANVIL_FORCE,
    H_ANVIL_KINETIC,
    H_ANVIL_VEL,
    H_BETWEEN_BLOWS,
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
    H_TO_SHAFT,
    H_TOOL_KINETIC,
    H_TOOL_STRAIN,
    H_TRANSFERRED,
    H_WITHDRAWN,
    H_WORKING_END,
    TENSION,
    X_CO_IMPACT,
    X_CONTACTS,
    X_FADE_TIME,
    X_MAX_TRANSFERRED,
    X_MIN_CONTACT_STEPS,
    X_PEAK_FORCE,
    X_PEAK_FORCE_TIME,
    X_REBOUND_VELOCITY,
)
from .audit import first_node, widen
from .bundles import (
    S_ANVIL_DISP,
    S_ANVIL_FORCE,
    S_ANVIL_VELOCITY,
    S_CONTACT_START,
    S_FORCE_BEFORE,
    S_FORCE_BEFORE_THAT,
    S_FORCE_EARLIER,
    S_IN_CONTACT,
    S_MEDIUM_FORCE,
    S_MEDIUM_FORCE_BEFORE,
    S_MEDIUM_FORCE_EARLIER,
    S_MEDIUM_SET,
    S_TRANSFER_DISP,
    S_TRANSFER_FORCE,
    S_TRANSFERRED,
    Recorded,
)
from .contact import crossing, crossing_rate, external_force, fade_time, rounding_of


@compiled(inline="always")
def node_stress(u, recorded, i, step):
    """`σ_i = E·∂u/∂x` (tension +) at node i of the `Recorded` layer: central inside; at the ends
    the end force over the area."""
    if i == 0:
        return recorded.struck_end_stress
    if i == step.n:
        return recorded.working_end_stress
    return 0.5 * step.e_over_h * (u[recorded.row, i + 1] - u[recorded.row, i - 1])


@compiled(inline="always")
def track_contact(ends, observed, t_cross, velocity, fade, into_contact, tau):
    """A change of the overlap's sign at `t_cross`, the striker moving at `velocity` and the
    overlap crossing rounding in `fade` (`fade_time`): opens or closes a contact interval (δ ≥ 0 is
    contact); the first one to close sets the co-impact time, the rebound velocity and the fade. Past the
    blow's duration (`observed.until`, within its last step) nothing changes: the contact is as
    it stood where the duration ends."""
    if t_cross > observed.until:
        return
    extremes, contacts = observed.extremes, observed.contacts
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
            extremes[X_FADE_TIME] = fade
        ends[S_IN_CONTACT] = 0.0
    elif not in_contact and into_contact:
        ends[S_IN_CONTACT] = 1.0
        ends[S_CONTACT_START] = t_cross


@compiled(inline="always")
def track_overlap(ends, observed, overlaps, faces, m, t, velocity, tau):
    """The contact intervals from the new overlap between the `faces` (the striker's and the
    struck end's displacements at layer m, at `t`) and the layers' `Overlaps`: a change of sign
    placed on the parabola through the last three overlaps, which crosses the faces' rounding in
    `fade_time`."""
    delta = faces[0] - faces[1]
    if (delta >= 0.0) != (ends[S_IN_CONTACT] != 0.0):
        before_that = overlaps.old if m >= 2 else np.nan
        at = crossing(before_that, overlaps.cur, delta)
        fade = fade_time(rounding_of(faces[0], faces[1]), crossing_rate(before_that, overlaps.cur, delta, at) / tau)
        track_contact(ends, observed, t - tau + tau * at, velocity, fade, delta >= 0.0, tau)


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
def track_end_extreme(extremes, peak, value, x, t, until):
    """A new record of the `peak`'s (`COMPRESSION` or `TENSION`) value, with where and when, if it
    lies within the blow's duration (`t` ≤ `until`)."""
    value_slot, place_slot, time_slot = peak
    if value > extremes[value_slot] and t <= until:
        extremes[value_slot] = value
        extremes[place_slot] = x
        extremes[time_slot] = t


@compiled(inline="always")
def track_peak_force(extremes, force, t, until):
    """A new record of the contact force, if `t` lies within the blow's duration."""
    if force > extremes[X_PEAK_FORCE] and t <= until:
        extremes[X_PEAK_FORCE] = force
        extremes[X_PEAK_FORCE_TIME] = t


@compiled(inline="always")
def track_ends_between_layers(observed, contact_range, end_range, working_range, t, tool, rod, step):
    """The end forces' extremes within the step, as the ends' substeps saw them: `contact_range`
    (largest contact force, its time), `end_range` (the force on the tool's struck end: largest,
    its time, least, its time) and `working_range` (the medium force's, with their offsets from
    the step's start); those beyond the blow's duration are not seen."""
    extremes, until = observed.extremes, observed.until
    f_max, t_max = contact_range
    e_max, te_max, e_min, te_min = end_range
    g_max, tg_max, g_min, tg_min = working_range
    n, h, tau = step.n, rod.cell_length, rod.time_step
    end_area_0, end_area_n = tool.struck_end_area, tool.working_end_area
    track_peak_force(extremes, f_max, t_max, until)
    track_end_extreme(extremes, COMPRESSION, e_max / end_area_0, 0.0, te_max, until)
    track_end_extreme(extremes, TENSION, -e_min / end_area_0, 0.0, te_min, until)
    track_end_extreme(extremes, COMPRESSION, g_max / end_area_n, n * h, t - tau + tg_max, until)
    track_end_extreme(extremes, TENSION, -g_min / end_area_n, n * h, t - tau + tg_min, until)


@compiled(inline="always")
def track_stress_extremes(observed, u, recorded, interior, tool, rod, step):
    """The recorded layer's extreme stresses along the tool (`interior`: its interior nodes' least
    and greatest stress with their chunks, `tool_energy_and_stresses`, which raised the envelope's
    stretches with them) against the records; its end stresses raise the end stretches.

    Not refined between nodes: next to a kink (a reflected front meeting the peak) a parabola
    through three nodes overshoots by O(h), where the nodes' own error is O(h²)."""
    extremes, envelope = observed.extremes, observed.envelope
    low, low_chunk, high, high_chunk = interior
    s0, sn = recorded.struck_end_stress, recorded.working_end_stress
    widen(envelope, 0, s0, s0)
    widen(envelope, envelope.shape[1] - 1, sn, sn)
    s_low, s_high = min(s0, low, sn), max(s0, high, sn)
    for peak, value, inside, chunk, slots in (
        (-s_low, s_low, low, low_chunk, COMPRESSION),
        (s_high, s_high, high, high_chunk, TENSION),
    ):
        value_slot, place_slot, time_slot = slots
        if peak > extremes[value_slot]:
            # Where, only for a new record (most layers set none): the first node of that
            # stress, from the struck end.
            if value == s0:
                node = 0
            elif value == inside:
                node = first_node(u, recorded.row, step.half_e_over_h, tool.stress_chunks, chunk, value)
            else:
                node = step.n
            extremes[value_slot] = peak
            extremes[place_slot] = node * rod.cell_length
            extremes[time_slot] = recorded.time


@compiled(inline="always")
def between(before, now, weight):
    """The value `weight` of the way from `before` to `now` (`now` itself at weight 1)."""
    return now if weight >= 1.0 else before + weight * (now - before)


@compiled(inline="always")
def layer_at_end(recorded, ends, weight, until, tool):
    """The layer at `until`, where the blow's duration ends, `weight` of the step from the layer
    before the recorded one to it: its end forces and stresses linear between the two (those of
    the layer before as `ends` carries them, until `track_end_forces` and `track_transferred`
    move on), as the energy at the duration is (`controller.energy_at`)."""
    struck_before = -ends[S_TRANSFER_FORCE] / tool.struck_end_area
    medium_force = between(ends[S_MEDIUM_FORCE], recorded.medium_force, weight)
    return Recorded(
        row=recorded.row,
        time=until,
        velocity=recorded.velocity,
        contact_force=between(ends[S_FORCE_BEFORE], recorded.contact_force, weight),
        medium_force=medium_force,
        struck_end_stress=between(struck_before, recorded.struck_end_stress, weight),
        working_end_stress=-medium_force / tool.working_end_area,
    )


@compiled(inline="always")
def track_stress_at_end(observed, s, node, stretch, seen, rod):
    """Node `node`'s stress `s` at the duration's end against the extremes and its `stretch` of
    the envelope."""
    track_end_extreme(observed.extremes, COMPRESSION, -s, node * rod.cell_length, seen.time, seen.time)
    track_end_extreme(observed.extremes, TENSION, s, node * rod.cell_length, seen.time, seen.time)
    widen(observed.envelope, stretch, s, s)


@compiled(fastmath={"contract"})
def track_stresses_at_end(observed, u, seen, weight, tool, rod, step):
    """The extreme stresses along the tool at the duration's end (`seen`, `layer_at_end`): each
    interior node's linear between the layer before (the row before `seen.row`) and the recorded
    one, as its end stresses are, in the extremes and the envelope's stretches (the interior's
    by `tool.stress_chunks`). Once a blow, so node by node, and called, not inlined: a loop run
    once a blow is kept out of `advance`'s body (inlined there, the anvil's steps on 2000 cells
    measured 1.15 ns a node, against 1.02–1.15 without it)."""
    row, before = seen.row, (seen.row + 2) % 3
    chunks = tool.stress_chunks
    track_stress_at_end(observed, seen.struck_end_stress, 0, 0, seen, rod)
    for k in range(chunks.shape[1] - 1):
        for i in range(chunks[0, k], chunks[0, k + 1]):
            s = step.half_e_over_h * between(u[before, i + 1] - u[before, i - 1], u[row, i + 1] - u[row, i - 1], weight)
            track_stress_at_end(observed, s, i, chunks[1, k], seen, rod)
    track_stress_at_end(observed, seen.working_end_stress, step.n, observed.envelope.shape[1] - 1, seen, rod)


@compiled(inline="always")
def track_end_forces(extremes, ends, recorded, seen, until, m_rec, tool, rod, step, struck_vertex):
    """The peak contact force and the end stresses' extremes between layers, from the recorded
    layer's end forces and those of the three layers before it (carried in `ends`); at the struck
    end only when the contact force is the force on it (`struck_vertex`: not with an anvil,
    whose substeps' extremes are all there is). `seen`: the layer the extremes see, the recorded
    one or, past the blow's duration (`until`), the one at its end (`layer_at_end`)."""
    contact_force, medium_force = recorded.contact_force, recorded.medium_force
    t_rec, n, h, tau = recorded.time, step.n, rod.cell_length, rod.time_step
    end_area_0, end_area_n = tool.struck_end_area, tool.working_end_area
    track_peak_force(extremes, seen.contact_force, seen.time, until)
    # Extremes of the end forces between layers: the vertex of the parabola through the last
    # three, so that their error is the scheme's, not the sampling's.
    f1, f2, f3 = ends[S_FORCE_BEFORE], ends[S_FORCE_BEFORE_THAT], ends[S_FORCE_EARLIER]
    g1, g2, g3 = ends[S_MEDIUM_FORCE], ends[S_MEDIUM_FORCE_BEFORE], ends[S_MEDIUM_FORCE_EARLIER]
    if m_rec >= 3 and struck_vertex:
        top, offset = vertex(f3, f2, f1, contact_force)
        when = t_rec - tau + offset * tau
        track_peak_force(extremes, top, when, until)
        track_end_extreme(extremes, COMPRESSION, top / end_area_0, 0.0, when, until)
        top, offset = vertex(-f3, -f2, -f1, -contact_force)
        track_end_extreme(extremes, TENSION, top / end_area_0, 0.0, t_rec - tau + offset * tau, until)
    if m_rec >= 3:
        top, offset = vertex(g3, g2, g1, medium_force)
        track_end_extreme(extremes, COMPRESSION, top / end_area_n, n * h, t_rec - tau + offset * tau, until)
        top, offset = vertex(-g3, -g2, -g1, -medium_force)
        track_end_extreme(extremes, TENSION, top / end_area_n, n * h, t_rec - tau + offset * tau, until)
    ends[S_FORCE_EARLIER] = f2
    ends[S_FORCE_BEFORE_THAT] = f1
    ends[S_FORCE_BEFORE] = contact_force
    ends[S_MEDIUM_FORCE_EARLIER] = g2
    ends[S_MEDIUM_FORCE_BEFORE] = g1
    ends[S_MEDIUM_FORCE] = medium_force


@compiled(inline="always")
def track_transferred(extremes, ends, recorded, u, m_rec, tool, weight):
    """The work done on the tool through its struck end, ∫F·u_0' dt over this blow (trapezoidal
    over the recorded layers, F the force on the end, compression +), and its largest value so
    far: a pile driving analyser's EMX, to the blow's duration's end `weight` of the step to the
    recorded layer (F and u_0 linear over the step)."""
    force = -recorded.struck_end_stress * tool.struck_end_area
    at = u[recorded.row, 0]
    if m_rec > 0:
        before = ends[S_TRANSFERRED]
        ends[S_TRANSFERRED] += 0.5 * (force + ends[S_TRANSFER_FORCE]) * (at - ends[S_TRANSFER_DISP])
        seen = ends[S_TRANSFERRED]
        if weight < 1.0:
            force_seen = between(ends[S_TRANSFER_FORCE], force, weight)
            seen = before + 0.5 * (force_seen + ends[S_TRANSFER_FORCE]) * weight * (at - ends[S_TRANSFER_DISP])
        extremes[X_MAX_TRANSFERRED] = max(extremes[X_MAX_TRANSFERRED], seen)
    ends[S_TRANSFER_FORCE] = force
    ends[S_TRANSFER_DISP] = at


@compiled(inline="always")
def record_history(recorders, column, state, recorded, m_rec, force, anvil, step):
    """The recorded layer into `column` of the history (its energy terms as `energy[0]` holds
    them; none yet for layer 0, whose energy is all the striker's)."""
    history = recorders.history
    u, y, energy = state.u, state.y, state.energy
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
    history[H_TO_SHAFT, column] = energy[0, E_TO_SHAFT]
    history[H_TRANSFERRED, column] = state.ends[S_TRANSFERRED]
    history[H_BETWEEN_BLOWS, column] = energy[0, E_BETWEEN_BLOWS]
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
