"""A hammer's hydraulic drive between blows: the striker's flight back and forth, a phase without
contact (`drive` of kind `hydraulic`, `cycles`).

A differential piston: the front area A_f is always at the supply pressure p_s and pushes the
striker back, away from the tool; the rear area A_r > A_f is at the return pressure p_r on the way
back and at p_s on the way in, so that on the way in the net push is `(A_r − A_f)·p_s` toward the
tool. The valve switches the rear to supply when the striker, going back, passes `stroke` from the
impact point, and to return at impact, each over `valve_time` (the rear's pressure moves linearly
from one to the other). Coulomb friction opposes the motion; under gravity the striker's weight
acts along the tool.

The supply is fed by a pump's `flow` Q (constant) into a gas `accumulator` (volume V_0, precharge
p_0, polytropic exponent n: `p·V_gas^n = p_0·V_0^n`), and relieved at the supply pressure p_s it
starts from: what the chambers take, `(A_r·[rear on supply] − A_f)·y'`, and what the pump brings
move the gas. Without a pump the supply holds its pressure.

Between blows the tool's waves are spent and it is not stepped: the flight is an ODE in
(y, y', V_gas), integrated by `scipy.integrate.solve_ivp` to a relative tolerance finer than the
case's, with the valve's switch and the impact as events. `Flight` is what one flight gives the
next blow and the records.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.integrate import solve_ivp

FLIGHT_ROWS = 200  # records kept of each flight, evenly in time
ODE_TOLERANCE = 1e-9  # the flight's relative tolerance: far below any case's
MAX_FLIGHT = 10.0  # s: a striker that has not struck by then never will (refused as stalled)


@dataclass(frozen=True)
class Hydraulics:
    """The drive's numbers (SI): the striker's mass m, the areas, pressures, the stroke s, the
    valve's switching time, the friction, the pump's flow (0: none), the accumulator's volume,
    precharge and exponent (volume 0: none), and the weight along the tool (m·g, 0 without
    gravity)."""

    mass: float
    front_area: float
    rear_area: float
    supply_pressure: float
    return_pressure: float
    stroke: float
    valve_time: float = 0.0
    friction: float = 0.0
    flow: float = 0.0
    accumulator_volume: float = 0.0
    precharge: float = 0.0
    polytropic_exponent: float = 1.4
    weight: float = 0.0

    def gas_volume(self, pressure: float) -> float:
        """The accumulator's gas volume at `pressure` (its gas law); 0 without one."""
        if self.accumulator_volume == 0.0:
            return 0.0
        return self.accumulator_volume * (self.precharge / pressure) ** (1.0 / self.polytropic_exponent)

    def pressure(self, gas_volume: float) -> float:
        """The supply's pressure with `gas_volume` of gas in the accumulator (p_s without one)."""
        if self.accumulator_volume == 0.0:
            return self.supply_pressure
        return self.precharge * (self.accumulator_volume / gas_volume) ** self.polytropic_exponent


@dataclass
class Valve:
    """The rear chamber's connection: it moves from `start` (0: return, 1: supply) to `target`
    from `since` over the valve's time; its state at t is the fraction on supply."""

    target: float
    since: float
    start: float

    def shifted(self, span: float) -> Valve:
        """The same valve seen from `span` later (its time counted from then)."""
        return Valve(target=self.target, since=self.since - span, start=self.start)

    def on_supply(self, t: float, valve_time: float) -> float:
        if valve_time <= 0.0 or t >= self.since + valve_time:
            return self.target
        return self.start + (self.target - self.start) * max(0.0, t - self.since) / valve_time


@dataclass
class Flight:
    """One flight: its time (s), where the valve switched (s from its start), the striker's
    velocity at impact and the impact point (m), and records at `FLIGHT_ROWS` instants after its
    start, the last at impact: time from the flight's start,
    the striker's displacement and velocity, the rear's and the supply's pressures; the work on
    the striker (J) of the supply (the hydraulic energy it gave the chambers), of the return
    line's pressure, of friction (≤ 0) and of the weight, which sum to its kinetic energy's
    change; the pump's energy (J), and the supply's
    state at impact (the gas volume, and the valve turning to return from then: its time counted
    from the impact)."""

    duration: float
    switched: float
    impact_velocity: float
    impact_point: float
    time: np.ndarray
    displacement: np.ndarray
    velocity: np.ndarray
    rear_pressure: np.ndarray
    supply_pressure: np.ndarray
    supplied: float
    returned: float
    rubbed: float
    lifted: float
    pumped: float
    gas_volume: float
    valve: Valve = field(repr=False)


def rear_pressure(drive: Hydraulics, on_supply: float, supply: float) -> float:
    """The rear chamber's pressure, `on_supply` (0…1) of the way from return to supply."""
    return drive.return_pressure + on_supply * (supply - drive.return_pressure)


def push(drive: Hydraulics, velocity: float, rear: float, supply: float) -> float:
    """The net force on the striker toward the tool (N): the rear's push, the front's pull back,
    the weight, and friction against the motion (none at rest: it holds at most what the
    pressures push with, which the flight never rests on)."""
    force = rear * drive.rear_area - supply * drive.front_area + drive.weight
    return force - math.copysign(drive.friction, velocity) if velocity != 0.0 else force


def fly(
    drive: Hydraulics, start: float, velocity: float, impact_point: float, gas_volume: float, valve: Valve
) -> Flight:
    """The striker's flight from `start` (m, positive toward the tool) at `velocity` until it
    strikes at `impact_point`: back under the front's pull until it passes `stroke` from the
    impact point, where the valve turns the rear to supply, then in. `gas_volume` and `valve`:
    the supply's state when the flight starts (the valve turned to return at the last impact)."""
    switch_at = impact_point - drive.stroke
    pumped = drive.flow > 0.0 and drive.accumulator_volume > 0.0
    relieved = drive.gas_volume(drive.supply_pressure)  # the gas volume at the relief's pressure
    # an emptied accumulator (all gas) holds its precharge: a demand beyond it is not modelled
    emptied = drive.accumulator_volume

    def rates(t, x, valve):
        # x: y, y', the gas volume, and the work on the striker of the supply, of the return line
        # and of friction so far
        y, w, gas = x[:3]
        # relieved at the supply pressure: the gas is pressed no further (a trial stage of the
        # integrator past it reads the relief's pressure), the pump's surplus goes over the valve
        supply = drive.pressure(min(max(gas, relieved), emptied))
        on = valve.on_supply(t, drive.valve_time)
        taken = (on * drive.rear_area - drive.front_area) * w  # m³/s the chambers draw from the supply
        gas_rate = 0.0
        if drive.accumulator_volume > 0.0:
            gas_rate = taken - (drive.flow if pumped else 0.0)
            if (gas <= relieved and gas_rate < 0.0) or (gas >= emptied and gas_rate > 0.0):
                gas_rate = 0.0
        force = push(drive, w, rear_pressure(drive, on, supply), supply)
        returned = (1.0 - on) * drive.return_pressure * drive.rear_area * w
        return [w, force / drive.mass, gas_rate, supply * taken, returned, -drive.friction * abs(w)]

    def passes_switch(t, x, valve):
        return x[0] - switch_at

    passes_switch.terminal, passes_switch.direction = True, -1.0

    def strikes(t, x, valve):
        return x[0] - impact_point

    strikes.terminal, strikes.direction = True, 1.0

    pieces = []
    state = [start, velocity, gas_volume, 0.0, 0.0, 0.0]
    t0, switched = 0.0, math.nan
    # a striker the blow left beyond the switch point (a stroke shorter than its rebound) has
    # passed it: the valve turns at once
    stages = ("back", "in") if start > switch_at else ("in",)
    if start <= switch_at:
        switched = 0.0
        valve = Valve(target=1.0, since=0.0, start=valve.on_supply(0.0, drive.valve_time))
    for stage in stages:
        events = [passes_switch] if stage == "back" else [strikes]
        solution = solve_ivp(
            rates,
            (t0, t0 + MAX_FLIGHT),
            state,
            method="DOP853",
            rtol=ODE_TOLERANCE,
            atol=[1e-12, 1e-12, 1e-15, 1e-9, 1e-9, 1e-9],
            events=events,
            dense_output=True,
            args=(valve,),
        )
        if solution.status != 1:
            raise StalledStriker(stage, drive)
        pieces.append((t0, solution.t_events[0][0], solution.sol, valve))
        t0 = solution.t_events[0][0]
        state = list(solution.y_events[0][0])
        if stage == "back":
            switched = t0
            valve = Valve(target=1.0, since=t0, start=valve.on_supply(t0, drive.valve_time))
    times = np.linspace(0.0, t0, FLIGHT_ROWS + 1)[1:]  # its start is the blow's last record
    rows = np.empty((6, FLIGHT_ROWS))
    rear, supply = np.empty(FLIGHT_ROWS), np.empty(FLIGHT_ROWS)
    for k, t in enumerate(times):
        begin, end, dense, on_valve = next(p for p in pieces if t <= p[1] or p is pieces[-1])
        rows[:, k] = dense(min(max(t, begin), end))
        supply[k] = drive.pressure(min(max(rows[2, k], relieved), emptied))
        rear[k] = rear_pressure(drive, on_valve.on_supply(t, drive.valve_time), supply[k])
    return Flight(
        duration=t0,
        switched=switched,
        impact_velocity=state[1],
        impact_point=impact_point,
        time=times,
        displacement=rows[0],
        velocity=rows[1],
        rear_pressure=rear,
        supply_pressure=supply,
        supplied=state[3],
        returned=state[4],
        rubbed=state[5],
        lifted=drive.weight * (impact_point - start),
        pumped=drive.flow * drive.supply_pressure * t0 if pumped else 0.0,
        gas_volume=min(max(state[2], relieved), emptied),
        valve=Valve(target=0.0, since=0.0, start=valve.on_supply(t0, drive.valve_time)),
    )


class StalledStriker(ValueError):
    """A striker the drive never brings back or in (the front's pull too weak to stop its
    rebound, or the rear's push too weak to bring it in)."""

    def __init__(self, stage: str, drive: Hydraulics):
        where = "back past the stroke" if stage == "back" else "in to the tool"
        super().__init__(
            f"the drive does not bring the striker {where} within {MAX_FLIGHT:g} s: check drive.front_area, "
            "rear_area, supply_pressure and friction"
        )
