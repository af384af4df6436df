"""A hammer at work (`cycles` with a `drive`): what happens between two blows, and the summary's
`cycle`.

The controller runs a blow as it runs any (`blows`: the tool and the medium carry their state);
at its end the tool's waves are spent and the tool is held as it is, not stepped, while the
striker flies back and in under the drive (`drive.fly`, an ODE to its own tolerance); the next
blow starts where the striker strikes the struck end (the impact point follows the tool), at the
velocity the drive gave it. During a blow the drive's push on the striker is R(t): the rear on
return, the front on the supply (`blow_force`).

With `drive.control` (adaptive) each blow's set moves the next stroke toward the one that gives
`target_set`: the set grows about as the blow's energy, so the stroke is scaled by
`√(target_set/set)` within `min_stroke` and `max_stroke` (a blow that sets nothing takes the
longest).
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from . import kernel as K
from .case import Case
from .drive import Flight, Hydraulics, Valve, fly, seen_later
from .grid import striker_mass
from .laws import FORCE_PULSE

LAST_SHARE = 0.5  # the cycles a summary's means are over: the last half (at least one)


def hydraulics_of(case: Case) -> Hydraulics:
    """The case's drive as `drive.fly` takes it."""
    d = case.drive
    mass = striker_mass(case.striker)
    accumulator = d.accumulator
    return Hydraulics(
        mass=mass,
        front_area=d.front_area,
        rear_area=d.rear_area,
        supply_pressure=d.supply_pressure,
        return_pressure=d.return_pressure,
        stroke=d.stroke,
        valve_time=d.valve_time,
        friction=d.friction,
        flow=d.flow or 0.0,
        accumulator_volume=accumulator.volume if accumulator else 0.0,
        precharge=accumulator.precharge if accumulator else 0.0,
        polytropic_exponent=accumulator.polytropic_exponent if accumulator else 1.4,
        weight=mass * case.gravity.acceleration if case.gravity else 0.0,
    )


def blow_force(case: Case) -> K.ForceLaw:
    """The drive's push on the striker through a blow (R, constant): the rear on return, the front
    on the supply's starting pressure. None on an elastic striker, whose equations take no
    external force (as `force` is refused on one): its blows are short against its flights."""
    d = case.drive
    push = 0.0 if case.elastic_striker else d.rear_area * d.return_pressure - d.front_area * d.supply_pressure
    return K.ForceLaw(kind=FORCE_PULSE, amplitude=push, omega=0.0, start=0.0, duration=math.inf)


class HammerAtWork:
    """The cycles of a run whose blows each last `blow_duration` (s): each flight between two
    blows (`between`), and what the summary says of them (`summary`)."""

    def __init__(self, case: Case, blow_duration: float):
        self.drive = hydraulics_of(case)
        control = case.drive.control
        self.control = control
        self.blow_duration = blow_duration  # the grid's: whole steps, numerics.duration or a little more
        self.gas = self.drive.gas_volume(self.drive.supply_pressure)
        self.valve = Valve(target=0.0, since=0.0, start=1.0)  # the rear turns to return at each impact
        self.impact_velocities = [case.impact_velocity]
        self.strokes = [self.drive.stroke]
        self.flights: list[Flight] = []
        self.pushing = not case.elastic_striker  # whether the drive pushes it through its blows (`blow_force`)
        self.impact_at = 0.0  # the striker's displacement at the present blow's impact
        self.pushed: list[float] = []  # the supply's work on the front area through each blow

    def between(self, start: float, velocity: float, impact_point: float, last_set: float | None) -> Flight:
        """The flight after a blow that left the striker at `start` moving at `velocity` and set the
        tool by `last_set` (None: a medium that does not yield), to its next impact at
        `impact_point`."""
        # the front, on the supply, takes back what the striker moved toward the tool in the blow
        moved = start - self.impact_at if self.pushing else 0.0
        self.pushed.append(-self.drive.front_area * self.drive.supply_pressure * moved)
        if self.control is not None and last_set is not None:
            self.strokes.append(self.next_stroke(last_set))
        else:
            self.strokes.append(self.strokes[-1])
        drive = replace(self.drive, stroke=self.strokes[-1])
        # the valve began to turn at the blow's impact, a blow ago
        flight = fly(drive, start, velocity, impact_point, self.gas, seen_later(self.valve, self.blow_duration))
        self.gas, self.valve = flight.gas_volume, flight.valve
        self.flights.append(flight)
        self.impact_velocities.append(flight.impact_velocity)
        self.impact_at = flight.displacement[-1]
        return flight

    def next_stroke(self, last_set: float) -> float:
        control = self.control
        if last_set <= 0.0:
            return control.max_stroke
        scaled = self.strokes[-1] * math.sqrt(control.target_set / last_set)
        return min(control.max_stroke, max(control.min_stroke, scaled))

    def summary(self, blows: list[dict], tolerance: float) -> dict:
        """The summary's `cycle` from the flights and each blow's row (`blows`)."""
        count = len(self.flights)
        last = max(1, math.ceil(LAST_SHARE * count)) if count else 0
        mass = self.drive.mass
        velocities = [float(v) for v in self.impact_velocities[: len(blows)]]
        energies = [0.5 * mass * v * v for v in velocities]
        periods = [self.blow_duration + f.duration for f in self.flights]
        # a cycle's hydraulic energy: the pump's, or what the supply gave the chambers in its blow
        # and its flight
        hydraulic = [
            f.pumped + self.drive.supply_pressure * self.drive.flow * self.blow_duration
            if self.drive.flow
            else pushed + f.supplied
            for f, pushed in zip(self.flights, self.pushed)
        ]
        if not count:
            return {
                "impact_velocity": velocities,
                "stroke": [float(x) for x in self.strokes[: len(blows)]],
                "cycle_time": [],
                "impact_energy": energies[0],
                "frequency": None,
                "impact_power": None,
                "hydraulic_power": None,
                "efficiency": None,
                "penetration_rate": None,
                "periodic": False,
            }
        period = float(np.mean(periods[-last:]))
        # a cycle k: its blow, then its flight to the next impact
        energy = float(np.mean(energies[-last - 1 : -1] if len(energies) > last else energies[-last:]))
        to_medium = float(np.mean([b["to_medium"] for b in blows[-last - 1 : -1]] or [blows[-1]["to_medium"]]))
        sets = [b["set"] for b in blows[-last - 1 : -1]] or [blows[-1]["set"]]
        hydraulic_energy = float(np.mean(hydraulic[-last:]))
        v_now, v_before = velocities[-1], velocities[-2]
        return {
            "impact_velocity": velocities,
            "stroke": [float(x) for x in self.strokes[: len(blows)]],
            "cycle_time": [float(t) for t in periods],
            "impact_energy": energy,
            "frequency": 1.0 / period,
            "impact_power": energy / period,
            "hydraulic_power": hydraulic_energy / period,
            "efficiency": to_medium / hydraulic_energy if hydraulic_energy > 0 else None,
            "penetration_rate": float(np.mean(sets)) / period,
            "periodic": bool(abs(v_now - v_before) <= tolerance * abs(v_now)),
        }
