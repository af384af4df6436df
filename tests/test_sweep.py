"""Parameter sweeps: every variant validated up front naming its parameter, one table from every
core that matches solving each variant alone, and the CLI that prints it; sweeps over an elastic
piston, media that yield and blows."""

from __future__ import annotations

import csv
import json

import pytest

from percussim.cli import main
from percussim.solver.case import CaseError
from percussim.solver.limits import Limits
from percussim.solver.presets import preset_json
from percussim.solver.simulate import run_sweep, simulate
from percussim.solver.sweep import Sweep, table_row, variants
from percussim.testing import merge
from percussim.testing.reference import LundbergRock

FIG5 = preset_json("fig5")
ROCK, PILE = preset_json("rock_drill"), preset_json("pile")
GRID = {"striker.velocity": [3.0, 5.0, 7.0], "contact.stiffness": [4e11, 8e11]}


def test_every_combination_is_a_variant_in_order():
    found = variants(Sweep(case=FIG5, parameters=GRID))
    assert [values for values, _ in found] == [
        {"striker.velocity": v, "contact.stiffness": k}
        for v in GRID["striker.velocity"]
        for k in GRID["contact.stiffness"]
    ]
    values, case = found[3]
    assert case.striker.velocity == values["striker.velocity"] == 5.0
    assert case.contact.stiffness == values["contact.stiffness"] == 8e11


@pytest.mark.parametrize(
    "base, path, values",
    [
        (ROCK, "striker.length", [0.2, 0.4]),
        (ROCK, "medium.unloading_stiffness", [1e9, 2e10]),
        (PILE, "medium.quake", [1e-3, 5e-3]),
        (PILE, "medium.damping_factor", [0.16, 0.49]),
        (PILE, "blows.count", [1, 3]),  # the preset has no blows: the field is made
        (
            merge(PILE, {"anvil": {"mass": 500.0, "contact": {"stiffness": 5e9, "exponent": 0.0}}}),
            "anvil.mass",
            [200.0, 800.0],
        ),
    ],
)
def test_the_piston_the_media_and_blows_can_be_swept(base, path, values):
    found = variants(Sweep(case=base, parameters={path: values}))
    for value, (values_of, case) in zip(values, found):
        node = case.model_dump()
        for key in path.split("."):
            node = node[key]
        assert node == values_of[path] == value


@pytest.mark.parametrize(
    "base, parameters, field, message",
    [
        (
            FIG5,
            {"striker.velocity": [3.0, "fast"]},
            "parameters['striker.velocity'][1]",
            "striker.velocity: must be a number",
        ),
        (FIG5, {"tool.area": [0.01, -1.0]}, "parameters['tool.area'][1]", "tool.area: must be > 0"),
        (FIG5, {"striker.speed": [3.0]}, "parameters['striker.speed'][0]", "striker.speed: is not a known field"),
        (FIG5, {"striker.mass.value": [3.0]}, "parameters['striker.mass.value'][0]", "cannot be set"),
        (FIG5, {"striker.velocity": []}, "parameters['striker.velocity']", "give at least one value"),
        (FIG5, {"numerics.cells": [10, 200_000]}, "parameters['numerics.cells'][1]", "exceed the limit of 100000"),
        (
            ROCK,
            {"medium.unloading_stiffness": [1e9, 1e8]},
            "parameters['medium.unloading_stiffness'][1]",
            "medium.unloading_stiffness: must be ≥ medium.stiffness",
        ),
        (ROCK, {"medium.quake": [1e-3]}, "parameters['medium.quake'][0]", "is not a field of a bilinear medium"),
        (PILE, {"blows.count": [2, 0]}, "parameters['blows.count'][1]", "blows.count: must be ≥ 1"),
        # The only parameter is the culprit even when the field it breaks is another.
        (
            PILE,
            {"striker.length": [0.3]},
            "parameters['striker.length'][0]",
            "striker.mass: cannot be given with striker.length",
        ),
    ],
)
def test_a_bad_variant_is_refused_naming_the_parameter_value(base, parameters, field, message):
    with pytest.raises(CaseError) as error:
        variants(Sweep(case=base, parameters=parameters))
    [e] = error.value.errors
    assert e.field == field and message in e.message


def test_too_many_variants_are_refused_before_any_is_built():
    with pytest.raises(CaseError) as error:
        variants(
            Sweep(case=FIG5, parameters={"striker.velocity": list(range(1, 101)), "striker.mass": list(range(1, 101))}),
            max_variants=1000,
        )
    [e] = error.value.errors
    assert e.field == "parameters" and "10000 variants (100 × 100) exceed the limit of 1000" in e.message


def test_the_table_on_two_processes_is_each_variant_solved_alone():
    sweep = Sweep(case=FIG5, parameters=GRID)
    rows = run_sweep(sweep, processes=2)
    assert rows == run_sweep(sweep, processes=1)
    for row, (values, case) in zip(rows, variants(sweep)):
        alone = simulate(case).summary
        assert row["striker.velocity"] == values["striker.velocity"]
        assert row["co_impact_time"] == alone["co_impact_time"]
        assert row["peak_contact_force"] == alone["peak_contact_force"]["value"]
        assert row["max_compressive_stress"] == alone["max_compressive_stress"]["value"]
    # Faster strikers hit harder.
    forces = [r["peak_contact_force"] for r in rows if r["contact.stiffness"] == 8e11]
    assert forces == sorted(forces) and forces[0] < forces[-1]


def test_the_piston_length_takes_the_efficiency_through_lundbergs_optimum():
    """x = k·(2L_p/a)/Z grows with the piston: the rock drill's efficiency rises to Lundberg's
    optimum (x = 1.2564) and falls past it, each row his closed form for its piston."""
    sweep = Sweep(case=ROCK, parameters={"striker.length": [0.1, 0.2, 0.3, 0.5, 0.8]})
    rows = run_sweep(sweep, processes=1)
    for row, (_, case) in zip(rows, variants(sweep)):
        expected = LundbergRock.of_case(case)  # the piston of the rod's section: its whole energy
        assert row["transfer_efficiency"] == pytest.approx(expected.efficiency, rel=1e-2)
        assert row["permanent_penetration"] == pytest.approx(expected.permanent_penetration, rel=1e-2)
        assert row["max_penetration"] == pytest.approx(expected.max_penetration, rel=1e-2)
        assert row["last_blow_set"] is None  # no blows asked
    efficiency = [row["transfer_efficiency"] for row in rows]
    best = efficiency.index(max(efficiency))
    assert 0 < best < len(rows) - 1
    assert efficiency[: best + 1] == sorted(efficiency[: best + 1])
    assert efficiency[best:] == sorted(efficiency[best:], reverse=True)


def test_a_heavier_helmet_lowers_the_pile_heads_stress():
    """The pile's ram on a helmet (an anvil) of 200 and 2000 kg: a sweep solves both, and the
    heavier one, slower to pass the blow on, stresses the pile less."""
    helmet = merge(PILE, {"anvil": {"mass": 200.0, "contact": {"stiffness": 2e10, "exponent": 0.0}}})
    light, heavy = run_sweep({"case": helmet, "parameters": {"anvil.mass": [200.0, 2000.0]}}, processes=1)
    assert "error" not in light and "error" not in heavy
    assert heavy["max_compressive_stress"] < 0.95 * light["max_compressive_stress"]


def test_blow_after_blow_the_pile_goes_down_by_each_blows_set():
    rows = run_sweep(Sweep(case=PILE, parameters={"blows.count": [1, 2, 3]}), processes=1)
    assert rows[0]["last_blow_set"] == pytest.approx(rows[0]["permanent_penetration"], rel=1e-9)
    for before, after in zip(rows, rows[1:]):
        # n blows are the n − 1 blows before and one more (each run on its own grids: within 2%)
        assert after["permanent_penetration"] - before["permanent_penetration"] == pytest.approx(
            after["last_blow_set"], rel=2e-2
        )
        assert after["energy_to_medium"] > before["energy_to_medium"]


def test_a_summary_without_a_quantity_leaves_its_column_empty():
    """A job stored before a quantity existed, or a case without a medium or blows."""
    row = table_row({"co_impact_time": 2e-4, "energy": {"to_medium": 1.5}, "blows": [], "warnings": ["w"]})
    assert row["co_impact_time"] == 2e-4 and row["energy_to_medium"] == 1.5 and row["warnings"] == 1
    assert row["permanent_penetration"] is None and row["last_blow_set"] is None
    assert row["transfer_efficiency"] is None


def test_a_variant_that_fails_is_a_row_with_its_error():
    # A tolerance the limits cannot meet is found only by running the variant.
    case = merge(FIG5, {"numerics": {"cells": None, "time_step": None, "gamma": None}})
    sweep = Sweep(case=case, parameters={"numerics.tolerance": [1e-2, 1e-5]})
    rows = run_sweep(sweep, processes=1, limits=Limits(max_node_steps=3e7))
    assert "error" not in rows[0] and rows[0]["co_impact_time"] > 0
    assert "numerics.tolerance" in rows[1]["error"] and "co_impact_time" not in rows[1]


def test_the_cli_prints_and_writes_the_table(tmp_path, capsys):
    case = tmp_path / "fig5.json"
    case.write_text(json.dumps(FIG5))
    out = tmp_path / "table.csv"
    code = main(
        [
            "sweep",
            str(case),
            "--vary",
            "striker.velocity=3,5",
            "--vary",
            "contact.stiffness=8e11",
            "--processes",
            "2",
            "--csv",
            str(out),
        ]
    )
    assert code == 0
    printed = capsys.readouterr()
    assert printed.out.splitlines()[0].startswith("striker.velocity\tcontact.stiffness\tco_impact_time")
    assert "2/2 variants" in printed.err
    rows = list(csv.DictReader(out.open()))
    assert [r["striker.velocity"] for r in rows] == ["3", "5"]
    assert float(rows[1]["peak_contact_force"]) > float(rows[0]["peak_contact_force"])


def test_the_cli_names_a_bad_parameter(tmp_path, capsys):
    case = tmp_path / "fig5.json"
    case.write_text(json.dumps(FIG5))
    assert main(["sweep", str(case), "--vary", "striker.velocity=3,fast"]) == 2
    assert "parameters['striker.velocity'][1]: striker.velocity: must be a number" in capsys.readouterr().err
