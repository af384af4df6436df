"""Studies of cases whose ends limit the grid: an elastic striker (shorter than a third of its
tool, or longer than it), an anvil, and every medium kind. Each reaches the fit or the optimum,
whatever its numerics say, on a grid that every point within the bounds takes.

The records are the explicit scheme's on 400 cells (the fits run on grids of their own choosing)
with 1% noise: these tests hold that the studies run and find what the record holds; the SHPB
test (test_measured_records.py) holds a fit to a record made without the kernel."""

from __future__ import annotations

import numpy as np
import pytest

from percussim.solver.calibrate import calibrate
from percussim.solver.case import CaseError, parse_case
from percussim.solver.controller import simulate_rod
from percussim.solver.evaluate import Space
from percussim.solver.grid import explicit_numerics, fewest_cells, striker_cells
from percussim.solver.optimize import optimize
from percussim.solver.study import check_calibration, parse_calibration

STEEL = {"youngs_modulus": 2.1e11, "density": 7800.0, "area": 1e-3}
TOOL = 1.0  # m
GAUGE = 0.5  # m
MEDIA = {
    "none": None,
    "linear": {"stiffness": 5e8, "damping": 1e4},
    "bilinear": {"kind": "bilinear", "stiffness": 5e8, "unloading_stiffness": 5e9},
    "smith": {"kind": "smith", "ultimate_resistance": 2e5, "quake": 1e-3, "damping_factor": 0.3},
}
VELOCITY = 8.0


def case(striker_length: float, medium: str = "none", anvil: bool = False, **numerics) -> dict:
    tree = {
        "name": "ends",
        "striker": {"velocity": VELOCITY, "length": striker_length, **STEEL},
        "tool": {"length": TOOL, **STEEL},
        "contact": {"stiffness": 2e9, "exponent": 0.0},
        "numerics": {"duration": 1.2e-3, **numerics},
    }
    if MEDIA[medium] is not None:
        tree["medium"] = MEDIA[medium]
    if anvil:
        tree["anvil"] = {"mass": 0.5, "contact": {"stiffness": 5e9, "exponent": 0.0}}
    return tree


def record(truth: dict) -> dict:
    """The stress at the gauge, by the explicit scheme on 400 cells, at 1 MHz with 1% noise."""
    run_case = parse_case(truth | {"outputs": {"probes": [GAUGE]}})
    run = simulate_rod(run_case, numerics=explicit_numerics(run_case, 400))
    t = np.arange(0.0, 1.0e-3, 1e-6)
    values = np.interp(t, run.history["time"], run.probe_stress[:, 0])
    values += 0.01 * np.abs(values).max() * np.random.default_rng(0).standard_normal(len(t))
    return {"quantity": "stress", "x": GAUGE, "time": t.tolist(), "values": values.tolist()}


# (striker length, medium, anvil): a piston under a third of the tool, one longer than the tool
# (on a medium, which keeps the tool pressed long enough for the whole pulse to matter), an
# anvil, and each medium kind.
SCENES = [
    (0.3, "none", False),
    (1.5, "linear", False),
    (0.3, "none", True),
    (0.3, "linear", False),
    (0.3, "bilinear", False),
    (0.3, "smith", False),
]
# duration only; a fixed grid (set aside: a study chooses its own); a tolerance
NUMERICS = [{}, {"cells": 200}, {"cells": 200, "scheme": "explicit"}, {"tolerance": 0.01}]


def starting(length: float, medium: str, anvil: bool, numerics: dict) -> dict:
    start = case(1.1 * length, medium, anvil, **numerics)
    start["striker"]["velocity"] = 6.0
    return start


def bounds(length: float) -> dict:
    return {"striker.velocity": [4.0, 12.0], "striker.length": [0.8 * length, 1.2 * length]}


@pytest.mark.parametrize("length, medium, anvil", SCENES)
def test_an_elastic_striker_is_calibrated_whatever_the_scene(length, medium, anvil):
    fit = calibrate(
        {
            "case": starting(length, medium, anvil, {}),
            "record": record(case(length, medium, anvil)),
            "parameters": bounds(length),
        },
        processes=1,
    )
    found = fit["parameters"]
    assert abs(found["striker.velocity"]["value"] / VELOCITY - 1.0) < 0.01, found
    assert abs(found["striker.velocity"]["value"] - VELOCITY) <= 3.0 * found["striker.velocity"]["standard_error"]
    assert abs(found["striker.length"]["value"] - length) <= 3.0 * found["striker.length"]["standard_error"], found
    assert abs(found["striker.length"]["value"] / length - 1.0) < 0.02, found
    # the grid takes the shortest striker within the bounds
    shortest = parse_case(case(0.8 * length, medium, anvil))
    assert fit["grid"]["cells"] >= fewest_cells(shortest)


@pytest.mark.parametrize("numerics", NUMERICS, ids=["duration only", "cells 200", "explicit on 200 cells", "tolerance"])
def test_the_checks_before_a_fit_take_the_case_whatever_its_numerics(numerics):
    """The units check runs on a coarse grid of its own; the case's numerics neither decide it nor
    are named in a refusal."""
    request = parse_calibration(
        {"case": starting(0.3, "none", False, numerics), "record": record(case(0.3)), "parameters": bounds(0.3)}
    )
    space = check_calibration(request)
    assert space.paths == ("striker.velocity", "striker.length")


def test_the_units_check_refuses_an_elastic_strikers_record_naming_its_units():
    measured = record(case(0.3))
    measured["values"] = [v / 1000.0 for v in measured["values"]]  # kPa given as Pa
    with pytest.raises(CaseError) as refused:
        check_calibration(
            parse_calibration({"case": starting(0.3, "none", False, {}), "record": measured, "parameters": bounds(0.3)})
        )
    assert refused.value.errors[0].field == "record.values"
    assert "SI units" in refused.value.errors[0].message


def test_a_study_over_its_limits_names_what_the_user_can_change():
    from percussim.solver.limits import Limits

    with pytest.raises(CaseError) as refused:
        check_calibration(
            parse_calibration(
                {
                    "case": starting(0.3, "none", False, {"cells": 200}),
                    "record": record(case(0.3)),
                    "parameters": bounds(0.3),
                }
            ),
            Limits(max_node_steps=100.0),
        )
    error = refused.value.errors[0]
    assert error.field == "record.time"
    assert "PERCUSSIM_MAX_NODE_STEPS" in error.message and "shorten the record" in error.message
    for setting in ("numerics.cells", "numerics.time_step", "give at least"):
        assert setting not in error.message, error.message


def test_the_fewest_cells_give_an_elastic_striker_two_steps_at_every_corner():
    """`fewest_cells` is the least grid whose striker spans two steps, and one cell fewer is not."""
    for length in (0.05, 0.3, 0.61, 1.5, 7.0):
        one = parse_case(case(length))
        cells = fewest_cells(one)
        speed = np.sqrt(STEEL["youngs_modulus"] / STEEL["density"])
        assert striker_cells(one.striker, TOOL / cells / speed) >= 2
        assert cells == 2 or striker_cells(one.striker, TOOL / (cells - 1) / speed) < 2
    space = Space.of({"striker.length": [0.1, 0.4]}, "parameters")
    assert space.fewest_cells(parse_case(case(0.3))) == fewest_cells(parse_case(case(0.1)))


@pytest.mark.parametrize("length, medium, anvil", SCENES)
def test_an_elastic_striker_is_optimised_whatever_the_scene(length, medium, anvil):
    """Every run within the bounds succeeds, on a grid the shortest striker takes, and the design
    checked under the tolerance is within its bounds."""
    low, high = 0.5 * length, 1.2 * length
    answer = optimize(
        {
            "case": starting(length, medium, anvil, {"cells": 200}),
            "variables": {"striker.length": [low, high]},
            "objective": {"maximize": "energy.transfer_efficiency"},
            "max_evaluations": 40,
        },
        processes=1,
    )
    assert [run for run in answer["history"] if "error" in run] == []
    assert answer["grid"]["cells"] >= fewest_cells(parse_case(case(low, medium, anvil)))
    assert low <= answer["values"]["striker.length"] <= high
    assert answer["summary"]["error_estimate"] is not None
