"""The struck end driven by a given history (`struck_end`): a measured force or velocity in the
place of a striker, for the ends that integrate their own equations.

The end node moves as a rod's end does, `u_0' = F/Z + 2·v_in`, under the wave arriving at it
(`v_in`, linear over the step: `incoming_wave`). Driven by its force F(t), that is its velocity;
driven by its velocity v(t), it pushes with `F = Z·(v − 2·v_in)`. The history is linear between its
instants, so over each piece of a step between them F and u_0' are linear in time: the end's
displacement (their trapezoid) and the work done on the tool, `∫F·u_0' dt` (Simpson's rule, exact
for the product), are exact. Before the history's first instant and after its last the end is
free (F = 0). Its time counts from the blow's start (`S_BLOW_START`).

The striker's slots stay still: its face rides the end (δ = 0, no contact, no energy of its own),
so the audit and the records read the end's force as the contact's.
"""

from __future__ import annotations

import math

import numpy as np

from ..compiled import compiled
from .bundles import (
    DRIVEN_BY_FORCE,
    END_ANVIL_FORCE,
    END_CONTACT_FORCE,
    END_IMPULSE,
    END_IN_CONTACT,
    END_STRIKER_DISP,
    END_STRIKER_VELOCITY,
    END_TOOL_DISP,
)


@compiled(inline="always")
def piece(t, striker):
    """The piece of the history that holds t (s from the blow's start): `(inside, value at t,
    slope)`; outside its instants the end is free."""
    time, values = striker.signal_time, striker.signal_values
    last = time.shape[0] - 1
    if t < time[0] or t >= time[last]:
        return False, 0.0, 0.0
    k = min(np.searchsorted(time, t, side="right") - 1, last - 1)
    slope = (values[k + 1] - values[k]) / (time[k + 1] - time[k])
    return True, values[k] + slope * (t - time[k]), slope


@compiled(inline="always")
def driven_force(inside, value, v_in, impedance, striker):
    """`(F, u_0')`: the end's force and velocity under the history's `value` (when `inside` it)
    and the arriving wave's rate `v_in`."""
    if not inside:
        return 0.0, 2.0 * v_in
    if striker.driver == DRIVEN_BY_FORCE:
        return value, value / impedance + 2.0 * v_in
    return impedance * (value - 2.0 * v_in), value


@compiled(inline="always")
def next_instant(t, striker):
    """The history's first instant after t (s from the blow's start; ∞ past its last)."""
    time = striker.signal_time
    k = np.searchsorted(time, t, side="right")
    return time[k] if k < time.shape[0] else math.inf


@compiled()
def driven_end_step(t0, tau, state, v_mean, v_slope, contact, striker, blow_start):
    """Advance the driven struck end over [t0, t0 + τ] under the arriving wave's rate
    `v_in(t) = v_mean + v_slope·(t − t0 − τ/2)`, split at the history's instants. `state` (its
    slots `END_…`) at t0 on entry, at t0 + τ on return. Returns as `struck_end_step` does: the
    work done on the tool, nothing dissipated, no contact crossed, and the end force's extremes
    `(largest, its time)` and `(largest, its time, least, its time)` at the pieces' ends."""
    z = contact.impedance
    v_start = v_mean - 0.5 * tau * v_slope
    u0 = state[END_TOOL_DISP]
    work = 0.0
    t_a, t_end = t0, t0 + tau
    inside, value, _ = piece(t_a - blow_start, striker)
    f = driven_force(inside, value, v_start, z, striker)[0]
    f_max, t_max, f_min, t_min = f, t0, f, t0
    while t_a < t_end:
        t_b = min(t_end, blow_start + next_instant(t_a - blow_start, striker))
        if not t_b > t_a:  # an instant that rounding puts at t_a: the next piece
            t_b = t_end
        t_m = 0.5 * (t_a + t_b)
        inside, value_m, slope = piece(t_m - blow_start, striker)
        f_a, rate_a = driven_force(inside, value_m + slope * (t_a - t_m), v_start + v_slope * (t_a - t0), z, striker)
        f_m, rate_m = driven_force(inside, value_m, v_start + v_slope * (t_m - t0), z, striker)
        f, rate_b = driven_force(inside, value_m + slope * (t_b - t_m), v_start + v_slope * (t_b - t0), z, striker)
        span = t_b - t_a
        u0 += span * (rate_a + rate_b) * 0.5
        work += span * (f_a * rate_a + 4.0 * f_m * rate_m + f * rate_b) / 6.0
        for force, at in ((f_a, t_a), (f, t_b)):
            if force > f_max:
                f_max, t_max = force, at
            if force < f_min:
                f_min, t_min = force, at
        t_a = t_b
    state[END_TOOL_DISP] = u0
    state[END_STRIKER_DISP] = u0
    state[END_STRIKER_VELOCITY] = 0.0
    state[END_CONTACT_FORCE] = f
    state[END_ANVIL_FORCE] = f
    state[END_IMPULSE] = 0.0
    state[END_IN_CONTACT] = 0.0
    return work, 0.0, 0, (f_max, t_max), (f_max, t_max, f_min, t_min)
