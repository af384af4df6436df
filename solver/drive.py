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

Between blows the tool is at rest on the medium and is not stepped: the flight is an ODE in
(y, y', V_gas), integrated compiled (`kernel.flight`) to a relative tolerance finer than the
case's, until the valve's switch and the impact. `Flight` is what one flight gives the next blow
and the records.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from .kernel import flight as F
from .kernel.flight import Valve

FLIGHT_ROWS = 200  # records kept of each flight, evenly in time
ODE_TOLERANCE = 1e-9  # the flight's relative tolerance: far below any case's
ODE_FLOOR = (1e-12, 1e-12, 1e-15)  # and its absolute one on y (m), y' (m/s) and the gas (m³)
MAX_STEPS = 100_000  # of a flight's integration: a flight that needs more is refused as stalled
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
        return F.supply_pressure(gas_volume, self.compiled)

    @cached_property
    def compiled(self) -> F.FlightDrive:
        """The drive as the compiled flight takes it (`kernel.flight`): with the gas volumes at the
        relief's pressure and at emptying (all gas), between which the supply's gas is held."""
        pumped = self.flow > 0.0 and self.accumulator_volume > 0.0
        return F.FlightDrive(
            mass=self.mass,
            front_area=self.front_area,
            rear_area=self.rear_area,
            supply_pressure=self.supply_pressure,
            return_pressure=self.return_pressure,
            valve_time=self.valve_time,
            friction=self.friction,
            flow=self.flow,
            accumulator_volume=self.accumulator_volume,
            precharge=self.precharge,
            polytropic_exponent=self.polytropic_exponent,
            weight=self.weight,
            relieved=self.gas_volume(self.supply_pressure),
            emptied=self.accumulator_volume,
            pumped=1.0 if pumped else 0.0,
        )


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


def seen_later(valve: Valve, span: float) -> Valve:
    """The same valve seen from `span` later (its time counted from then)."""
    return valve._replace(since=valve.since - span)


def turning(valve: Valve, at: float, target: float, valve_time: float) -> Valve:
    """The valve turning toward `target` from `at`, from where `valve` has it then."""
    return Valve(target=target, since=at, start=F.on_supply(at, valve, valve_time))


def fly(
    drive: Hydraulics, start: float, velocity: float, impact_point: float, gas_volume: float, valve: Valve
) -> Flight:
    """The striker's flight from `start` (m, positive toward the tool) at `velocity` until it
    strikes at `impact_point`: back under the front's pull until it passes `stroke` from the
    impact point, where the valve turns the rear to supply, then in. `gas_volume` and `valve`:
    the supply's state when the flight starts (the valve turned to return at the last impact)."""
    compiled = drive.compiled
    switch_at = impact_point - drive.stroke
    state = (start, velocity, gas_volume, 0.0, 0.0, 0.0)
    steps = np.empty((MAX_STEPS, F.STEP_ROWS))
    t0, switched, rows = 0.0, math.nan, 0
    valves, ends = [], []
    # a striker the blow left beyond the switch point (a stroke shorter than its rebound) has
    # passed it: the valve turns at once
    stages = ("back", "in") if start > switch_at else ("in",)
    if start <= switch_at:
        switched = 0.0
        valve = turning(valve, 0.0, 1.0, drive.valve_time)
    for stage in stages:
        until, direction = (switch_at, -1.0) if stage == "back" else (impact_point, 1.0)
        kept, t0, state = F.fly_to(
            state, t0, until, direction, MAX_FLIGHT, compiled, valve, ODE_TOLERANCE, ODE_FLOOR, steps[rows:]
        )
        if kept < 0:
            raise StalledStriker(stage, drive)
        rows += kept
        valves.append(valve)
        ends.append(t0)
        if stage == "back":
            switched = t0
            valve = turning(valve, t0, 1.0, drive.valve_time)
    times = np.linspace(0.0, t0, FLIGHT_ROWS + 1)[1:]  # its start is the blow's last record
    displacement, velocities, gas = F.records(times, steps, rows)
    supply, rear = F.pressures(times, gas, tuple(valves), np.array(ends), compiled)
    pumped = compiled.pumped > 0.0
    return Flight(
        duration=t0,
        switched=switched,
        impact_velocity=state[1],
        impact_point=impact_point,
        time=times,
        displacement=displacement,
        velocity=velocities,
        rear_pressure=rear,
        supply_pressure=supply,
        supplied=state[3],
        returned=state[4],
        rubbed=state[5],
        lifted=drive.weight * (impact_point - start),
        pumped=drive.flow * drive.supply_pressure * t0 if pumped else 0.0,
        gas_volume=F.held_gas(state[2], compiled),
        valve=seen_later(turning(valve, t0, 0.0, drive.valve_time), t0),
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
