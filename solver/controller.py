"""Runs a case: the kernel in chunks of steps, with progress, cancellation, probes and sampling.

Between chunks the controller reports progress and checks for cancellation; each chunk's kept
layers go to a `Recorder`: held in memory (`MemoryRecorder`), or streamed to an HDF5 file
(`solver.io.ResultWriter`), in which case memory is O(N) whatever the outputs ask for.
"""

from __future__ import annotations

from contextlib import nullcontext

import numpy as np

from . import kernel as K
from . import layout as L
from .blows import BlowLog
from .case import Case, Contact, Force, Medium, parse_case
from .compiled import mark_cache_used
from .cycle import HammerAtWork, blow_force
from .drive import FLIGHT_ROWS, Flight
from .errors import Cancelled, NumericalFailure
from .grid import (
    DEFAULT_TOLERANCE,
    Grid,
    ResolvedNumerics,
    make_grid,
    node_weights,
    resolve_numerics,
    shaft_nodes,
    shaft_spans,
    striker_grid,
    striker_mass,
    tolerance_of,
    wave_speed,
)
from .laws import FORCE_KINDS
from .rest import at_rest
from .result import CancelCheck, MemoryRecorder, ProgressCallback, Recorder, Result
from .summary import FORCE_HISTORY, MAX_CONTACTS, build_summary, force_history_rows, launch_energy

CHUNK_NODE_STEPS = 2_000_000  # work between two progress reports (about 10 ms)

# History columns as stored under their HDF5 paths.
HISTORY_PATHS = {
    "time": L.H_TIME,
    "striker/displacement": L.H_STRIKER_DISP,
    "striker/velocity": L.H_STRIKER_VEL,
    "tool/struck_end_displacement": L.H_STRUCK_END,
    "tool/working_end_displacement": L.H_WORKING_END,
    "contact/force": L.H_CONTACT_FORCE,
    "contact/overlap": L.H_OVERLAP,
    "medium/force": L.H_MEDIUM_FORCE,
    "external/force": L.H_EXTERNAL_FORCE,
    "energy/external_work": L.H_EXTERNAL_WORK,
    "energy/dissipated_contact": L.H_DISSIPATED_CONTACT,
    "energy/dissipated_medium": L.H_DISSIPATED_MEDIUM,
    "energy/striker_kinetic": L.H_STRIKER_KINETIC,
    "energy/tool_kinetic": L.H_TOOL_KINETIC,
    "energy/tool_strain": L.H_TOOL_STRAIN,
    "energy/contact_potential": L.H_CONTACT_POTENTIAL,
    "energy/medium_potential": L.H_MEDIUM_POTENTIAL,
    "tool/transferred_energy": L.H_TRANSFERRED,
}
# What a striker has: none when a history drives the struck end.
STRIKER_PATHS = (
    "striker/displacement",
    "striker/velocity",
    "contact/overlap",
    "external/force",
    "energy/striker_kinetic",
    "energy/contact_potential",
)
# A medium that yields adds these.
YIELDING_PATHS = {
    "medium/penetration": L.H_WORKING_END,
    "medium/permanent_penetration": L.H_PERMANENT_PENETRATION,
    "energy/medium_plastic": L.H_MEDIUM_PLASTIC,
}


# An anvil adds these (its force: on the tool's struck end).
ANVIL_PATHS = {
    "anvil/displacement": L.H_ANVIL_DISP,
    "anvil/velocity": L.H_ANVIL_VEL,
    "anvil/force": L.H_ANVIL_FORCE,
    "energy/anvil_kinetic": L.H_ANVIL_KINETIC,
}


# Blow after blow adds what the strikers launched after the first brought, and what each took away;
# a hammer at work, what the tool held each time it came to rest between blows.
BLOW_PATHS = {"energy/launched": L.H_LAUNCHED, "energy/striker_withdrawn": L.H_WITHDRAWN}
CYCLE_PATHS = {"energy/dissipated_between_blows": L.H_BETWEEN_BLOWS}


def history_paths(case: Case) -> dict[str, int]:
    """The history columns a case keeps, by HDF5 path: only what its model has."""
    paths = dict(HISTORY_PATHS)
    if case.struck_end is not None:  # no striker: "contact/force" is the force on the struck end
        for path in STRIKER_PATHS:
            del paths[path]
    if case.medium_yields:
        paths.update(YIELDING_PATHS)
    if case.elastic_striker:
        paths["energy/striker_strain"] = L.H_STRIKER_STRAIN
    if case.anvil is not None:
        paths.update(ANVIL_PATHS)
    if case.blows_run > 1:
        paths.update(BLOW_PATHS)
    if case.cycles is not None:
        paths.update(CYCLE_PATHS)
    if case.shaft:
        paths["energy/to_shaft"] = L.H_TO_SHAFT
    return paths


def _kept(first: int, last: int, stride: int) -> int:
    """How many layers in [first, last] are multiples of `stride` (none when last < first)."""
    return last // stride - (first - 1) // stride if stride > 0 and last >= first else 0


def _probe_nodes(grid: Grid, probes: list[float]) -> tuple[np.ndarray, np.ndarray]:
    """Each probe as the node left of it and the linear weight of the node to its right."""
    s = np.asarray(probes, dtype=float) / grid.h
    node = np.minimum(np.floor(s).astype(np.int64), grid.cells)
    weight = np.where(node >= grid.cells, 0.0, s - node)
    return node, weight


def force_law(f: Force | None) -> K.ForceLaw:
    """R(t) as the kernel (and `laws.external_force`) takes it."""
    if f is None:
        return K.ForceLaw(kind=K.FORCE_NONE, amplitude=0.0, omega=0.0, start=0.0, duration=0.0)
    if f.kind == "pulse":
        return K.ForceLaw(kind=K.FORCE_PULSE, amplitude=f.amplitude, omega=0.0, start=f.start, duration=f.duration)
    return K.ForceLaw(kind=FORCE_KINDS[f.kind], amplitude=f.amplitude, omega=f.omega, start=0.0, duration=0.0)


MEDIUM_KINDS = {"linear": K.MEDIUM_LINEAR, "bilinear": K.MEDIUM_BILINEAR, "smith": K.MEDIUM_SMITH}


DRIVEN_CONTACT = Contact(stiffness=1.0, exponent=0.0)


def end_conditions(case: Case, grid: Grid) -> tuple[K.Contact, K.Medium]:
    """The striker and contact, and the medium, with the impedances of the tool's end cells. With
    a history driving the struck end the contact is a still, massless stand-in (`DRIVEN_CONTACT`)
    that only carries the end's impedance."""
    c, m = case.contact or DRIVEN_CONTACT, case.medium
    impedance = grid.density * wave_speed(case.tool)
    contact = K.Contact(
        striker_mass=striker_mass(case.striker) if case.striker else 1.0,
        striker_velocity=case.impact_velocity,
        stiffness=c.stiffness,
        exponent=c.exponent,
        tension_stiffness=c.tension_stiffness,
        damping=c.damping,
        impedance=impedance * grid.end_area[0],
        restitution=c.restitution,
        deepest=0.0,
    )
    if m is None:
        m = Medium(stiffness=0.0)
    medium = K.Medium(
        kind=MEDIUM_KINDS[m.kind],
        stiffness=m.loading_stiffness,
        damping=m.damping,
        impedance=impedance * grid.end_area[1],
        unloading_stiffness=m.unloading_stiffness or 0.0,
        ultimate_resistance=m.ultimate_resistance or 0.0,
        damping_factor=m.damping_factor,
    )
    return contact, medium


DRIVERS = {"force": K.DRIVEN_BY_FORCE, "velocity": K.DRIVEN_BY_VELOCITY}


def striker_on(case: Case, num: ResolvedNumerics, tool: K.Tool, rod: K.Rod) -> K.Striker:
    """The striker as the kernel takes it: an elastic one on its grid at Courant number 1; a lumped
    one as `elastic = False` (its mass is the `Contact`'s; the tool's bundles fill the rest); a
    history driving the struck end as the `driver` of a still, massless lumped one."""
    striker, g = case.striker, acceleration(case)
    driven = {"driver": K.NOT_DRIVEN, "signal_time": np.zeros(0), "signal_values": np.zeros(0)}
    if case.struck_end is not None:
        kind, signal = case.struck_end.driver
        driven = {
            "driver": DRIVERS[kind],
            "signal_time": np.asarray(signal.time, float),
            "signal_values": np.asarray(signal.values, float),
        }
    if striker is None or not striker.elastic:
        mass = striker.mass if striker is not None else 1.0
        return K.Striker(
            elastic=False,
            tool=tool,
            rod=rod,
            impedance=1.0,
            back_impedance=1.0,
            mass=mass,
            back_delay=0.0,
            weight=mass * g if striker is not None else 0.0,
            **driven,
        )
    grid, back_delay = striker_grid(striker, num.time_step)
    impedance = grid.density * wave_speed(striker.rod())
    return K.Striker(
        elastic=True,
        tool=tool_on(grid, gravity_on(grid, num.time_step, g), stretches=1),  # the tool's envelope only
        rod=rod_on(grid, num.time_step, 1.0),
        impedance=impedance * grid.end_area[0],
        back_impedance=impedance * grid.end_area[1],
        mass=striker_mass(striker),
        back_delay=back_delay,
        weight=0.0,
        **driven,
    )


def anvil_on(case: Case, grid: Grid, contact: K.Contact) -> K.Anvil:
    """The anvil as the kernel takes it, with its contact on the tool's struck end (the case's
    `contact`, the striker's, fills an absent anvil's place)."""
    anvil = case.anvil
    if anvil is None:
        return K.Anvil(present=False, mass=1.0, velocity=0.0, contact=contact, weight=0.0)
    c = anvil.contact
    return K.Anvil(
        present=True,
        mass=anvil.mass,
        velocity=anvil.velocity,
        contact=K.Contact(
            striker_mass=anvil.mass,
            striker_velocity=anvil.velocity,
            stiffness=c.stiffness,
            exponent=c.exponent,
            tension_stiffness=c.tension_stiffness,
            damping=c.damping,
            impedance=contact.impedance,
            restitution=c.restitution,
            deepest=0.0,
        ),
        weight=anvil.mass * acceleration(case),
    )


def acceleration(case: Case) -> float:
    """g (m/s²) of the case's gravity, 0 without it."""
    return case.gravity.acceleration if case.gravity is not None else 0.0


def gravity_on(grid: Grid, tau: float, g: float) -> K.Gravity:
    """The weight of a rod's nodes on its grid under g, as the kernel takes it (`grid.node_weights`)."""
    if g == 0.0:
        return K.no_gravity()
    weight = node_weights(grid, g)
    mass = grid.node_area * grid.density * grid.h
    return K.Gravity(
        first=1,
        last=grid.cells - 1,
        lift=np.divide(tau * tau * weight, mass, out=np.zeros_like(mass), where=mass > 0),
        weight=weight,
    )


def shaft_on(case: Case, grid: Grid, tau: float) -> K.Shaft:
    """The soil along the tool's side as the kernel takes it, node by node (`grid.shaft_nodes`)."""
    if not case.shaft:
        return K.no_shaft()
    resistance, stiffness, damping_factor = shaft_nodes(case.shaft, grid)
    loaded = np.flatnonzero(resistance)
    mass = grid.node_area * grid.density * grid.h
    return K.Shaft(
        first=int(loaded[0]),
        last=int(loaded[-1]),
        resistance=resistance,
        stiffness=stiffness,
        damping_factor=damping_factor,
        inv_mass=np.divide(tau * tau, mass, out=np.zeros_like(mass), where=mass > 0),
    )


def shaft_shares(case: Case, grid: Grid) -> np.ndarray:
    """Node i's share of segment k's force (segments × nodes)."""
    if not case.shaft:
        return np.zeros((0, grid.cells + 1))
    each = np.array([shaft_nodes([segment], grid)[0] for segment in case.shaft])
    total = each.sum(axis=0)
    return np.divide(each, total, out=np.zeros_like(each), where=total > 0)


def share_spans(shares: np.ndarray) -> np.ndarray:
    """Each segment's first and last node with a share of it (segments × 2; (1, 0), none, for a
    segment with no share)."""
    spans = np.zeros((len(shares), 2), np.int64)
    spans[:, 0] = 1
    for k, row in enumerate(shares):
        nodes = np.flatnonzero(row)
        if nodes.size:
            spans[k] = nodes[0], nodes[-1]
    return spans


def shaft_length(grid: Grid) -> np.ndarray:
    """Each node's length of shaft (m), which turns its force into the resistance per metre (N/m)."""
    left, right = shaft_spans(grid)
    return right - left


def tool_on(grid: Grid, gravity: K.Gravity | None = None, stretches: int = L.ENVELOPE_BINS) -> K.Tool:
    """The tool on its grid, with its nodes' weight (`gravity_on`; none by default), as the kernel
    takes it, its stress envelope kept over `stretches` stretches."""
    return K.Tool(
        gravity=gravity or K.no_gravity(),
        lower=grid.lower,
        upper=grid.upper,
        node_area=grid.node_area,
        area_mid=grid.area_mid,
        uniform=grid.uniform,
        struck_end_area=float(grid.area[0]),
        working_end_area=float(grid.area[-1]),
        stress_chunks=K.stress_chunks(grid.cells, stretches),
    )


def rod_constants(case: Case, num: ResolvedNumerics, grid: Grid) -> K.Rod:
    """The tool's constants on the grid and time step."""
    tool, tau, h = case.tool, num.time_step, grid.h
    impedance_ends = num.ends == "impedance"
    # Courant number 1 exactly where the ends rely on the end rows being the characteristic relation
    r = 1.0 if impedance_ends else (tool.youngs_modulus / tool.density) * tau * tau / (h * h)
    return rod_on(grid, tau, r)


def rod_on(grid: Grid, tau: float, courant_squared: float) -> K.Rod:
    """A rod's constants on its grid (h, E, ρ, the end cells' S·E/h), time step and (a·τ/h)²."""
    h, modulus = grid.h, grid.youngs_modulus
    return K.Rod(
        cell_length=h,
        time_step=tau,
        courant_squared=courant_squared,
        youngs_modulus=modulus,
        density=grid.density,
        struck_end_stiffness=grid.end_area[0] * modulus / h,
        working_end_stiffness=grid.end_area[1] * modulus / h,
    )


def scheme_weights(num: ResolvedNumerics) -> K.Weights:
    """The scheme as the kernel takes it."""
    scheme = num.weights()
    return K.Weights(
        new=scheme.weight_new,
        old=scheme.weight_old,
        centered=scheme.centered,
        end_masses=scheme.end_masses,
        impedance_ends=num.ends == "impedance",
    )


def energy_at(
    energy: np.ndarray, last: int, tau: float, duration: float, ends_at_layer: bool, elastic_striker: bool = False
) -> np.ndarray:
    """The energy terms at `duration`, interpolated between the kernel's last two layers (`energy`
    row 0 after layer `last`, row 1 before it): the run's last layer can lie up to a step beyond
    the duration. The terms are at layer m − ½ in the scheme's own form, but for the ends that
    integrate their own equations (`ends_at_layer`), whose work, dissipation and stored energy are
    at layer m (but for an elastic striker's, at m − ½ as the tool's)."""
    at = np.full(L.ENERGY_SLOTS, (last - 0.5) * tau)
    if ends_at_layer:
        at[
            [
                L.E_EXTERNAL_WORK,
                L.E_DISSIPATED_CONTACT,
                L.E_DISSIPATED_MEDIUM,
                L.E_STRIKER_KINETIC,
                L.E_CONTACT_POTENTIAL,
                L.E_MEDIUM_POTENTIAL,
                L.E_MEDIUM_PLASTIC,
                L.E_ANVIL_KINETIC,
            ]
        ] = last * tau
        if elastic_striker:
            at[L.E_STRIKER_KINETIC] = (last - 0.5) * tau
    if last < 2:
        return energy[0].copy()
    weight = (duration - at) / tau  # 0 at row 0, −1 at row 1
    return energy[0] + weight * (energy[0] - energy[1])


def simulate_rod(
    case: Case,
    numerics: ResolvedNumerics | None = None,
    progress: ProgressCallback | None = None,
    cancelled: CancelCheck | None = None,
    recorder: Recorder | None = None,
) -> Result:
    """Solve the case with the tool as an elastic rod (the paper's scheme (8)–(13)).

    The outputs go to `recorder`, by default a `MemoryRecorder` whose arrays the result carries;
    with any other the result is `streamed` and carries the summary only.
    """
    num = numerics or resolve_numerics(case, model="rod")
    weights = scheme_weights(num)
    grid = make_grid(case.tool, num.cells, weights.end_masses)
    n, tau = grid.cells, num.time_step
    tool, rod = tool_on(grid, gravity_on(grid, tau, acceleration(case))), rod_constants(case, num, grid)
    contact, medium = end_conditions(case, grid)
    striker = striker_on(case, num, tool, rod)
    anvil = anvil_on(case, grid, contact)
    rows = K.factor_tool_rows(tool, rod, weights, medium)
    force = blow_force(case) if case.drive is not None else force_law(case.force)
    shaft = shaft_on(case, grid, tau)

    out = case.outputs
    probe_node, probe_weight = _probe_nodes(grid, out.probes)
    field_stride = out.field_stride if out.fields else 0
    state = K.new_state(n, len(striker.tool.node_area) - 1 if striker.elastic else 0)
    if case.gravity is not None:
        K.start_at_rest(state, at_rest(case, grid))
    set_at_rest = float(state.ends[K.S_MEDIUM_SET])
    blows = case.blows_run
    blow, blow_steps = 0, num.steps // blows
    # blow k's extremes are those of its duration, which its last layer may pass by up to a step
    blow_ends = np.arange(blows) * (blow_steps * tau) + case.numerics.duration
    observed = K.new_observed(MAX_CONTACTS, until=blow_ends[0])
    hammer = HammerAtWork(case, blow_steps * tau) if case.cycles is not None else None
    log = BlowLog(launch_energy=launch_energy(case), set_at_rest=set_at_rest)
    log.start(state.energy[0])
    # The centred schemes' boundary forces are centred on a layer: it is recorded one step later.
    lag = 1 if weights.centered and not weights.impedance_ends else 0
    last_layer = num.steps + lag

    recorder = MemoryRecorder() if recorder is None else recorder
    recorder.start()
    # each flight between two blows adds its records (`drive.FLIGHT_ROWS`) to every history
    total_rows = _kept(0, num.steps, out.history_stride) + (FLIGHT_ROWS * (blows - 1) if hammer else 0)
    total_frames = _kept(0, num.steps, field_stride)
    probe_x = np.asarray(out.probes, float)
    paths = history_paths(case)
    for path in list(paths) + (list(DRIVE_PATHS) if hammer else []):
        recorder.create(path, (total_rows,))
    recorder.create("probes/x", probe_x.shape)
    recorder.append("probes/x", probe_x)
    recorder.create("probes/stress", (total_rows, len(probe_x)))
    # the fields along the tool, and along an elastic striker (`fields/striker_…`)
    striker_nodes = state.striker.shape[1] if striker.elastic else 0
    along = {"": grid.x}
    if striker.elastic:
        along["striker_"] = np.arange(striker_nodes) * striker.rod.cell_length
    if out.fields:
        recorder.create("fields/time", (total_frames,))
        for prefix, x in along.items():
            recorder.create(f"fields/{prefix}x", x.shape)
            recorder.append(f"fields/{prefix}x", x)
            recorder.create(f"fields/{prefix}displacement", (total_frames, len(x)))
            recorder.create(f"fields/{prefix}stress", (total_frames, len(x)))
    # the shaft's force on each segment, and its resistance along the tool
    shaft_share = shaft_shares(case, grid)
    shaft_span = share_spans(shaft_share)
    segment_paths = [f"shaft/segment_{k}/force" for k in range(len(shaft_share))]
    for path in segment_paths:
        recorder.create(path, (total_rows,))
    shaft_field = bool(case.shaft) and out.fields
    if shaft_field:
        recorder.create("fields/shaft_resistance", (total_frames, n + 1))
        lengths = shaft_length(grid)
    # Gathered during the run, so that the summary never needs the whole history (given only
    # these rows, it keeps them all).
    summary_rows = force_history_rows(total_rows)
    summary_columns = [HISTORY_PATHS[path] for path in FORCE_HISTORY.values()]
    summary_table = []  # the summary's histories at `summary_rows`, chunk by chunk
    row = 0  # history rows kept before this chunk
    elapsed = 0.0  # the flights' time so far (s), between blows

    chunk = max(1, CHUNK_NODE_STEPS // (n + 1))
    first = 0
    while first <= last_layer:
        boundary = (blow + 1) * blow_steps if blow < blows - 1 else last_layer
        last = min(boundary, first + chunk - 1)
        recorded = (max(0, first - lag), last - lag)  # the layers this chunk records
        kept_rows = _kept(*recorded, out.history_stride)
        frames = _kept(*recorded, field_stride)
        recorders = K.Recorders(
            history=np.empty((L.HISTORY_COLUMNS, kept_rows)),
            history_stride=out.history_stride,
            probe_node=probe_node,
            probe_weight=probe_weight,
            probes=np.empty((kept_rows, len(probe_node))),
            field_u=np.empty((frames, n + 1)),
            field_stress=np.empty((frames, n + 1)),
            field_stride=field_stride,
            striker_u=np.empty((frames, striker_nodes)),
            striker_stress=np.empty((frames, striker_nodes)),
            shaft_share=shaft_share,
            shaft_span=shaft_span,
            shaft_history=np.empty((len(shaft_share), kept_rows)),
            shaft_field=np.zeros((frames if shaft_field else 0, n + 1)),
        )
        status, n_hist, n_field = K.advance(
            first,
            last,
            tool,
            rows,
            rod,
            weights,
            contact,
            striker,
            anvil,
            medium,
            force,
            shaft,
            state,
            observed,
            recorders,
        )
        if status == K.STATUS_NON_FINITE:
            raise NumericalFailure(observed.extremes[L.X_FAILED_TIME], num)
        history = recorders.history
        history[L.H_TIME, :n_hist] += elapsed  # the flights' time between the blows
        for path, column in paths.items():
            recorder.append(path, history[column, :n_hist])
        if n_hist:
            kept_last = (history[:, n_hist - 1].copy(), recorders.probes[n_hist - 1].copy())
        if hammer is not None:
            recorder.append("drive/rear_pressure", np.full(n_hist, case.drive.return_pressure))
            recorder.append("drive/supply_pressure", np.full(n_hist, hammer.drive.pressure(hammer.gas)))
        recorder.append("probes/stress", recorders.probes[:n_hist])
        for k, path in enumerate(segment_paths):
            recorder.append(path, recorders.shaft_history[k, :n_hist])
        low, high = np.searchsorted(summary_rows, (row, row + n_hist))
        summary_table.append(history[summary_columns].take(summary_rows[low:high] - row, axis=1))
        row += n_hist
        if n_field:
            lo, hi = recorded
            recorder.append(
                "fields/time", np.arange(-(-lo // field_stride) * field_stride, hi + 1, field_stride) * tau + elapsed
            )
            layers = {
                "": (recorders.field_u, recorders.field_stress),
                "striker_": (recorders.striker_u, recorders.striker_stress),
            }
            for prefix in along:
                displacement, stress = layers[prefix]
                recorder.append(f"fields/{prefix}displacement", displacement[:n_field])
                recorder.append(f"fields/{prefix}stress", stress[:n_field])
            if shaft_field:
                resistance = np.divide(
                    recorders.shaft_field[:n_field],
                    lengths,
                    out=np.zeros((n_field, n + 1)),
                    where=lengths > 0,
                )
                recorder.append("fields/shaft_resistance", resistance)
        first = last + 1
        if last == boundary and blow < blows - 1:
            ended = state.energy[0].copy()
            velocity = case.impact_velocity
            if hammer is not None:
                K.rest_tool(last, state, contact, anvil)
                flight = fly_between(hammer, state, last, striker, contact, anvil, log, case.medium_yields)
                flown = flight_history(kept_last, flight, last * tau + elapsed, state)
                record_flight(recorder, paths, kept_last, flight, flown)
                low, high = np.searchsorted(summary_rows, (row, row + FLIGHT_ROWS))
                summary_table.append(flown[summary_columns].take(summary_rows[low:high] - row, axis=1))
                row += FLIGHT_ROWS
                elapsed += flight.duration
                velocity = flight.impact_velocity
            K.start_blow(last, state, observed, contact, striker, anvil, medium, tau, velocity)
            log.finish(ended, observed)
            blow += 1
            observed = K.new_observed(MAX_CONTACTS, until=blow_ends[blow])
            log.start(state.energy[0])
        if progress is not None:
            progress(min(1.0, first / (last_layer + 1)))
        if cancelled is not None and first <= last_layer and cancelled():
            raise Cancelled(f"cancelled at t = {first * tau:.6g} s")

    table = np.concatenate(summary_table, axis=1)
    ends = state.ends
    energy = energy_at(state.energy, last_layer, tau, blow_ends[-1], weights.impedance_ends, striker.elastic)
    log.finish(energy, observed)
    extremes = log.extremes()
    summary = build_summary(
        case=case,
        numerics=num,
        extremes=extremes,
        contacts=log.contacts(),
        open_contact=ends[K.S_CONTACT_START] if ends[K.S_IN_CONTACT] else None,
        energy=energy,
        history=dict(zip(FORCE_HISTORY.values(), table)),
        permanent_penetration=log.table()[-1]["permanent_penetration"],
        set_at_rest=set_at_rest,
        blows=log.table() if case.blows or hammer else None,
        extra_warnings=log.still_rising(extremes, blow_ends, tau),
        envelope=log.envelope(),
    )
    if hammer is not None:
        summary["cycle"] = hammer.summary(log.table(), tolerance_of(case.numerics) or DEFAULT_TOLERANCE)
    held = recorder.held()
    if held is None:
        return Result(
            case=case,
            numerics=num,
            history={},
            probe_x=probe_x,
            probe_stress=np.empty((0, len(probe_x))),
            fields=None,
            summary=summary,
            streamed=True,
        )
    return Result.from_arrays(case, num, held, summary)


DRIVE_PATHS = ("drive/rear_pressure", "drive/supply_pressure")  # a hammer at work's, beside the kernel's


def fly_between(hammer, state, last, striker, contact, anvil, log, has_set) -> Flight:
    """The striker's flight after the blow that ended at layer `last`, from the kernel's state:
    the striker's displacement and velocity (an elastic one's mean), to the struck end (or the
    anvil) where the tool is held."""
    row, ends = last % 3, state.ends
    velocity = ends[K.S_STRIKER_VELOCITY]
    if striker.elastic:
        velocity = ends[K.S_LAUNCH_VELOCITY] - ends[K.S_IMPULSE] / striker.mass
    impact_point = ends[K.S_ANVIL_DISP] if anvil.present else state.u[row, 0]
    last_set = log.set_of(ends[K.S_MEDIUM_SET]) if has_set else None
    return hammer.between(state.y[row], velocity, impact_point, last_set)


def flight_history(kept_last, flight: Flight, start: float, state) -> np.ndarray:
    """A flight's rows of the history's columns from `start` (s): the striker's from the flight,
    no contact force, the tool at rest on the medium as `kernel.rest_tool` left it in `state`
    (unstressed, no force on the medium), the rest held at the last row kept (`kept_last`: the
    history's and the probes')."""
    rows = np.repeat(kept_last[0][:, None], FLIGHT_ROWS, axis=1)
    rows[[L.H_STRUCK_END, L.H_WORKING_END]] = state.ends[K.S_MEDIUM_SET]
    rows[[L.H_MEDIUM_FORCE, L.H_TOOL_KINETIC, L.H_TOOL_STRAIN, L.H_MEDIUM_POTENTIAL, L.H_ANVIL_FORCE]] = 0.0
    rows[L.H_ANVIL_DISP] = state.ends[K.S_ANVIL_DISP]
    rows[L.H_CONTACT_POTENTIAL] = state.energy[0, L.E_CONTACT_POTENTIAL]
    rows[L.H_BETWEEN_BLOWS] = state.energy[0, L.E_BETWEEN_BLOWS]
    rows[L.H_TIME] = start + flight.time
    rows[L.H_STRIKER_DISP] = flight.displacement
    rows[L.H_STRIKER_VEL] = flight.velocity
    rows[L.H_CONTACT_FORCE] = 0.0
    rows[L.H_OVERLAP] = flight.displacement - flight.impact_point
    return rows


def record_flight(recorder, paths, kept_last, flight: Flight, rows: np.ndarray) -> None:
    """A flight's records (`rows`, `flight_history`'s) in every history, the drive's pressures,
    and the probes on the tool at rest (unstressed)."""
    for path, column in paths.items():
        recorder.append(path, rows[column])
    recorder.append("drive/rear_pressure", flight.rear_pressure)
    recorder.append("drive/supply_pressure", flight.supply_pressure)
    recorder.append("probes/stress", np.zeros((FLIGHT_ROWS, len(kept_last[1]))))


WARM_UP_BLOW = {
    "striker": {"mass": 1.0, "velocity": 1.0},
    "tool": {"length": 1.0, "youngs_modulus": 1e9, "density": 1e3, "area": 1e-3},
    "contact": {"stiffness": 1e8, "exponent": 0.5},
    "force": {"kind": "pulse", "amplitude": 1.0, "duration": 1e-5},
    "numerics": {"duration": 1e-4, "cells": 4},
    "outputs": {"probes": [0.5], "fields": True},
}
WARM_UP_HAMMER = {key: value for key, value in WARM_UP_BLOW.items() if key != "force"} | {
    "medium": {"kind": "linear", "stiffness": 1e6},
    "drive": {"kind": "hydraulic", "supply_pressure": 1e6, "front_area": 1e-4, "rear_area": 2e-4, "stroke": 0.01},
    "cycles": {"count": 2},
    "numerics": {"duration": 1e-4, "cells": 4, "scheme": "explicit"},
}


def warm_up(processes: int = 1) -> None:
    """Compile the kernel into Numba's on-disk cache (a no-op when it is there already): a blow,
    and two of a hammer at work, whose rest between blows and flight are compiled functions of
    their own. With two `processes`, the flight (a third of the compiling) is compiled in a second
    process meanwhile. The cache is marked as used (`compiled.prune_caches` keeps it). Last it
    loads what a ladder that refines unevenly needs (`accuracy.observed_order`'s root finder,
    0.2 s to import), so that a worker's first such job does not pay it."""
    from concurrent.futures import ProcessPoolExecutor  # here: a process pool only when compiling
    from multiprocessing import get_context

    with ProcessPoolExecutor(1, mp_context=get_context("spawn")) if processes > 1 else nullcontext() as other:
        flight = other.submit(warm_up_flight) if other else None
        simulate_rod(parse_case(WARM_UP_BLOW))
        if flight:
            flight.result()
    simulate_rod(parse_case(WARM_UP_HAMMER))
    mark_cache_used()
    import scipy.optimize  # noqa: F401


def warm_up_flight() -> None:
    """The warm-up hammer's first flight alone, which compiles apart from the blow's kernel."""
    case = parse_case(WARM_UP_HAMMER)
    HammerAtWork(case, blow_duration=1e-4).between(start=0.0, velocity=-1.0, impact_point=0.0, last_set=None)
