"""A hammer's flight between two blows, compiled (`drive.fly` sets it up and reads it): the
striker under the drive's pressures, an ODE in (y, y', V_gas) with the work on the striker of the
supply, of the return line and of friction, integrated by the classical Runge–Kutta method with
step doubling (a step's error is the difference of one step and two half steps over 15, and the
two half steps, extrapolated by it, are kept) to a relative tolerance, until the striker passes
the switch point or strikes, located on the cubic through the step's ends (positions and
velocities). A flight took 3–7 ms in `scipy.integrate.solve_ivp`, whose steps are Python; here
about a hundredth of that, so that the cycles of a ladder's every grid cost little beside its blows.
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np

from ..compiled import compiled
from .struck_end import hermite, hermite_root

# The drive (SI), as `drive.Hydraulics` gives it, with the gas volumes at which the supply is
# relieved (at its pressure) and at which the accumulator is empty (all gas), and whether a pump
# feeds it (`pumped`, 1.0 or 0.0)
FlightDrive = namedtuple(
    "FlightDrive",
    "mass front_area rear_area supply_pressure return_pressure valve_time friction flow "
    "accumulator_volume precharge polytropic_exponent weight relieved emptied pumped",
)
# The rear chamber's connection: from `start` (0 return, 1 supply) toward `target` from `since`
Valve = namedtuple("Valve", "target since start")
STATE = 6  # y, y', V_gas, and the work of the supply, of the return line and of friction
STEP_ROWS = 7  # a step's end as kept: t, the state's first three and their rates
GROWTH, SHRINK = 4.0, 0.2  # the most a step grows or shrinks by
SAFETY = 0.9


@compiled(inline="always")
def held_gas(gas, drive):
    """The accumulator's gas held between the relief (pressed no further) and emptying (all gas)."""
    return min(max(gas, drive.relieved), drive.emptied)


@compiled(inline="always")
def supply_pressure(gas, drive):
    """The supply's pressure with `gas` of gas in the accumulator (`held_gas`; p_s without an
    accumulator)."""
    if drive.accumulator_volume == 0.0:
        return drive.supply_pressure
    return drive.precharge * (drive.accumulator_volume / held_gas(gas, drive)) ** drive.polytropic_exponent


@compiled(inline="always")
def on_supply(t, valve, valve_time):
    """The rear's connection at t: the fraction of the way from return to supply."""
    if valve_time <= 0.0 or t >= valve.since + valve_time:
        return valve.target
    return valve.start + (valve.target - valve.start) * max(0.0, t - valve.since) / valve_time


@compiled(inline="always")
def rear_pressure(on, supply, drive):
    """The rear chamber's pressure, `on` (0…1) of the way from return to supply."""
    return drive.return_pressure + on * (supply - drive.return_pressure)


@compiled(inline="always")
def rates(t, x, drive, valve):
    """The state's rates: the net push toward the tool (the rear's, the front's back, the weight,
    Coulomb friction against the motion) over the mass; what the chambers draw from the supply
    less what the pump brings moves the gas, held at the relief and at emptying."""
    w, gas = x[1], x[2]
    supply = supply_pressure(gas, drive)
    on = on_supply(t, valve, drive.valve_time)
    taken = (on * drive.rear_area - drive.front_area) * w  # m³/s the chambers draw from the supply
    gas_rate = 0.0
    if drive.accumulator_volume > 0.0:
        gas_rate = taken - drive.flow * drive.pumped
        if (gas <= drive.relieved and gas_rate < 0.0) or (gas >= drive.emptied and gas_rate > 0.0):
            gas_rate = 0.0
    force = rear_pressure(on, supply, drive) * drive.rear_area - supply * drive.front_area + drive.weight
    if w != 0.0:
        force -= math.copysign(drive.friction, w)
    returned = (1.0 - on) * drive.return_pressure * drive.rear_area * w
    return (w, force / drive.mass, gas_rate, supply * taken, returned, -drive.friction * abs(w))


@compiled(inline="always")
def shifted(x, span, k):
    """`x + span·k`."""
    return (
        x[0] + span * k[0],
        x[1] + span * k[1],
        x[2] + span * k[2],
        x[3] + span * k[3],
        x[4] + span * k[4],
        x[5] + span * k[5],
    )


@compiled(inline="always")
def runge_kutta(t, x, k1, span, drive, valve):
    """One classical Runge–Kutta step of `span` from (t, x), whose rates are `k1`."""
    half = 0.5 * span
    k2 = rates(t + half, shifted(x, half, k1), drive, valve)
    k3 = rates(t + half, shifted(x, half, k2), drive, valve)
    k4 = rates(t + span, shifted(x, span, k3), drive, valve)
    s = span / 6.0
    return (
        x[0] + s * (k1[0] + 2.0 * k2[0] + 2.0 * k3[0] + k4[0]),
        x[1] + s * (k1[1] + 2.0 * k2[1] + 2.0 * k3[1] + k4[1]),
        x[2] + s * (k1[2] + 2.0 * k2[2] + 2.0 * k3[2] + k4[2]),
        x[3] + s * (k1[3] + 2.0 * k2[3] + 2.0 * k3[3] + k4[3]),
        x[4] + s * (k1[4] + 2.0 * k2[4] + 2.0 * k3[4] + k4[4]),
        x[5] + s * (k1[5] + 2.0 * k2[5] + 2.0 * k3[5] + k4[5]),
    )


@compiled(inline="always")
def doubled(t, x, k1, span, drive, valve, rtol, atol):
    """The step of `span` from (t, x) as two half steps extrapolated by their difference from one
    whole step (fifth order), and that difference's size against the tolerance on y, y' and the
    gas (≤ 1: within it)."""
    whole = runge_kutta(t, x, k1, span, drive, valve)
    half = 0.5 * span
    middle = runge_kutta(t, x, k1, half, drive, valve)
    two = runge_kutta(t + half, middle, rates(t + half, middle, drive, valve), half, drive, valve)
    error = 0.0
    for i in range(3):
        scale = atol[i] + rtol * max(abs(x[i]), abs(two[i]))
        error = max(error, abs(two[i] - whole[i]) / 15.0 / scale)
    return (
        two[0] + (two[0] - whole[0]) / 15.0,
        two[1] + (two[1] - whole[1]) / 15.0,
        two[2] + (two[2] - whole[2]) / 15.0,
        two[3] + (two[3] - whole[3]) / 15.0,
        two[4] + (two[4] - whole[4]) / 15.0,
        two[5] + (two[5] - whole[5]) / 15.0,
    ), error


@compiled(inline="always")
def keep(steps, row, t, x, k):
    steps[row, 0] = t
    steps[row, 1], steps[row, 2], steps[row, 3] = x[0], x[1], x[2]
    steps[row, 4], steps[row, 5], steps[row, 6] = k[0], k[1], k[2]


@compiled()
def fly_to(start, t0, until, direction, longest, drive, valve, rtol, atol, steps):
    """From the state `start` at t0, until the striker's y crosses `until` going `direction`
    (+1 in, −1 back), for at most `longest` s. Each step's end is kept in `steps` (`STEP_ROWS`
    columns: t, y, y', V_gas, and their rates), the first row the start's. Returns `(rows kept,
    the crossing's t, the state there)`; no crossing within `longest` or the rows: `rows = −1`."""
    t, x = t0, start
    k = rates(t, x, drive, valve)
    keep(steps, 0, t, x, k)
    rows = 1
    span = 1e-6 * max(1.0, longest)
    while t - t0 < longest and rows < steps.shape[0]:
        new, error = doubled(t, x, k, span, drive, valve, rtol, atol)
        factor = SAFETY * (error + 1e-300) ** -0.2
        if error > 1.0:
            span *= max(SHRINK, factor)
            continue
        k_new = rates(t + span, new, drive, valve)
        before, after = direction * (x[0] - until), direction * (new[0] - until)
        if before < 0.0 <= after:
            s = hermite_root(x[0] - until, new[0] - until, k[0], k_new[0], span)
            # the crossing's state: the step to it, as doubled as the others
            at, _ = doubled(t, x, k, s * span, drive, valve, rtol, atol)
            keep(steps, rows, t + s * span, at, rates(t + s * span, at, drive, valve))
            return rows + 1, t + s * span, at
        t, x, k = t + span, new, k_new
        keep(steps, rows, t, x, k)
        rows += 1
        span *= min(GROWTH, factor)
    return -1, t, x


@compiled()
def records(times, steps, rows):
    """y, y' and V_gas at `times` (within the kept steps, in order), each on the cubic through
    its step's ends (values and rates): fourth order, as the steps are."""
    out = np.empty((3, times.shape[0]))
    j = 0
    for i in range(times.shape[0]):
        t = times[i]
        while j < rows - 2 and steps[j + 1, 0] < t:
            j += 1
        span = steps[j + 1, 0] - steps[j, 0]
        s = 0.0 if span <= 0.0 else min(1.0, max(0.0, (t - steps[j, 0]) / span))
        for q in range(3):
            out[q, i] = hermite(steps[j, 1 + q], steps[j + 1, 1 + q], steps[j, 4 + q], steps[j + 1, 4 + q], span, s)
    return out


@compiled()
def pressures(times, gas, valves, ends, drive):
    """The supply's and the rear's pressures at `times` (the gas there), the rear under the valve
    of the piece (`valves`, each ending at `ends`) each instant falls in."""
    supply = np.empty(times.shape[0])
    rear = np.empty(times.shape[0])
    piece = 0
    for i in range(times.shape[0]):
        while piece < len(ends) - 1 and times[i] > ends[piece]:
            piece += 1
        supply[i] = supply_pressure(gas[i], drive)
        rear[i] = rear_pressure(on_supply(times[i], valves[piece], drive.valve_time), supply[i], drive)
    return supply, rear
