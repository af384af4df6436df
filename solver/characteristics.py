"""An independent reference solver: the rod as waves crossing a chain of uniform cells.

It shares nothing with the finite-difference kernel but the case: its own discretisation, its own
end conditions, its own integrator. The accuracy figures of the solver (`bench/matrix.py`,
`tests/test_matrix.py`) are measured against it.

The tool is cut into N cells of length h, each uniform with its exact mean area (the end cells
with the ends' own areas, which an end's sudden force meets), and each holds
the two waves crossing it, right- and left-going, as the axial force (tension +) each carries,
averaged over the cell: a wave's velocity is ∓(its force)/Z, Z = ρ·a·S the cell's impedance.
With `τ = h/a` every wave crosses one cell a step, and at each joint it is transmitted and
reflected with the exact coefficients of a change of impedance, `2·Z_next/(Z + Z_next)` and
`(Z_next − Z)/(Z + Z_next)` (continuity of force and velocity). That is the exact solution of the
stepped tool, which tends to the tapered one at second order in h; on a uniform tool, and at a
shoulder on a joint, it is exact.

At each end one wave arrives over the step, the mean of the cell it leaves, taken linear within
the step with the smaller of its slopes to the waves arriving just before and just after, none
where they disagree in sign (minmod: second order for a smooth wave, a front kept sharp), and
the end's own equations give the wave it sends back:

- struck end: the striker `m1·y'' = R(t) − F_c`, the contact `F_c = G(δ)·δ + b1·δ'`, `δ = y − u_0`,
  and the end's velocity `u_0' = (F_c + 2·N⁻)/Z`;
- working end: the medium's force `F_m = c2·u_L + b2·u_L'` and `u_L' = −(F_m + 2·N⁺)/Z`.

Each end's equations are integrated by classical Runge–Kutta substeps, as many as their
stiffness needs, split where R(t) jumps or kinks and at every change of sign of δ (located to
round-off); the mean of the end force over the step makes the wave sent back. What the summary
needs is observed as it goes (contact intervals, the extreme end forces at every substep, the
stress of every cell at every step, the work done on the medium and by R), so a run keeps O(N)
memory. Accuracy comes from refinement (`solver.matrix.converged_reference`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .case import Case
from .compiled import compiled
from .grid import area_integral, tool_area, wave_speed
from .kernel.contact import fade_time, rounding_of

FORCE_NONE, FORCE_SINE, FORCE_ABS_SINE, FORCE_PULSE = 0, 1, 2, 3

# Observed quantities (`observed[...]`)
O_PEAK_FORCE, O_PEAK_FORCE_TIME = 0, 1
O_COMPRESSION, O_COMPRESSION_X, O_COMPRESSION_TIME = 2, 3, 4
O_TENSION, O_TENSION_X, O_TENSION_TIME = 5, 6, 7
O_CO_IMPACT, O_REBOUND, O_CONTACTS = 8, 9, 10
O_EXTERNAL_WORK, O_MEDIUM_DISSIPATED, O_MEDIUM_DISPLACEMENT = 11, 12, 13
O_IN_CONTACT, O_CONTACT_START = 14, 15
O_FADE = 16  # how long the overlap took to cross rounding where the first contact ended
OBSERVED = 17

STIFFNESS_STEP = 0.25  # a substep's length times the end's fastest rate
MIN_SUBSTEPS = 4
MAX_SUBSTEPS = 100_000


@compiled()
def _external_force(t, kind, amplitude, omega, start, duration):
    if kind == FORCE_SINE:
        return amplitude * math.sin(omega * t)
    if kind == FORCE_ABS_SINE:
        return amplitude * abs(math.sin(omega * t))
    if kind == FORCE_PULSE and start <= t <= start + duration:
        return amplitude
    return 0.0


@compiled()
def _next_break(t, kind, omega, start, duration):
    """The first instant after t where R(t) jumps or kinks (inf when there is none)."""
    if kind == FORCE_PULSE:
        if t < start:
            return start
        if t < start + duration:
            return start + duration
        return math.inf
    if kind == FORCE_ABS_SINE:
        half = math.pi / omega
        return (math.floor(t / half) + 1.0) * half
    return math.inf


@compiled()
def _spring(delta, c1, alpha, c0):
    """G(δ)·δ and its derivative in δ."""
    if delta >= 0.0:
        return c1 * delta ** (alpha + 1.0), (alpha + 1.0) * c1 * delta**alpha
    return c0 * delta, c0


@compiled()
def _contact_force(y, w, u0, incoming, c1, alpha, c0, b1, z):
    """F_c from the striker (y, w), the struck end u_0 and the arriving wave (`incoming` = 2·N⁻):
    the damper sees `δ' = w − u_0'`, `u_0' = (F_c + incoming)/Z`, solved for F_c."""
    spring, _ = _spring(y - u0, c1, alpha, c0)
    return (spring + b1 * (w - incoming / z)) / (1.0 + b1 / z)


@compiled()
def _arriving(t, p, wave):
    """The arriving wave (2·N⁻ at the struck end) at t: `wave` = (its mean over the step, its
    change over the step), the step starting at p[11] and lasting p[14]."""
    return wave[0] + wave[1] * ((t - p[11]) / p[14] - 0.5)


@compiled()
def _struck_rates(t, s, wave, p, out):
    """d/dt of (y, w, u_0, work of R, impulse of F_c) at the struck end."""
    c1, alpha, c0, b1, m1, z = p[0], p[1], p[2], p[3], p[4], p[5]
    incoming = _arriving(t, p, wave)
    force = _contact_force(s[0], s[1], s[2], incoming, c1, alpha, c0, b1, z)
    r = _external_force(t, int(p[6]), p[7], p[8], p[9], p[10])
    out[0] = s[1]
    out[1] = (r - force) / m1
    out[2] = (incoming + force) / z
    out[3] = r * s[1]
    out[4] = force


@compiled()
def _struck_substep(t, dt, s, wave, p, out, k, stage):
    """One RK4 substep of the struck end from t, written to `out`. R is evaluated on the substep's
    own side of a break (the caller never lets a substep straddle one)."""
    for j in range(4):
        c = (0.0, 0.5, 0.5, 1.0)[j]
        for q in range(5):
            stage[q] = s[q] + (c * dt * k[j - 1, q] if j > 0 else 0.0)
        tt = min(max(t + c * dt, t + 1e-12 * dt), t + dt - 1e-12 * dt)
        _struck_rates(tt, stage, wave, p, k[j])
    for q in range(5):
        out[q] = s[q] + dt / 6.0 * (k[0, q] + 2.0 * k[1, q] + 2.0 * k[2, q] + k[3, q])


@compiled()
def _struck_rate_bound(s, incoming, p):
    """The struck end's fastest rate: contact relaxation against the tool, the striker's
    oscillation on the contact, the damper against the striker."""
    c1, alpha, c0, b1, m1, z = p[0], p[1], p[2], p[3], p[4], p[5]
    # the overlap can grow within the step: take the stiffness a little deeper
    _, k = _spring(abs(s[0] - s[2]) * 1.5 + 1e-300, c1, alpha, c0)
    k = max(k, c0)
    return k / (z + b1) + math.sqrt(k / m1) + b1 * z / (m1 * (z + b1))


@compiled()
def _observe_struck(t, force, area0, obs):
    if force > obs[O_PEAK_FORCE]:
        obs[O_PEAK_FORCE] = force
        obs[O_PEAK_FORCE_TIME] = t
    if force / area0 > obs[O_COMPRESSION]:
        obs[O_COMPRESSION], obs[O_COMPRESSION_X], obs[O_COMPRESSION_TIME] = force / area0, 0.0, t
    if -force / area0 > obs[O_TENSION]:
        obs[O_TENSION], obs[O_TENSION_X], obs[O_TENSION_TIME] = -force / area0, 0.0, t


@compiled()
def _vertex(t0, dt, earliest, f0, f1, f2):
    """Maximum of the parabola through (t0 − dt, f0), (t0, f1), (t0 + dt, f2) when f1 is the
    largest and the four samples from `earliest` (at t0 − 2·dt) are a parabola's (third difference
    small against the second: a parabola through a jump overshoots), and its time; else (f1, t0)."""
    curvature = f0 - 2.0 * f1 + f2
    third = f2 - 3.0 * f1 + 3.0 * f0 - earliest
    if curvature >= 0.0 or abs(third) > 0.5 * abs(curvature):
        return f1, t0
    offset = 0.5 * (f0 - f2) / curvature
    return f1 - 0.25 * (f0 - f2) * offset, t0 + offset * dt


@compiled()
def _struck_end_step(t_step, tau, s, wave, p, obs, prev):
    """Advance the struck end over [t_step, t_step + τ] under the arriving `wave`: substeps,
    breaks of R, events δ = 0 (each located by bisection on the substep length) and the extreme
    contact force (refined by the parabola through three equal substeps; `prev` holds the last three
    substep forces and their spacings). Returns the contact force at the step's end."""
    area0, z = p[12], p[5]
    t_end = t_step + tau
    t = t_step
    out = np.empty(5)
    trial = np.empty(5)
    k = np.empty((4, 5))
    stage = np.empty(5)
    # the force just after the step's start, under the wave arriving now (a front arrives on a
    # step's boundary, and the force can jump there)
    p[11], p[14] = t_step, tau
    _observe_struck(t, _contact_force(s[0], s[1], s[2], _arriving(t, p, wave), p[0], p[1], p[2], p[3], z), area0, obs)
    while t < t_end:
        rate = _struck_rate_bound(s, _arriving(t, p, wave), p)
        n = min(MAX_SUBSTEPS, max(MIN_SUBSTEPS, math.ceil(tau * rate / STIFFNESS_STEP)))
        stop = min(t + tau / n, t_end)
        brk = _next_break(t, int(p[6]), p[8], p[9], p[10])
        if brk <= t * (1.0 + 1e-15):
            brk = _next_break(t * (1.0 + 1e-15) + 1e-300, int(p[6]), p[8], p[9], p[10])
        if brk < stop:
            stop = brk
        h = stop - t
        _struck_substep(t, h, s, wave, p, out, k, stage)
        before = s[0] - s[2]
        after = out[0] - out[2]
        crossed_down = before >= 0.0 and after < 0.0
        crossed_up = before < 0.0 and after >= 0.0
        if crossed_down or crossed_up:
            # the crossing, to round-off: bisect the substep's length
            lo, hi = 0.0, h
            for _ in range(80):
                mid = 0.5 * (lo + hi)
                _struck_substep(t, mid, s, wave, p, trial, k, stage)
                if (trial[0] - trial[2] < 0.0) == crossed_down:
                    hi = mid
                else:
                    lo = mid
                if hi - lo <= 1e-15 * max(t, tau):
                    break
            _struck_substep(t, hi, s, wave, p, out, k, stage)
            stop = t + hi
            if crossed_down:
                count = int(obs[O_CONTACTS])
                if count == 0:
                    obs[O_CO_IMPACT] = stop
                    obs[O_REBOUND] = out[1]
                    incoming = _arriving(stop, p, wave)
                    parted = _contact_force(out[0], out[1], out[2], incoming, p[0], p[1], p[2], p[3], z)
                    obs[O_FADE] = fade_time(rounding_of(out[0], out[2]), out[1] - (incoming + parted) / z)
                obs[O_CONTACTS] = count + 1
                obs[O_IN_CONTACT] = 0.0
            else:
                obs[O_IN_CONTACT] = 1.0
                obs[O_CONTACT_START] = stop
        force = _contact_force(out[0], out[1], out[2], _arriving(stop, p, wave), p[0], p[1], p[2], p[3], z)
        _observe_struck(stop, force, area0, obs)
        # the extreme force between substeps of equal length
        h_prev, f_prev, f_prev2, f_prev3 = prev[0], prev[1], prev[2], prev[3]
        if (
            abs(h_prev - (stop - t)) <= 1e-9 * h_prev
            and abs(prev[4] - h_prev) <= 1e-9 * h_prev
            and f_prev >= f_prev2
            and f_prev > force
        ):
            value, when = _vertex(t, h_prev, f_prev3, f_prev2, f_prev, force)
            if value > obs[O_PEAK_FORCE]:
                obs[O_PEAK_FORCE], obs[O_PEAK_FORCE_TIME] = value, when
            if value / area0 > obs[O_COMPRESSION]:
                obs[O_COMPRESSION], obs[O_COMPRESSION_X], obs[O_COMPRESSION_TIME] = (value / area0, 0.0, when)
        prev[4], prev[0], prev[1], prev[2], prev[3] = h_prev, stop - t, force, f_prev, f_prev2
        for q in range(5):
            s[q] = out[q]
        t = stop
    return _contact_force(s[0], s[1], s[2], _arriving(t_end, p, wave), p[0], p[1], p[2], p[3], z)


@compiled()
def _working_end_step(tau, s, wave, c2, b2, z, area, t_step, length, obs):
    """Advance the working end over one step under the arriving `wave` (2·N⁺: its mean and change
    over the step): RK4 substeps of `u_L' = −(incoming + c2·u_L)/(Z + b2)`, with ∫b2·u_L'² and ∫F_m
    in `s[1]`, `s[2]`; the working-end stress observed at each. Returns the medium's force at the
    end."""
    rate = c2 / (z + b2)
    n = min(MAX_SUBSTEPS, max(MIN_SUBSTEPS, math.ceil(tau * rate / STIFFNESS_STEP)))
    dt = tau / n
    k = np.empty((4, 3))
    incoming = wave[0] - 0.5 * wave[1]
    force = c2 * s[0] - b2 * (incoming + c2 * s[0]) / (z + b2)  # just after the step's start
    if force / area > obs[O_COMPRESSION]:
        obs[O_COMPRESSION], obs[O_COMPRESSION_X], obs[O_COMPRESSION_TIME] = force / area, length, t_step
    if -force / area > obs[O_TENSION]:
        obs[O_TENSION], obs[O_TENSION_X], obs[O_TENSION_TIME] = -force / area, length, t_step
    for j_sub in range(n):
        base = s[0]
        for j in range(4):
            c = (0.0, 0.5, 0.5, 1.0)[j]
            u = base + (c * dt * k[j - 1, 0] if j > 0 else 0.0)
            incoming = wave[0] + wave[1] * ((j_sub + c) * dt / tau - 0.5)
            v = -(incoming + c2 * u) / (z + b2)
            k[j, 0], k[j, 1], k[j, 2] = v, b2 * v * v, c2 * u + b2 * v
        for q in range(3):
            s[q] += dt / 6.0 * (k[0, q] + 2.0 * k[1, q] + 2.0 * k[2, q] + k[3, q])
        incoming = wave[0] + wave[1] * ((j_sub + 1) * dt / tau - 0.5)
        v = -(incoming + c2 * s[0]) / (z + b2)
        force = c2 * s[0] + b2 * v
        when = t_step + (j_sub + 1) * dt
        if force / area > obs[O_COMPRESSION]:
            obs[O_COMPRESSION], obs[O_COMPRESSION_X], obs[O_COMPRESSION_TIME] = force / area, length, when
        if -force / area > obs[O_TENSION]:
            obs[O_TENSION], obs[O_TENSION_X], obs[O_TENSION_TIME] = -force / area, length, when
    incoming = wave[0] + 0.5 * wave[1]
    return c2 * s[0] - b2 * (incoming + c2 * s[0]) / (z + b2)


@compiled()
def _limited(before, now, after):
    """The change over a step of a wave whose means over it and its neighbours are given: the
    smaller of the two one-sided changes, 0 where they disagree in sign (minmod)."""
    left, right = now - before, after - now
    if left * right <= 0.0:
        return 0.0
    return left if abs(left) < abs(right) else right


@compiled()
def _run(h, tau, steps, last_fraction, cell_area, cell_z, striker, medium, obs, history, stride):
    """March `steps` whole steps and a last one of `last_fraction`·τ (the ends only: the run ends
    at exactly the duration). Cell j holds its right- and left-going waves' forces; `striker`
    packs the struck end's parameters (with the area at x = 0), `medium` (c2, b2, the area at
    x = L)."""
    n = len(cell_z)
    right = np.zeros(n)
    left = np.zeros(n)
    new_right = np.zeros(n)
    new_left = np.zeros(n)
    struck = np.zeros(5)  # y, w, u_0, work of R, impulse of F_c
    struck[1] = striker[13]  # W1
    working = np.zeros(3)  # u_L, dissipated by b2, impulse of F_m
    prev = np.zeros(5)
    wave = np.zeros(2)
    far_wave = np.zeros(2)
    last_in = last_far = 0.0
    c2, b2 = medium[0], medium[1]
    length = n * h
    _observe_struck(
        0.0,
        _contact_force(0.0, striker[13], 0.0, 0.0, striker[0], striker[1], striker[2], striker[3], cell_z[0]),
        striker[12],
        obs,
    )
    obs[O_IN_CONTACT] = 1.0
    kept = 0
    for m in range(steps + 1):
        whole = m < steps
        span = tau if whole else last_fraction * tau
        if span <= 0.0:
            break
        t = m * tau
        # the waves arriving at the ends now, and those to arrive next (through the joint next to
        # the end, with what the end sent last)
        arriving = left[0]
        far_arriving = right[n - 1]
        if n > 1:
            z_a, z_b = cell_z[0], cell_z[1]
            next_in = ((z_b - z_a) * right[0] + 2.0 * z_a * left[1]) / (z_a + z_b)
            z_a, z_b = cell_z[n - 2], cell_z[n - 1]
            next_far = (2.0 * z_b * right[n - 2] + (z_a - z_b) * left[n - 1]) / (z_a + z_b)
        else:
            next_in, next_far = right[0], left[0]
        # over the step (or the first `frac` of it, the run's last): mean and change, ×2
        frac = span / tau
        change = 2.0 * _limited(last_in, arriving, next_in)
        wave[0], wave[1] = 2.0 * arriving + 0.5 * (frac - 1.0) * change, change * frac
        change = 2.0 * _limited(last_far, far_arriving, next_far)
        far_wave[0], far_wave[1] = 2.0 * far_arriving + 0.5 * (frac - 1.0) * change, change * frac
        last_in, last_far = arriving, far_arriving
        impulse = struck[4]
        end_force = _struck_end_step(t, span, struck, wave, striker, obs, prev)
        far_impulse = working[2]
        medium_force = _working_end_step(span, working, far_wave, c2, b2, cell_z[n - 1], medium[2], t, length, obs)
        if not whole:
            break
        # each wave crosses its cell; at each joint it is transmitted and reflected
        for j in range(n - 1):
            z_a, z_b = cell_z[j], cell_z[j + 1]
            a, b = right[j], left[j + 1]
            new_right[j + 1] = (2.0 * z_b * a + (z_a - z_b) * b) / (z_a + z_b)
            new_left[j] = ((z_b - z_a) * a + 2.0 * z_a * b) / (z_a + z_b)
        # what the ends sent back: the mean over the step of their force, less the arriving wave
        new_right[0] = -(struck[4] - impulse) / tau - arriving
        new_left[n - 1] = -(working[2] - far_impulse) / tau - far_arriving
        t_new = t + tau
        for j in range(n):
            stress = (new_right[j] + new_left[j]) / cell_area[j]
            if -stress > obs[O_COMPRESSION]:
                obs[O_COMPRESSION], obs[O_COMPRESSION_X], obs[O_COMPRESSION_TIME] = (-stress, (j + 0.5) * h, t_new)
            if stress > obs[O_TENSION]:
                obs[O_TENSION], obs[O_TENSION_X], obs[O_TENSION_TIME] = stress, (j + 0.5) * h, t_new
        if stride > 0 and (m + 1) % stride == 0 and kept < history.shape[1]:
            history[0, kept] = t_new
            history[1, kept] = end_force
            history[2, kept] = medium_force
            history[3, kept] = struck[1]
            kept += 1
        right, new_right = new_right, right
        left, new_left = new_left, left
    obs[O_EXTERNAL_WORK] = struck[3]
    obs[O_MEDIUM_DISSIPATED] = working[1]
    obs[O_MEDIUM_DISPLACEMENT] = working[0]
    return kept


@dataclass
class Reference:
    """What a characteristics run observed, in the summary's terms (SI)."""

    cells: int
    co_impact_time: float | None
    striker_rebound_velocity: float | None
    contact_fade_time: float | None
    peak_contact_force: float
    peak_contact_force_time: float
    max_compressive_stress: float
    max_compressive_stress_x: float
    max_tensile_stress: float
    max_tensile_stress_x: float
    to_medium: float
    external_work: float
    initial: float
    contacts: int
    history: dict[str, np.ndarray]

    @property
    def transfer_efficiency(self) -> float:
        return self.to_medium / (self.initial + self.external_work)

    def headline(self) -> dict[str, float | None]:
        """The headline quantities under their summary names."""
        return {
            "co_impact_time": self.co_impact_time,
            "peak_contact_force": self.peak_contact_force,
            "max_compressive_stress": self.max_compressive_stress,
            "max_tensile_stress": self.max_tensile_stress,
            "energy.to_medium": self.to_medium,
            "striker_rebound_velocity": self.striker_rebound_velocity,
        }


def _force_code(case: Case) -> tuple[int, float, float, float, float]:
    f = case.force
    if f is None:
        return FORCE_NONE, 0.0, 0.0, 0.0, 0.0
    if f.kind == "pulse":
        return FORCE_PULSE, f.amplitude, 0.0, f.start, f.duration
    return (FORCE_SINE if f.kind == "sine" else FORCE_ABS_SINE), f.amplitude, f.omega, 0.0, 0.0


def solve(case: Case, cells: int, history_points: int = 0) -> Reference:
    """The case by characteristics on `cells` cells (τ = h/a), to exactly `numerics.duration`.

    With `history_points`, the contact force, the medium force and the striker's velocity are
    kept at about that many instants (`history`: time, contact, medium, striker_velocity).
    """
    tool = case.tool
    a = wave_speed(tool)
    h = tool.length / cells
    tau = h / a
    duration = case.numerics.duration
    steps = int(math.floor(duration / tau * (1.0 + 1e-14)))
    last_fraction = max(0.0, duration / tau - steps)
    cell_area = np.diff(area_integral(tool, np.linspace(0.0, tool.length, cells + 1))) / h
    # the end cells at the ends' own areas: an end answers a sudden force through the impedance
    # just inside it (a cell mean would put it O(h) off on a taper)
    cell_area[[0, -1]] = tool_area(tool, np.array([0.0, tool.length]))
    cell_z = tool.density * a * cell_area
    c = case.contact
    kind, amplitude, omega, start, pulse = _force_code(case)
    end_areas = tool_area(tool, np.array([0.0, tool.length]))
    striker = np.array(
        [
            c.stiffness,
            c.exponent,
            c.tension_stiffness,
            c.damping,
            case.striker.mass,
            cell_z[0],
            kind,
            amplitude,
            omega,
            start,
            pulse,
            0.0,
            end_areas[0],
            case.impact_velocity,
            0.0,
        ]
    )
    medium = np.array(
        [case.medium.stiffness if case.medium else 0.0, case.medium.damping if case.medium else 0.0, end_areas[1]]
    )
    obs = np.zeros(OBSERVED)
    obs[O_CO_IMPACT] = obs[O_REBOUND] = obs[O_FADE] = np.nan
    stride = max(1, steps // history_points) if history_points else 0
    history = np.zeros((4, steps // stride + 1 if stride else 0))
    kept = _run(h, tau, steps, last_fraction, cell_area, cell_z, striker, medium, obs, history, stride)
    c2 = medium[0]
    to_medium = 0.5 * c2 * obs[O_MEDIUM_DISPLACEMENT] ** 2 + obs[O_MEDIUM_DISSIPATED]
    contacts = int(obs[O_CONTACTS]) + (1 if obs[O_IN_CONTACT] else 0)
    return Reference(
        cells=cells,
        co_impact_time=None if math.isnan(obs[O_CO_IMPACT]) else float(obs[O_CO_IMPACT]),
        striker_rebound_velocity=None if math.isnan(obs[O_REBOUND]) else float(obs[O_REBOUND]),
        contact_fade_time=None if math.isnan(obs[O_FADE]) else float(obs[O_FADE]),
        peak_contact_force=float(obs[O_PEAK_FORCE]),
        peak_contact_force_time=float(obs[O_PEAK_FORCE_TIME]),
        max_compressive_stress=float(obs[O_COMPRESSION]),
        max_compressive_stress_x=float(obs[O_COMPRESSION_X]),
        max_tensile_stress=float(obs[O_TENSION]),
        max_tensile_stress_x=float(obs[O_TENSION_X]),
        to_medium=float(to_medium),
        external_work=float(obs[O_EXTERNAL_WORK]),
        initial=0.5 * case.striker.mass * case.impact_velocity**2,
        contacts=contacts,
        history={
            name: history[k, :kept].copy() for k, name in enumerate(("time", "contact", "medium", "striker_velocity"))
        },
    )
