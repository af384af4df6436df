"""The time-stepping kernel: the paper's weighted scheme (8)–(13), one tridiagonal solve a step.

Unknowns of layer n+1 are `[y, u_0, …, u_N]` (model.md). The rows `u_1 … u_N` never change from
step to step (only their right-hand sides do), so their elimination, swept from the working end
toward the struck end as in the paper's (14)–(20), is factored once in `factor_tool_rows`:
`u_i = P_i·u_{i−1} + Q_i`. A step then computes the `Q_i` (one pass), solves the 2×2 system of
the striker row (11) and the struck-end row (9) with the lagged contact stiffness `G(δ^n)`, and
substitutes forward (one pass). Everything the summary needs (contact intervals, peaks, the
energy audit) is observed inside the loop, so a summary-only run keeps nothing of size N·M.

All arrays are float64. Layers n−1, n, n+1 of the tool live in rows `(n−1)%3, n%3, (n+1)%3` of
`u` (3 × (N+1)) and of the striker's `y` (3), so no state but the layer index is carried between
chunks.
"""

from __future__ import annotations

import numpy as np
from numba import njit

# Force kinds (`force_kind`)
FORCE_NONE, FORCE_SINE, FORCE_ABS_SINE, FORCE_PULSE = 0, 1, 2, 3

# History columns, one row per kept layer
H_TIME, H_STRIKER_DISP, H_STRIKER_VEL, H_STRUCK_END, H_WORKING_END = 0, 1, 2, 3, 4
H_CONTACT_FORCE, H_OVERLAP, H_MEDIUM_FORCE, H_EXTERNAL_FORCE = 5, 6, 7, 8
H_EXTERNAL_WORK, H_DISSIPATED_CONTACT, H_DISSIPATED_MEDIUM = 9, 10, 11
H_STRIKER_KINETIC, H_TOOL_KINETIC, H_TOOL_STRAIN, H_CONTACT_POTENTIAL, H_MEDIUM_POTENTIAL = (
    12, 13, 14, 15, 16)
HISTORY_COLUMNS = 17

# Tracker slots (running extremes and contact state)
T_PEAK_FORCE, T_PEAK_FORCE_TIME = 0, 1
T_MAX_COMPRESSION, T_MAX_COMPRESSION_X, T_MAX_COMPRESSION_TIME = 2, 3, 4
T_MAX_TENSION, T_MAX_TENSION_X, T_MAX_TENSION_TIME = 5, 6, 7
T_IN_CONTACT, T_CONTACT_START, T_CONTACTS = 8, 9, 10
T_CO_IMPACT, T_REBOUND_VELOCITY = 11, 12
T_ENERGY_EXCESS = 13  # max over time of (stored + dissipated − input): > 0 means energy created
T_FAILED_TIME = 14
T_MIN_CONTACT_STEPS = 15  # fewest steps any finished contact interval was resolved by
TRACKER_SLOTS = 16

# Energy slots: running work and dissipation, and the stored terms of the last layer
E_EXTERNAL_WORK, E_DISSIPATED_CONTACT, E_DISSIPATED_MEDIUM = 0, 1, 2
E_STRIKER_KINETIC, E_TOOL_KINETIC, E_TOOL_STRAIN, E_CONTACT_POTENTIAL, E_MEDIUM_POTENTIAL = (
    3, 4, 5, 6, 7)
ENERGY_SLOTS = 8

STATUS_OK, STATUS_NON_FINITE = 0, 1


def new_trackers() -> np.ndarray:
    t = np.zeros(TRACKER_SLOTS)
    t[T_CO_IMPACT] = np.nan
    t[T_REBOUND_VELOCITY] = np.nan
    t[T_FAILED_TIME] = np.nan
    t[T_MIN_CONTACT_STEPS] = np.inf
    return t


def factor_tool_rows(q, area, h, youngs_modulus, medium_stiffness, medium_damping, r, gamma, tau):
    """Eliminate rows u_N … u_1 once: returns `P`, `1/den` and the interior upper coefficients.

    Row u_N (10): `−k_N·u_{N−1} + (k_N + c2 + b2/τ)·u_N = (b2/τ)·u_N^n`, `k_N = S_N·E/h`.
    Rows u_i (8): `−γr(1−q_i)·u_{i−1} + (1+2γr)·u_i − γr(1+q_i)·u_{i+1} = rhs_i`.
    """
    n = len(q) - 1
    p = np.zeros(n + 1)
    inv_den = np.zeros(n + 1)
    upper = -gamma * r * (1.0 + q)
    k_n = area[n] * youngs_modulus / h
    diag_n = k_n + medium_stiffness + medium_damping / tau
    p[n] = k_n / diag_n
    inv_den[n] = 1.0 / diag_n
    for i in range(n - 1, 0, -1):
        den = 1.0 + 2.0 * gamma * r + upper[i] * p[i + 1]
        p[i] = gamma * r * (1.0 - q[i]) / den
        inv_den[i] = 1.0 / den
    return p, inv_den, upper


@njit(cache=True, inline="always")
def external_force(t, kind, amplitude, omega, start, duration):
    """`R(t)`: P·sin(ωt), P·|sin(ωt)|, or P on [t1, t1 + Δt]."""
    if kind == FORCE_SINE:
        return amplitude * np.sin(omega * t)
    if kind == FORCE_ABS_SINE:
        return amplitude * abs(np.sin(omega * t))
    if kind == FORCE_PULSE:
        if start <= t <= start + duration:
            return amplitude
    return 0.0


@njit(cache=True, inline="always")
def contact_stiffness(delta, c1, alpha, c0):
    """`G(δ)` of (7): `c1·δ^α` in contact, `c0` in separation."""
    if delta >= 0.0:
        if alpha == 0.0:
            return c1
        return c1 * delta**alpha
    return c0


@njit(cache=True, inline="always")
def contact_potential(delta, c1, alpha, c0):
    """Energy stored in the contact: `c1·δ^(α+2)/(α+2)`, or `c0·δ²/2` in separation."""
    if delta >= 0.0:
        return c1 * delta ** (alpha + 2.0) / (alpha + 2.0)
    return 0.5 * c0 * delta * delta


@njit(cache=True, inline="always")
def node_stress(u, i, n, e_over_h):
    """`σ_i = E·∂u/∂x` (tension +): central inside, one-sided at the ends (= end force / S)."""
    if i == 0:
        return e_over_h * (u[1] - u[0])
    if i == n:
        return e_over_h * (u[n] - u[n - 1])
    return 0.5 * e_over_h * (u[i + 1] - u[i - 1])


@njit(cache=True)
def advance(
    first, last,
    u, y, q, area, area_mid, p, inv_den, upper,
    h, tau, r, gamma, youngs_modulus, density,
    striker_mass, striker_velocity,
    c1, alpha, c0, b1, c2, b2,
    force_kind, force_amplitude, force_omega, force_start, force_duration,
    trackers, energy, contacts,
    history, history_stride, probe_node, probe_weight, probes,
    field_u, field_stress, field_stride,
):
    """Compute layers `first … last` (inclusive; layer 0 is the initial state).

    Writes every `history_stride`-th layer to `history`/`probes` and every `field_stride`-th to
    `field_u`/`field_stress` (strides ≤ 0 keep nothing), from row 0 of each buffer. Returns
    `(status, rows of history written, rows of fields written)`; on a non-finite value it stops
    with `STATUS_NON_FINITE` and the time in `trackers[T_FAILED_TIME]`.
    """
    n = len(q) - 1
    m1_tau2 = striker_mass / (tau * tau)
    b1_tau = b1 / tau
    b2_tau = b2 / tau
    k0 = area[0] * youngs_modulus / h
    w_explicit = (1.0 - gamma) * r
    e_over_h = youngs_modulus / h
    kinetic_factor = 0.5 * density * h / (tau * tau)
    strain_factor = 0.5 * youngs_modulus / h
    initial_energy = 0.5 * striker_mass * striker_velocity * striker_velocity
    n_hist = 0
    n_field = 0

    for m in range(first, last + 1):
        new = m % 3
        cur = (m - 1) % 3
        old = (m - 2) % 3
        t = m * tau
        un = u[new]
        uc = u[cur]
        uo = u[old]
        if m == 0:
            # (5), (6): tool at rest, striker at 0 moving at W1.
            for i in range(n + 1):
                un[i] = 0.0
            y[new] = 0.0
            y_cur = 0.0
            delta_cur = 0.0
            contact_force = 0.0
            medium_force = 0.0
            velocity = striker_velocity
        else:
            y_cur = y[cur]
            delta_cur = y_cur - uc[0]
            g = contact_stiffness(delta_cur, c1, alpha, c0)
            r_n = external_force((m - 1) * tau, force_kind, force_amplitude, force_omega,
                                 force_start, force_duration)  # R(t_n), explicit in row (11)
            if m == 1:
                # (12), (13): first order in τ, the tool (struck end included) still at rest.
                for i in range(n + 1):
                    un[i] = 0.0
                y[new] = striker_velocity * tau
            else:
                # Right-hand sides of rows u_N … u_1, eliminated toward the struck end.
                qn = b2_tau * uc[n] * inv_den[n]
                un[n] = qn  # Q_i is kept in `un` until the forward substitution overwrites it
                for i in range(n - 1, 0, -1):
                    lap = uc[i + 1] - 2.0 * uc[i] + uc[i - 1] + q[i] * (uc[i + 1] - uc[i - 1])
                    rhs = 2.0 * uc[i] - uo[i] + w_explicit * lap
                    un[i] = (rhs - upper[i] * un[i + 1]) * inv_den[i]
                # Striker row (11) and struck-end row (9) with u_1 = P_1·u_0 + Q_1.
                gb = g + b1_tau
                rel = b1_tau * (y_cur - uc[0])
                a11 = m1_tau2 + gb
                a12 = -gb
                b_y = m1_tau2 * (2.0 * y_cur - y[old]) + rel + r_n
                a21 = gb
                a22 = -(k0 * (1.0 - p[1]) + gb)
                b_0 = rel - k0 * un[1]
                det = a11 * a22 - a12 * a21
                y_new = (b_y * a22 - a12 * b_0) / det
                u0_new = (a11 * b_0 - a21 * b_y) / det
                if not (abs(y_new) < 1e300 and abs(u0_new) < 1e300):
                    trackers[T_FAILED_TIME] = t
                    return STATUS_NON_FINITE, n_hist, n_field
                y[new] = y_new
                un[0] = u0_new
                for i in range(1, n + 1):
                    un[i] = p[i] * un[i - 1] + un[i]
            y_new = y[new]
            delta = y_new - un[0]
            contact_force = g * delta + b1_tau * (delta - delta_cur)
            medium_force = c2 * un[n] + b2_tau * (un[n] - uc[n])
            if m == 1:
                velocity = striker_velocity
            else:
                velocity = (3.0 * y_new - 4.0 * y_cur + y[old]) / (2.0 * tau)

            # Energy at layer m − 1/2: velocities from (m−1, m), positions at their midpoint.
            dy = y_new - y_cur
            striker_kinetic = 0.5 * striker_mass * dy * dy / (tau * tau)
            tool_kinetic = 0.0
            for i in range(1, n):
                du = un[i] - uc[i]
                tool_kinetic += area[i] * du * du
            tool_kinetic *= kinetic_factor
            tool_strain = 0.0
            for i in range(n):
                de = (un[i + 1] + uc[i + 1]) - (un[i] + uc[i])
                tool_strain += area_mid[i] * de * de
            tool_strain *= 0.25 * strain_factor
            contact_pot = contact_potential(0.5 * (delta + delta_cur), c1, alpha, c0)
            un_mid = 0.5 * (un[n] + uc[n])
            medium_pot = 0.5 * c2 * un_mid * un_mid
            if m >= 2:
                energy[E_EXTERNAL_WORK] += r_n * 0.5 * (y_new - y[old])
            dd = delta - delta_cur
            energy[E_DISSIPATED_CONTACT] += b1_tau * dd * dd
            dn = un[n] - uc[n]
            energy[E_DISSIPATED_MEDIUM] += b2_tau * dn * dn
            energy[E_STRIKER_KINETIC] = striker_kinetic
            energy[E_TOOL_KINETIC] = tool_kinetic
            energy[E_TOOL_STRAIN] = tool_strain
            energy[E_CONTACT_POTENTIAL] = contact_pot
            energy[E_MEDIUM_POTENTIAL] = medium_pot
            balance = (striker_kinetic + tool_kinetic + tool_strain + contact_pot + medium_pot
                       + energy[E_DISSIPATED_CONTACT] + energy[E_DISSIPATED_MEDIUM]
                       - initial_energy - energy[E_EXTERNAL_WORK])
            if not abs(balance) < 1e300:
                trackers[T_FAILED_TIME] = t
                return STATUS_NON_FINITE, n_hist, n_field
            if balance > trackers[T_ENERGY_EXCESS]:
                trackers[T_ENERGY_EXCESS] = balance

            # Stress extremes along the tool.
            for i in range(n + 1):
                s = node_stress(un, i, n, e_over_h)
                if -s > trackers[T_MAX_COMPRESSION]:
                    trackers[T_MAX_COMPRESSION] = -s
                    trackers[T_MAX_COMPRESSION_X] = i * h
                    trackers[T_MAX_COMPRESSION_TIME] = t
                if s > trackers[T_MAX_TENSION]:
                    trackers[T_MAX_TENSION] = s
                    trackers[T_MAX_TENSION_X] = i * h
                    trackers[T_MAX_TENSION_TIME] = t
            if contact_force > trackers[T_PEAK_FORCE]:
                trackers[T_PEAK_FORCE] = contact_force
                trackers[T_PEAK_FORCE_TIME] = t

            # Contact intervals: δ ≥ 0 is contact; crossings are placed by linear interpolation.
            in_contact = trackers[T_IN_CONTACT] != 0.0
            if in_contact and delta < 0.0:
                t_cross = t - tau + tau * delta_cur / (delta_cur - delta)
                k = int(trackers[T_CONTACTS])
                if k < contacts.shape[0]:
                    contacts[k, 0] = trackers[T_CONTACT_START]
                    contacts[k, 1] = t_cross
                trackers[T_CONTACTS] = k + 1
                steps = (t_cross - trackers[T_CONTACT_START]) / tau
                if steps < trackers[T_MIN_CONTACT_STEPS]:
                    trackers[T_MIN_CONTACT_STEPS] = steps
                if k == 0:
                    trackers[T_CO_IMPACT] = t_cross
                    trackers[T_REBOUND_VELOCITY] = dy / tau
                trackers[T_IN_CONTACT] = 0.0
            elif not in_contact and delta >= 0.0:
                trackers[T_IN_CONTACT] = 1.0
                trackers[T_CONTACT_START] = t - tau + tau * (-delta_cur) / (delta - delta_cur)

        if m == 0:
            trackers[T_IN_CONTACT] = 1.0  # δ(0) = 0: contact from the first instant
            trackers[T_CONTACT_START] = 0.0

        if history_stride > 0 and m % history_stride == 0:
            row = history[n_hist]
            row[H_TIME] = t
            row[H_STRIKER_DISP] = y[new]
            row[H_STRIKER_VEL] = velocity
            row[H_STRUCK_END] = un[0]
            row[H_WORKING_END] = un[n]
            row[H_CONTACT_FORCE] = contact_force
            row[H_OVERLAP] = y[new] - un[0]
            row[H_MEDIUM_FORCE] = medium_force
            row[H_EXTERNAL_FORCE] = external_force(
                t, force_kind, force_amplitude, force_omega, force_start, force_duration)
            row[H_EXTERNAL_WORK] = energy[E_EXTERNAL_WORK]
            row[H_DISSIPATED_CONTACT] = energy[E_DISSIPATED_CONTACT]
            row[H_DISSIPATED_MEDIUM] = energy[E_DISSIPATED_MEDIUM]
            if m == 0:
                row[H_STRIKER_KINETIC] = initial_energy
                for c in range(H_TOOL_KINETIC, HISTORY_COLUMNS):
                    row[c] = 0.0
            else:
                row[H_STRIKER_KINETIC] = energy[E_STRIKER_KINETIC]
                row[H_TOOL_KINETIC] = energy[E_TOOL_KINETIC]
                row[H_TOOL_STRAIN] = energy[E_TOOL_STRAIN]
                row[H_CONTACT_POTENTIAL] = energy[E_CONTACT_POTENTIAL]
                row[H_MEDIUM_POTENTIAL] = energy[E_MEDIUM_POTENTIAL]
            for k in range(len(probe_node)):
                j = probe_node[k]
                w = probe_weight[k]
                s = (1.0 - w) * node_stress(un, j, n, e_over_h)
                if w > 0.0:
                    s += w * node_stress(un, j + 1, n, e_over_h)
                probes[n_hist, k] = s
            n_hist += 1
        if field_stride > 0 and m % field_stride == 0:
            for i in range(n + 1):
                field_u[n_field, i] = un[i]
                field_stress[n_field, i] = node_stress(un, i, n, e_over_h)
            n_field += 1
    return STATUS_OK, n_hist, n_field
