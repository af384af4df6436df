"""A hammer's hydraulic drive between blows (solver/drive.py): the flight against the closed
forms of ideal hydraulics, the energy audit of a flight, the accumulator's gas law, and cycles
end to end (`cycles`)."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from percussim.solver.case import CaseError, parse_case
from percussim.solver.drive import StalledStriker, Valve, fly
from percussim.solver.simulate import simulate
from percussim.testing import closed_forms as CF
from percussim.testing.closed_forms import blow_ends, hammer_at_work, ideal_flight, supply_work_per_cycle

IDEAL = CF.IDEAL_DRIVE
RETURNING = CF.RETURNING


@pytest.mark.parametrize("rebound", [0.0, -3.0, -8.0])
def test_ideal_hydraulics_strike_at_the_closed_forms_velocity_after_its_times(rebound):
    flight = fly(IDEAL, 0.0, rebound, 0.0, 0.0, RETURNING)
    t_back, t_in, v_impact = ideal_flight(IDEAL, 0.0, rebound, 0.0)
    # √(2·p·A_r·s/m + v_r²) when the flight starts at the impact point
    assert v_impact == pytest.approx(math.sqrt(2 * 15e6 * 3e-4 * 0.05 / 2.0 + rebound**2), rel=1e-12)
    assert flight.impact_velocity == pytest.approx(v_impact, rel=1e-8)
    assert flight.switched == pytest.approx(t_back, rel=1e-8)
    assert flight.duration == pytest.approx(t_back + t_in, rel=1e-8)
    assert flight.displacement[-1] == pytest.approx(0.0, abs=1e-12)
    assert flight.displacement.min() < -IDEAL.stroke  # it turned beyond the switch point


def test_a_drive_weaker_than_its_friction_is_refused_as_stalled():
    """Friction of 5 kN against the ideal drive's 1.5-kN pull back and 3-kN push in: a rebound at
    3 m/s stops 1.4 mm back, short of the 50-mm stroke, and a striker at the switch point is never
    pushed in; each refused, naming the stage and the fields to check."""
    drive = replace(IDEAL, friction=5e3)
    with pytest.raises(StalledStriker, match="back past the stroke .* friction"):
        fly(drive, 0.0, -3.0, 0.0, 0.0, RETURNING)
    with pytest.raises(StalledStriker, match="in to the tool"):
        fly(drive, -IDEAL.stroke - 1e-3, 0.0, 0.0, 0.0, RETURNING)


def test_the_flights_work_is_its_kinetic_energys_change():
    """Supply, return line, friction and weight: their work sums to ½m(v_i² − v_r²)."""
    drive = CF.LOSSY_DRIVE
    gas = drive.gas_volume(drive.supply_pressure)
    flight = fly(drive, 1e-3, -4.0, 0.0, gas, Valve(target=0.0, since=0.0, start=1.0))
    change = 0.5 * drive.mass * (flight.impact_velocity**2 - 4.0**2)
    work = flight.supplied + flight.returned + flight.rubbed + flight.lifted
    assert work == pytest.approx(change, rel=1e-7)
    assert flight.rubbed < 0 and flight.returned < 0 and flight.supplied > 0


def test_the_accumulator_follows_its_gas_law():
    """Without a pump the gas takes what the chambers draw: V_gas = V_0' + ∫(on·A_r − A_f)·dy,
    and p = p_0·(V_0/V_gas)^n (started at 12 MPa, under the relief at the supply's 15 MPa, which
    the oil pushed back as the striker turns never reaches)."""
    drive = replace(
        IDEAL,
        accumulator_volume=2e-4,
        precharge=8e6,
        polytropic_exponent=1.3,
    )
    start_gas = drive.gas_volume(12e6)
    flight = fly(drive, 0.0, -3.0, 0.0, start_gas, RETURNING)
    switch = -drive.stroke
    y = flight.displacement
    after = flight.time > flight.switched
    drawn = -drive.front_area * y + np.where(after, drive.rear_area * (y - switch), 0.0)
    expected = 8e6 * (2e-4 / (start_gas + drawn)) ** 1.3
    assert np.allclose(flight.supply_pressure, expected, rtol=1e-6)
    assert np.ptp(flight.supply_pressure) > 0.05 * 12e6  # it did move
    assert flight.supply_pressure.max() < drive.supply_pressure


def test_a_pump_relieved_at_the_supply_pressure_never_passes_it():
    drive = replace(
        IDEAL,
        flow=5e-3,
        accumulator_volume=2e-4,
        precharge=8e6,
    )
    flight = fly(drive, 0.0, -3.0, 0.0, drive.gas_volume(15e6), RETURNING)
    assert flight.supply_pressure.max() <= 15e6 * (1 + 1e-9)
    assert flight.pumped == pytest.approx(15e6 * 5e-3 * flight.duration, rel=1e-3)


def hammer(**changes) -> dict:
    return hammer_at_work(**changes)


def test_cycles_strike_at_what_the_ideal_drive_gives_after_each_blow():
    case = parse_case(hammer())
    result = simulate(case)
    cycle, h = result.summary["cycle"], result.history
    grid = result.summary["runs"][-1]
    duration = grid["steps"] // case.cycles.count * grid["time_step"]  # a blow, in whole steps
    for k, (start, velocity, point) in enumerate(blow_ends(result)):
        t_back, t_in, v_impact = ideal_flight(IDEAL, start, velocity, point)
        assert cycle["impact_velocity"][k + 1] == pytest.approx(v_impact, rel=1e-7)
        assert cycle["cycle_time"][k] == pytest.approx(duration + t_back + t_in, rel=1e-7)
    assert np.all(np.diff(h["time"]) > 0)
    assert cycle["frequency"] == pytest.approx(1.0 / np.mean(cycle["cycle_time"][-2:]), rel=1e-12)
    assert cycle["impact_power"] == pytest.approx(cycle["impact_energy"] * cycle["frequency"], rel=1e-12)
    assert len(h["drive/rear_pressure"]) == len(h["time"])


@pytest.mark.parametrize(
    "change, field",
    [
        (
            {
                "drive": {
                    "kind": "hydraulic",
                    "supply_pressure": 15e6,
                    "front_area": 3e-4,
                    "rear_area": 3e-4,
                    "stroke": 0.05,
                }
            },
            "drive.rear_area",
        ),
        (
            {
                "drive": {
                    "kind": "hydraulic",
                    "supply_pressure": 1e5,
                    "return_pressure": 2e5,
                    "front_area": 1e-4,
                    "rear_area": 3e-4,
                    "stroke": 0.05,
                }
            },
            "drive.supply_pressure",
        ),
        (
            {
                "drive": {
                    "kind": "hydraulic",
                    "supply_pressure": 15e6,
                    "front_area": 1e-4,
                    "rear_area": 3e-4,
                    "stroke": 0.0,
                }
            },
            "drive.stroke",
        ),
        ({"blows": {"count": 2}}, "cycles"),
        ({"cycles": None}, "cycles"),
        (
            {
                "medium": {"kind": "linear", "stiffness": 1e8},
                "drive": {
                    "kind": "hydraulic",
                    "supply_pressure": 15e6,
                    "front_area": 1e-4,
                    "rear_area": 3e-4,
                    "stroke": 0.05,
                    "control": {"kind": "adaptive", "target_set": 1e-3, "min_stroke": 0.02, "max_stroke": 0.1},
                },
            },
            "drive.control",
        ),
        # between blows the tool rests on the medium, unloaded: a rest that holds forces is not modelled
        ({"medium": None}, "medium"),
        ({"gravity": {"acceleration": 9.81}}, "gravity"),
        ({"shaft": [{"from": 0.0, "to": 1.0, "ultimate_resistance": 1e4, "quake": 2.5e-3}]}, "shaft"),
    ],
)
def test_a_drive_that_cannot_work_is_refused_naming_the_field(change, field):
    case = hammer(**change)
    with pytest.raises(CaseError) as refused:
        parse_case(case)
    assert [e.field for e in refused.value.errors] == [field]


def test_each_blow_meets_a_tool_at_rest_and_rock_takes_lundbergs_share_of_it():
    """The equal piston on Lundberg's rock (`closed_forms.lundberg_cycles`): rock keeps η of the
    wave and the piston stops dead. Between blows the tool comes to rest on the rock, so every
    blow, launched from rest at the impact point at √(2·p_s·A_r·s/m), gives the rock η of its
    energy, and what the rock sent back into the tool, (1 − η) of each blow but the last, is spent
    between blows. (With the tool held as the blow left it, its reflected wave met the next blow:
    the rock took 0.80–0.85 of the second to fourth blows' energy, not η = 0.733, their rows read
    2.3–2.6 as they divided by the first blow's launch, and their impacts drifted from 16.98 to
    17.65 m/s.)"""
    summary = simulate(parse_case(CF.lundberg_cycles(4))).summary
    eta = CF.lundberg(CF.OPTIMUM)
    assert [blow["transfer_efficiency"] for blow in summary["blows"]] == pytest.approx([eta] * 4, rel=1e-4)
    mass = CF.PISTON_MASS
    velocities = summary["cycle"]["impact_velocity"]
    assert velocities[1:] == pytest.approx([math.sqrt(2 * 15e6 * 3e-4 * 0.05 / mass)] * 3, rel=1e-4)
    energy = summary["energy"]
    reflected = (1.0 - eta) * sum(0.5 * mass * v * v for v in velocities[:-1])
    # within what the scheme lost and what the piston kept (its contact is stiff, not rigid)
    slack = abs(energy["numerical"]) + energy["striker_withdrawn"]
    assert abs(energy["dissipated_between_blows"] - reflected) <= slack < 1e-2 * reflected


def test_the_cycles_histories_are_written_with_their_units(tmp_path):
    import h5py

    path = tmp_path / "result.h5"
    summary = simulate(hammer(cycles={"count": 2}), result_path=path).summary
    with h5py.File(path) as f:
        assert f["drive/rear_pressure"].attrs["units"] == "Pa"
        assert f["drive/supply_pressure"].attrs["units"] == "Pa"
        time, y = f["time"][:], f["striker/displacement"][:]
        assert len(f["drive/rear_pressure"]) == len(time)
        # the striker flew back beyond the stroke between the blows, in the same history
        assert y.min() < -0.05 and np.all(np.diff(time) > 0)
        # in its flight the tool is at rest on the rock, unstressed, what it held spent
        spent = f["energy/dissipated_between_blows"]
        assert spent.attrs["units"] == "J" and spent[-1] == summary["energy"]["dissipated_between_blows"] > 0
        grid = summary["runs"][-1]
        blow = grid["steps"] // 2 * grid["time_step"]  # a blow, in whole steps
        flying = (time > blow * (1 + 1e-9)) & (time <= summary["cycle"]["cycle_time"][0] * (1 + 1e-12))
        assert flying.sum() == 200
        for name in ("energy/tool_kinetic", "energy/tool_strain", "medium/force"):
            assert np.all(f[name][:][flying] == 0.0), name
        rest = f["medium/permanent_penetration"][:][flying]
        assert np.all(f["tool/struck_end_displacement"][:][flying] == rest) and np.all(spent[:][flying] > 0)


def adaptive(stiffness: float, count: int = 16) -> dict:
    case = hammer(cycles={"count": count})
    case["medium"] = {"kind": "bilinear", "stiffness": stiffness, "unloading_stiffness": 10 * stiffness}
    case["drive"]["control"] = {"kind": "adaptive", "target_set": 1.6e-3, "min_stroke": 0.01, "max_stroke": 0.3}
    return simulate(parse_case(case)).summary


def test_the_adaptive_stroke_settles_the_set_at_its_target_and_lengthens_on_harder_rock():
    soft, hard = adaptive(5e7), adaptive(1.5e8)
    for summary in (soft, hard):
        sets = [blow["set"] for blow in summary["blows"]]
        assert sets[-1] == pytest.approx(1.6e-3, rel=0.03)
        assert abs(sets[-1] - 1.6e-3) < 0.5 * abs(sets[1] - 1.6e-3)  # it closed in on it
        strokes = summary["cycle"]["stroke"]
        assert all(0.01 <= s <= 0.3 for s in strokes)
    assert hard["cycle"]["stroke"][-1] > 2.0 * soft["cycle"]["stroke"][-1]


def test_a_cycle_at_the_default_accuracy_estimates_its_own_quantities():
    from percussim.solver.summary import Summary

    case = hammer()
    case["numerics"] = {"duration": 0.002}
    summary = simulate(parse_case(case)).summary
    Summary.model_validate(summary)  # as the service serves it
    estimate = summary["error_estimate"]
    for name in ("cycle.impact_velocity", "cycle.frequency", "cycle.impact_energy", "cycle.efficiency"):
        assert 0.0 <= estimate[name] <= estimate["worst"], name
    assert summary["cycle"]["hydraulic_power"] > summary["cycle"]["impact_power"] * 0.5


def test_a_cycles_hydraulic_energy_is_the_supplys_work_on_the_volumes_it_fills():
    """Ideal hydraulics: from one impact to the next the rear fills on supply from the switch point,
    `stroke` back from the impact point, to the impact (A_r·s), and the front, always on supply,
    gives back what the tool advanced (A_f·Δ, Δ the blow's set): p_s·(A_r·s − A_f·Δ) a cycle,
    the blow's share (the striker pushed back while in contact) included, whatever it rebounds."""
    summary = simulate(parse_case(hammer(cycles={"count": 8}))).summary
    cycle = summary["cycle"]
    sets = [blow["set"] for blow in summary["blows"]][:-1]  # each cycle's: its blow, then its flight
    last = math.ceil(0.5 * len(cycle["cycle_time"]))
    expected = np.mean([supply_work_per_cycle(15e6, 3e-4, 1e-4, 0.05, d) for d in sets[-last:]])
    assert cycle["hydraulic_power"] / cycle["frequency"] == pytest.approx(expected, rel=1e-3)
    assert 0.0 < cycle["efficiency"] <= 1.0


def test_an_elastic_pistons_cycles_close_their_energy_audit():
    """An elastic striker takes no external force (its equations have none): the drive pushes it
    only in its flights, and no work of a push through its blows enters the audit, which closes."""
    piston = {"velocity": 8.0, "length": 0.1282, "youngs_modulus": 2.1e11, "density": 7800.0, "area": 2e-3}
    summary = simulate(parse_case(hammer(striker=piston))).summary
    energy = summary["energy"]
    assert energy["external_work"] == 0.0
    assert abs(energy["numerical"]) < 5e-3 * energy["initial"]  # 5% (its external work) before


def test_a_matched_piston_stops_dead_and_the_drive_strikes_from_rest_every_cycle():
    """A piston of the rod's impedance on a stiff face stops dead in each blow (its wave all in
    the rod), so each flight starts at rest at the impact point and strikes at √(2·p_s·A_r·s/m),
    whatever the blow before was launched at: its mean velocity counts from its own launch (it
    counted from the first blow's, and the third struck at 30.4 m/s, not 21.9)."""
    piston = {"velocity": 8.0, "length": 0.12, "youngs_modulus": 2.1e11, "density": 7800.0, "area": 1e-3}
    case = hammer(
        striker=piston,
        contact={"stiffness": 1e12, "exponent": 0.0},
        numerics={"duration": 1.5e-4, "scheme": "explicit", "cells": 200},  # before the rod's end answers
        cycles={"count": 3},
    )
    velocities = simulate(parse_case(case)).summary["cycle"]["impact_velocity"]
    mass = 7800.0 * 1e-3 * 0.12
    assert velocities[1:] == pytest.approx([math.sqrt(2 * 15e6 * 3e-4 * 0.05 / mass)] * 2, rel=1e-5)


def test_the_cycle_is_plotted_from_its_result(tmp_path):
    from percussim.solver.plots import figure, problem, problems

    path = tmp_path / "result.h5"
    velocities = simulate(hammer(cycles={"count": 3}), result_path=path).summary["cycle"]["impact_velocity"]
    assert problems(path)["cycle"] is None
    fig = figure(path, "cycle")
    motion, pressures, energies, strokes = fig.axes[:4]
    assert len(energies.lines[0].get_xdata()) == 3 and len(strokes.lines[0].get_ydata()) == 3
    # each impact's ½·m·v² of the 2-kg striker
    assert list(energies.lines[0].get_ydata()) == pytest.approx([0.5 * 2.0 * v * v for v in velocities], rel=1e-12)
    assert min(motion.lines[0].get_ydata()) < -50.0  # back beyond the 50-mm stroke, in mm
    assert max(pressures.lines[1].get_ydata()) == pytest.approx(15.0)  # the supply, MPa
    other = tmp_path / "fig3.h5"
    simulate(hammer(cycles=None, drive=None), result_path=other)
    import h5py

    with h5py.File(other) as f:
        assert "give it a drive and cycles" in problem(f, "cycle")


def test_the_valve_turning_at_impact_is_carried_into_the_next_flight():
    """The rear began to turn to return at impact, a blow before the flight starts: flights from
    the same state strike the same, whatever came before (the valve's time is the flight's own)."""
    from percussim.solver.cycle import HammerAtWork

    case = hammer()
    case["drive"] |= {"valve_time": 5e-3, "return_pressure": 5e5}
    hammer_at = HammerAtWork(parse_case(case), blow_duration=2e-3)
    velocities = [hammer_at.between(0.0, -0.5, 0.0, None).impact_velocity for _ in range(3)]
    assert velocities[1] == pytest.approx(velocities[0], rel=1e-9)
    assert velocities[2] == pytest.approx(velocities[0], rel=1e-9)
    # a valve still on supply for its first 3 ms pushes the striker in as it rebounds: a slower return
    case["drive"]["valve_time"] = 0.0
    instant = HammerAtWork(parse_case(case), blow_duration=2e-3).between(0.0, -0.5, 0.0, None)
    assert hammer_at.flights[0].switched > instant.switched
