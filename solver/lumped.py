"""The paper's model problem (21)–(25): the striker and the tool as two lumped masses.

The striker `m1` (displacement `x1 = y`, initial velocity `W1`) hits the tool taken as one rigid
mass `m2 = ρ∫S dx` (displacement `x2`, both tool ends move with it):

    m1·x1'' = R(t) − F,    m2·x2'' = F − c2·x2 − b2·x2',    F = G(δ)·δ + b1·δ',  δ = x1 − x2,

with the rod model's contact law (7), `G = c1·δ^α` for δ ≥ 0 and `c0` for δ < 0, so the two models
are comparable; with c0 = 0 this is (25) with the force exponent 1 + α. The damper `b1` always acts,
as in (21)–(22). Initial state (23)–(24): x1 = x2 = 0, x1' = W1, x2' = 0.

The force law is not smooth at δ = 0, so integration never steps over it: each segment integrates
one branch of the law (extended smoothly past δ = 0) with DOP853 and ends at a terminal event
δ = 0, from which the other branch restarts. The switches of R(t) (the pulse's ends, the kinks of
P·|sin ωt|) end segments too. Three extra states integrate the work of R, ∫R·x1' dt, and what the
dampers dissipate, ∫b1·δ'² dt and ∫b2·x2'² dt, so the energy audit closes to the integrator's
tolerance.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from . import laws
from . import layout as L
from .case import Case, Force
from .controller import HISTORY_PATHS, force_law
from .errors import Cancelled, NumericalFailure
from .grid import ResolvedNumerics, contact_time_estimate, resolve_numerics, tool_area, tool_mass, tool_mass_ahead
from .kernel.contact import fade_time, rounding_of
from .result import CancelCheck, ProgressCallback, Result
from .summary import MAX_CONTACTS, build_summary

# scipy (about 40 MB resident) is imported where the model runs, so that a process running only
# the rod, such as a worker, does not carry it.
if TYPE_CHECKING:
    from scipy.integrate import OdeSolution

RTOL = 1e-10
PEAK_SEARCH_POINTS = 4  # points per integrator step scanned for the peak force before refining
# δ = 0 belongs to contact in (7); shifting it off zero keeps a touch at rest from firing the event.
CONTACT_SIDE = 1e-300

# The ODE state
X1, V1, X2, V2, WORK, DISSIPATED_CONTACT, DISSIPATED_MEDIUM = range(7)
STATES = 7

NO_FIELDS_WARNING = (
    "the lumped model has no wave in the tool: outputs.fields are not computed "
    "(probes and stress maxima are its quasi-static stress)"
)
STRESS_STATIONS = 129  # stations along the tool scanned for the quasi-static stress maxima
STRESS_CHUNK = 4096  # samples of the histories scanned at a time


class IntegrationFailure(NumericalFailure):
    """The ODE integrator gave up (it has no time step or grid to change)."""

    def __init__(self, time: float, reason: str):
        self.time = time
        RuntimeError.__init__(self, f"the lumped model's integrator failed at t = {time:.6g} s: {reason}")


@dataclass(frozen=True)
class Parameters:
    """The model problem's coefficients: masses m1, m2; contact c1, α, c0, b1; medium c2, b2."""

    m1: float
    m2: float
    c1: float
    alpha: float
    c0: float
    b1: float
    c2: float
    b2: float

    @classmethod
    def of(cls, case: Case) -> Parameters:
        medium = case.medium
        return cls(
            m1=case.striker.mass,
            m2=tool_mass(case.tool),
            c1=case.contact.stiffness,
            alpha=case.contact.exponent,
            c0=case.contact.tension_stiffness,
            b1=case.contact.damping,
            c2=medium.stiffness if medium else 0.0,
            b2=medium.damping if medium else 0.0,
        )


@dataclass
class Segment:
    """One integrated piece: its dense output on [t0, t1], the branch of the law it used, and
    whether it ended on δ = 0 (the branch switches there)."""

    sol: OdeSolution
    t0: float
    t1: float
    contact: bool
    crossed: bool
    end: np.ndarray


# --- the model ---------------------------------------------------------------------------------


def spring_force(delta, p: Parameters, contact: bool):
    """`G(δ)·δ` on one branch: the contact's, continued smoothly past 0 (`laws.pressed_branch`),
    or `c0·δ`."""
    if contact:
        return laws.pressed_branch(delta, p.c1, p.alpha)
    return p.c0 * delta


def contact_force(delta, rate, p: Parameters):
    """Contact force on the tool `F = G(δ)·δ + b1·δ'` at each instant (`laws.contact_law_on`)."""
    return laws.contact_law_on(delta, p.c1, p.alpha, p.c0)[0] + p.b1 * rate


def contact_potential(delta, p: Parameters):
    """The contact's stored energy Φ(δ) at each instant (`laws.contact_law_on`)."""
    return laws.contact_law_on(delta, p.c1, p.alpha, p.c0)[1]


def external_force(force: Force | None, t):
    """`R(t)` at each instant (`laws.external_force_on`)."""
    return laws.external_force_on(t, *force_law(force))


def segment_force(force: Force | None, t0: float, t1: float) -> Callable[[float], float]:
    """R(t) on a segment between two breaks: the pulse is constant there, taken at the midpoint,
    so that the integrator's stages at the segment's ends see the segment's side of a jump."""
    if force is not None and force.kind == "pulse":
        level = float(external_force(force, 0.5 * (t0 + t1)))
        return lambda t: level
    return lambda t: float(external_force(force, t))


def force_breaks(force: Force | None, t_end: float) -> list[float]:
    """Instants where R(t) is not smooth, in (0, t_end), then t_end."""
    breaks = []
    if force is not None and force.kind == "pulse":
        breaks = [force.start, force.start + force.duration]
    elif force is not None and force.kind == "abs_sine":
        half_period = math.pi / force.omega
        breaks = [k * half_period for k in range(1, int(t_end / half_period) + 1)]
    return sorted({b for b in breaks if 0.0 < b < t_end}) + [t_end]


def rhs(t, s, p: Parameters, contact: bool, force: Callable[[float], float]) -> np.ndarray:
    """(21)–(22) on one branch of the contact law, with the work and dissipation integrals."""
    rate = s[V1] - s[V2]
    f = spring_force(s[X1] - s[X2], p, contact) + p.b1 * rate
    r = force(t)
    medium = p.c2 * s[X2] + p.b2 * s[V2]
    return np.array(
        [s[V1], (r - f) / p.m1, s[V2], (f - medium) / p.m2, r * s[V1], p.b1 * rate * rate, p.b2 * s[V2] * s[V2]]
    )


def overlap_event(contact: bool):
    """Terminal event δ = 0, crossed out of the current branch: downward in contact, upward in
    separation, so a segment that starts at δ = 0 moving into its branch does not stop at once."""

    def event(t, s, *rhs_args):  # solve_ivp passes the rhs's args on to events
        delta = s[X1] - s[X2]
        return delta if delta < 0.0 else delta + CONTACT_SIDE

    event.terminal = True
    event.direction = -1.0 if contact else 1.0
    return event


def absolute_tolerance(case: Case, p: Parameters, t_end: float) -> np.ndarray:
    """atol per state: RTOL times the size the state can reach (the contact depth for the
    displacements, W1 and the velocity R can add for the velocities, their kinetic energy), so
    states that start at zero are resolved relative to their scale."""
    push = abs(case.force.amplitude) * t_end / p.m1 if case.force else 0.0
    speed = (abs(case.impact_velocity) + push) or 1.0  # nothing moves: any scale will do
    depth = speed * min(t_end, contact_time_estimate(case))
    energy = 0.5 * p.m1 * speed * speed
    return RTOL * np.array([depth, speed, depth, speed, energy, energy, energy])


def segments(case: Case, p: Parameters, t_end: float) -> Iterator[Segment]:
    """Integrate from 0 to `t_end` segment by segment (see the module's docstring)."""
    from scipy.integrate import solve_ivp

    state = np.zeros(STATES)
    state[V1] = case.impact_velocity
    # δ(0) = 0 is contact in (7); a striker moving away leaves at once (a zero-length segment).
    t, contact = 0.0, True
    atol = absolute_tolerance(case, p, t_end)
    for stop in force_breaks(case.force, t_end):
        while t < stop:
            ode = solve_ivp(
                rhs,
                (t, stop),
                state,
                method="DOP853",
                rtol=RTOL,
                atol=atol,
                dense_output=True,
                events=overlap_event(contact),
                args=(p, contact, segment_force(case.force, t, stop)),
            )
            if ode.status < 0:
                raise IntegrationFailure(float(ode.t[-1]), ode.message)
            crossed = ode.status == 1
            t1 = float(ode.t_events[0][0]) if crossed else stop
            end = ode.y_events[0][0] if crossed else ode.y[:, -1]
            yield Segment(ode.sol, t, t1, contact, crossed, end)
            t, state, contact = t1, end, contact != crossed


# --- what a run observes -----------------------------------------------------------------------


@dataclass
class ContactLog:
    """Contact intervals from the δ = 0 events; δ(0) = 0 puts the striker in contact at t = 0."""

    intervals: list[tuple[float, float]] = dataclasses.field(default_factory=list)
    start: float = 0.0
    in_contact: bool = True
    first_end: float = math.nan
    rebound_velocity: float = math.nan
    fade_time: float = math.nan

    def observe(self, seg: Segment) -> None:
        if not seg.crossed:
            return
        if seg.contact and seg.t1 > self.start:  # a zero-length touch is no contact
            if not self.intervals:
                self.first_end, self.rebound_velocity = seg.t1, float(seg.end[V1])
                rounding = rounding_of(seg.end[X1], seg.end[X2])
                self.fade_time = float(fade_time(rounding, seg.end[V1] - seg.end[V2]))
            self.intervals.append((self.start, seg.t1))
        elif not seg.contact:
            self.start = seg.t1
        self.in_contact = not seg.contact


def segment_peak(seg: Segment, p: Parameters) -> tuple[float, float]:
    """Largest contact force on a segment and its time: scanned on the dense output, then refined
    by a bounded Brent search between the scan's neighbours of the best point."""
    from scipy.optimize import minimize_scalar

    steps = seg.sol.ts
    scan = np.concatenate(
        [np.linspace(a, b, PEAK_SEARCH_POINTS, endpoint=False) for a, b in zip(steps[:-1], steps[1:])] + [steps[-1:]]
    )

    def force(t):
        s = seg.sol(t)
        return contact_force(s[X1] - s[X2], s[V1] - s[V2], p)

    values = force(scan)
    best = int(np.argmax(values))
    lo, hi = scan[max(best - 1, 0)], scan[min(best + 1, len(scan) - 1)]
    refined = minimize_scalar(
        lambda t: -float(force(t)), bounds=(lo, hi), method="bounded", options={"xatol": 1e-9 * (hi - lo)}
    )
    if -refined.fun > values[best]:
        return -float(refined.fun), float(refined.x)
    return float(values[best]), float(scan[best])


def history_table(case: Case, p: Parameters, time: np.ndarray, s: np.ndarray) -> dict[str, np.ndarray]:
    """The rod model's histories from the sampled states; both tool ends are x2."""
    delta, rate = s[X1] - s[X2], s[V1] - s[V2]
    columns = {
        L.H_TIME: time,
        L.H_STRIKER_DISP: s[X1],
        L.H_STRIKER_VEL: s[V1],
        L.H_STRUCK_END: s[X2],
        L.H_WORKING_END: s[X2],
        L.H_CONTACT_FORCE: contact_force(delta, rate, p),
        L.H_OVERLAP: delta,
        L.H_MEDIUM_FORCE: p.c2 * s[X2] + p.b2 * s[V2],
        L.H_EXTERNAL_FORCE: external_force(case.force, time),
        L.H_EXTERNAL_WORK: s[WORK],
        L.H_DISSIPATED_CONTACT: s[DISSIPATED_CONTACT],
        L.H_DISSIPATED_MEDIUM: s[DISSIPATED_MEDIUM],
        L.H_STRIKER_KINETIC: 0.5 * p.m1 * s[V1] ** 2,
        L.H_TOOL_KINETIC: 0.5 * p.m2 * s[V2] ** 2,
        L.H_TOOL_STRAIN: np.zeros_like(time),
        L.H_CONTACT_POTENTIAL: contact_potential(delta, p),
        L.H_MEDIUM_POTENTIAL: 0.5 * p.c2 * s[X2] ** 2,
        # the work through the struck end is all the rigid tool holds and gave the medium
        L.H_TRANSFERRED: 0.5 * p.m2 * s[V2] ** 2 + 0.5 * p.c2 * s[X2] ** 2 + s[DISSIPATED_MEDIUM],
    }
    return {path: np.array(columns[col], dtype=float) for path, col in HISTORY_PATHS.items()}


def final_energy(p: Parameters, s: np.ndarray) -> np.ndarray:
    """The kernel's energy slots at the final state (no strain energy: the tool is rigid)."""
    energy = np.zeros(L.ENERGY_SLOTS)
    energy[L.E_EXTERNAL_WORK] = s[WORK]
    energy[L.E_DISSIPATED_CONTACT] = s[DISSIPATED_CONTACT]
    energy[L.E_DISSIPATED_MEDIUM] = s[DISSIPATED_MEDIUM]
    energy[L.E_STRIKER_KINETIC] = 0.5 * p.m1 * s[V1] ** 2
    energy[L.E_TOOL_KINETIC] = 0.5 * p.m2 * s[V2] ** 2
    energy[L.E_CONTACT_POTENTIAL] = contact_potential(s[X1] - s[X2], p)
    energy[L.E_MEDIUM_POTENTIAL] = 0.5 * p.c2 * s[X2] ** 2
    return energy


def energy_excess(history: dict[str, np.ndarray], initial: float) -> float:
    """Largest energy created at a sample, stored + dissipated − input (the kernel's tracker)."""
    names = (
        "striker_kinetic",
        "tool_kinetic",
        "tool_strain",
        "contact_potential",
        "medium_potential",
        "dissipated_contact",
        "dissipated_medium",
    )
    balance = sum(history[f"energy/{n}"] for n in names) - initial - history["energy/external_work"]
    return max(0.0, float(np.max(balance)))


def contact_table(log: ContactLog) -> np.ndarray:
    """The finished contact intervals (start, end) in the controller's fixed-size table."""
    table = np.zeros((MAX_CONTACTS, 2))
    kept = np.reshape(log.intervals[:MAX_CONTACTS], (-1, 2))
    table[: len(kept)] = kept
    return table


def quasi_static_stress(
    case: Case, p: Parameters, contact: np.ndarray, medium: np.ndarray, x: np.ndarray
) -> np.ndarray:
    """Stress (tension +) at stations `x` of the rigid tool, each sample: the part of the tool
    ahead of x, mass `μ(x)·m2`, moves with the whole, so `σ = −((1 − μ)·F_c + μ·F_m)/S(x)`."""
    mu = np.clip(tool_mass_ahead(case.tool, x) / p.m2, 0.0, 1.0)
    return -(np.outer(contact, 1.0 - mu) + np.outer(medium, mu)) / tool_area(case.tool, x)


def stress_extremes(case: Case, p: Parameters, history: dict[str, np.ndarray], peak: tuple[float, float]) -> np.ndarray:
    """`(max compression, x, t, max tension, x, t)` of the quasi-static stress, scanned in chunks
    so the memory stays independent of the run's length; the struck end's compression at the
    peak contact force (found between samples) is a candidate too."""
    x = np.union1d(
        np.linspace(0.0, case.tool.length, STRESS_STATIONS), case.tool.profile.x if case.tool.profile else []
    )
    time = history["time"]
    at_peak = peak[0] / float(tool_area(case.tool, np.zeros(1))[0])
    best = np.array([at_peak, 0.0, peak[1], 0.0, 0.0, 0.0])
    for start in range(0, len(time), STRESS_CHUNK):
        part = slice(start, start + STRESS_CHUNK)
        stress = quasi_static_stress(case, p, history["contact/force"][part], history["medium/force"][part], x)
        for sign, slot in ((-1.0, 0), (1.0, 3)):
            k = np.argmax(sign * stress)
            value = sign * stress.flat[k]
            if value > best[slot]:
                row, col = np.unravel_index(k, stress.shape)
                best[slot : slot + 3] = value, x[col], time[part][row]
    return best


def fill_extremes(log: ContactLog, peak: tuple[float, float], stress: np.ndarray, excess: float) -> np.ndarray:
    """The kernel's extremes from the contact log, the refined peak force and the stress maxima."""
    extremes = L.new_extremes()
    extremes[L.X_PEAK_FORCE], extremes[L.X_PEAK_FORCE_TIME] = peak
    (
        extremes[L.X_MAX_COMPRESSION],
        extremes[L.X_MAX_COMPRESSION_X],
        extremes[L.X_MAX_COMPRESSION_TIME],
        extremes[L.X_MAX_TENSION],
        extremes[L.X_MAX_TENSION_X],
        extremes[L.X_MAX_TENSION_TIME],
    ) = stress
    extremes[L.X_CONTACTS] = len(log.intervals)
    extremes[L.X_CO_IMPACT] = log.first_end
    extremes[L.X_REBOUND_VELOCITY] = log.rebound_velocity
    extremes[L.X_FADE_TIME] = log.fade_time
    extremes[L.X_ENERGY_EXCESS] = excess
    return extremes


def simulate_lumped(
    case: Case,
    numerics: ResolvedNumerics | None = None,
    progress: ProgressCallback | None = None,
    cancelled: CancelCheck | None = None,
) -> Result:
    """Solve the case with the tool as one rigid mass m2 (the model problem (21)–(25)).

    `numerics.time_step` is only the sampling step of the histories (k·τ, k = 0 … steps, every
    `outputs.history_stride`-th); the integrator chooses its own steps. Progress is reported and
    cancellation checked between integration segments.
    """
    num = numerics or dataclasses.replace(
        resolve_numerics(case, model="lumped"), scheme="dop853", end_masses=False, cells=0, courant=0.0
    )
    p = Parameters.of(case)
    t_end = num.steps * num.time_step
    time = np.arange(0, num.steps + 1, case.outputs.history_stride) * num.time_step
    samples = np.empty((STATES, len(time)))
    log = ContactLog()
    peak = (0.0, 0.0)
    for seg in segments(case, p, t_end):
        if seg.t1 > seg.t0:
            inside = (seg.t0 <= time) & (time <= seg.t1)
            samples[:, inside] = seg.sol(time[inside])
            candidate = segment_peak(seg, p)
            if candidate[0] > peak[0]:
                peak = candidate
        log.observe(seg)
        final = seg.end
        if progress is not None:
            progress(min(1.0, seg.t1 / t_end))
        if cancelled is not None and seg.t1 < t_end and cancelled():
            raise Cancelled(f"cancelled at t = {seg.t1:.6g} s")

    history = history_table(case, p, time, samples)
    initial = 0.5 * p.m1 * case.impact_velocity**2
    extremes = fill_extremes(log, peak, stress_extremes(case, p, history, peak), energy_excess(history, initial))
    extremes[L.X_MAX_PENETRATION] = np.max(history["tool/working_end_displacement"])
    extremes[L.X_MAX_TRANSFERRED] = np.max(history["tool/transferred_energy"])
    summary = build_summary(
        case=case,
        numerics=num,
        extremes=extremes,
        contacts=contact_table(log),
        open_contact=log.start if log.in_contact else None,
        energy=final_energy(p, final),
        history=history,
        extra_warnings=[NO_FIELDS_WARNING] if case.outputs.fields else [],
    )
    probe_x = np.asarray(case.outputs.probes, dtype=float)
    probe_stress = quasi_static_stress(case, p, history["contact/force"], history["medium/force"], probe_x)
    return Result(
        case=case,
        numerics=num,
        history=history,
        probe_x=probe_x,
        probe_stress=probe_stress,
        fields=None,
        summary=summary,
    )
