"""Signal matching (`solver/signal_match.py`): a pile's soil from a head record made by a finer
run of the pile with 2% noise on force and velocity, within 3 standard errors; the non-uniqueness
warning where the record cannot tell the shaft from the toe; and bad records refused naming the
field."""

from __future__ import annotations

import json
import math
import re

import numpy as np
import pytest

from percussim.solver.case import CaseError
from percussim.solver.signal_match import check_record, driven_case, parse_signal_match, read_pile_record, signal_match
from percussim.testing.pile_records import SHAFT, TOE, head_record, pile

RESISTANCES = {"shaft.0.ultimate_resistance": [5e4, 4e6], "medium.ultimate_resistance": [5e4, 4e6]}


def guessed(**changes) -> dict:
    """The pile with its resistances guessed wrong: 1.5 and 0.6 times the truth's."""
    shaft = [
        dict(segment, ultimate_resistance=1.5 * segment["ultimate_resistance"])
        for segment in changes.pop("shaft", SHAFT)
    ]
    return pile(shaft=shaft, medium=dict(TOE, ultimate_resistance=0.6 * TOE["ultimate_resistance"]), **changes)


@pytest.fixture(scope="module")
def record() -> dict:
    return head_record(pile())


def test_the_soils_resistances_come_back_within_their_uncertainty(record):
    match = signal_match({"case": guessed(), "record": record, "parameters": RESISTANCES}, processes=1)
    for path, truth in (("shaft.0.ultimate_resistance", 4e5), ("medium.ultimate_resistance", 4e5)):
        found = match["parameters"][path]
        assert abs(found["value"] - truth) <= 3 * found["standard_error"], (path, found)
    capacity = match["capacity"]
    assert abs(capacity["value"] - 8e5) <= 3 * capacity["standard_error"] and capacity["standard_error"] < 0.02 * 8e5
    assert [row["part"] for row in match["resistance_distribution"]] == ["shaft.0", "toe"]
    assert sum(row["resistance"] for row in match["resistance_distribution"]) == pytest.approx(capacity["value"])
    # the misfit is the noise of the force and of the velocity that drives the pile, not more
    assert not any(w.startswith("the misfit") for w in match["warnings"]), match["warnings"]
    quality = match["match_quality"]
    assert 0.01 < quality["value"] < 0.05 and quality["window"] is not None and quality["after"] is not None
    # the static load test of the fitted soil plunges at its capacity
    test = match["static_load_test"]
    assert test["load"][-1] == pytest.approx(capacity["value"], rel=1e-5) and np.all(np.diff(test["settlement"]) > 0)
    assert [row["damping_factor"] for row in match["case_method"]] == [0.2, 0.3, 0.4, 0.5, 0.6, 0.7]
    # nothing comes up before the shaft's top (3 m down) answers, 6 m/c after the impact: the wave
    # up is the noise alone there, measured and computed
    waves = match["waves"]
    before = np.asarray(waves["time"]) < 6.0 / math.sqrt(2.1e11 / 7850.0)
    down = np.asarray(waves["measured"]["down"])
    for curves, bound in ((waves["measured"], 0.06), (waves["computed"], 0.03)):
        assert np.max(np.abs(np.asarray(curves["up"])[before])) < bound * np.max(down)
    # and the measured wave up carries the soil's answer afterwards, as the computed one does
    assert np.max(np.asarray(waves["computed"]["up"])) > 0.2 * np.max(down)


def test_a_record_that_cannot_tell_the_shaft_from_the_toe_says_so():
    """Soil along the last half metre only, and a record that ends just after 2L/c: the shaft's and
    the toe's answers reach the gauges together, and only their sum is known."""
    near = [dict(SHAFT[0], **{"from": 9.5})]
    short = {"duration": 0.0062}
    match = signal_match(
        {
            "case": guessed(shaft=near, numerics=short),
            "record": head_record(pile(shaft=near, numerics=short)),
            "parameters": RESISTANCES,
        },
        processes=1,
    )
    assert any("strongly correlated" in w and "shaft.0.ultimate_resistance" in w for w in match["warnings"])
    capacity = match["capacity"]
    assert abs(capacity["value"] - 8e5) <= 3 * capacity["standard_error"]
    shares = [match["parameters"][p]["standard_error"] for p in RESISTANCES]
    assert capacity["standard_error"] < min(shares)  # the sum is better known than its parts


def bad(record: dict, **changes) -> dict:
    return {"case": pile(), "record": record | changes}


@pytest.mark.parametrize(
    "change, field",
    [
        (lambda r: bad(r, time=[r["time"][0], r["time"][0]] + r["time"][2:]), "record.time"),
        (lambda r: bad(r, force=[math.nan] + r["force"][1:]), "record.force"),
        (lambda r: bad(r, velocity=r["velocity"][:-3]), "record.velocity"),
        (lambda r: bad(r, x=12.0), "record.x"),
        (lambda r: bad(r, time=r["time"][:80], force=r["force"][:80], velocity=r["velocity"][:80]), "record.time"),
        (lambda r: bad(r, force=[1e-3 * f for f in r["force"]]), "record.force"),
        (lambda r: {"case": pile() | {"striker": {"mass": 1.0, "velocity": 1.0}}, "record": r}, "case.striker"),
    ],
    ids=["time not increasing", "NaN", "lengths", "gauge off the pile", "shorter than 2L/c", "kN for N", "a striker"],
)
def test_a_bad_record_is_refused_naming_the_field(record, change, field):
    with pytest.raises(CaseError) as refused:
        request = parse_signal_match(change(record))
        check_record(request, driven_case(request))
    assert any(e.field.startswith(field) for e in refused.value.errors), refused.value.errors


def test_a_record_whose_force_is_not_z_times_velocity_at_impact_is_warned(record):
    request = parse_signal_match({"case": pile(tool=pile()["tool"] | {"area": 0.014}), "record": record})
    (warning,) = check_record(request, driven_case(request))
    ratio = float(warning.split("impact is ")[1].split(" ×")[0])
    assert ratio == pytest.approx(0.01 / 0.014, rel=0.05) and "area or wave speed" in warning  # the noise's share


def test_a_csv_record_reads_as_its_json(record):
    rows = "\n".join(f"{t!r},{f!r},{v!r}" for t, f, v in zip(record["time"], record["force"], record["velocity"]))
    read = read_pile_record("# a pile driving analyser's export\ntime,force@0,velocity@0\n" + rows)
    assert read.model_dump() == parse_signal_match({"case": {}, "record": record}).record.model_dump()
    with pytest.raises(CaseError, match="time,force@X,velocity@X"):
        read_pile_record("time,force@0,speed@0\n0,1,2\n")
    # a bad sample is named by its line in the file, comments and blank lines counted
    with pytest.raises(CaseError, match=re.escape("line 5: '1e-4,nan?,2' is not three numbers")):
        read_pile_record("# gauges at the head\ntime,force@0,velocity@0\n0,1,2\n\n1e-4,nan?,2\n")


def test_the_command_line_matches_and_refuses(record, tmp_path, capsys):
    from percussim.cli import main

    rows = "\n".join(f"{t!r},{f!r},{v!r}" for t, f, v in zip(record["time"], record["force"], record["velocity"]))
    (tmp_path / "record.csv").write_text("time,force@0,velocity@0\n" + rows + "\n")
    (tmp_path / "pile.json").write_text(json.dumps(guessed()))
    fits = [arg for path, (low, high) in RESISTANCES.items() for arg in ("--fit", f"{path}={low}:{high}")]
    common = [str(tmp_path / "pile.json"), "--record", str(tmp_path / "record.csv"), *fits, "--processes", "1"]
    assert main(["match", *common, "--output", str(tmp_path / "m.json"), "--plot", str(tmp_path / "m.png")]) == 0
    shown = json.loads(capsys.readouterr().out)
    assert abs(shown["capacity"]["value"] - 8e5) <= 3 * shown["capacity"]["standard_error"]
    assert json.loads((tmp_path / "m.json").read_text())["static_load_test"]["load"][-1] > 7e5
    assert (tmp_path / "m.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    (tmp_path / "pile.json").write_text(json.dumps(guessed() | {"striker": {"mass": 1.0, "velocity": 1.0}}))
    assert main(["match", *common]) == 2
    assert "case.striker: the record drives the pile" in capsys.readouterr().err
    (tmp_path / "pile.json").write_text("{not json")
    assert main(["match", *common]) == 2
    assert "case: is not valid JSON" in capsys.readouterr().err
