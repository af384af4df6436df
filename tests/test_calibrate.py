"""Calibration against records it did not make: each record is solved by another scheme on another
grid (the σ-scheme on 1200 cells at τ = 0.1 µs, where every fit runs the explicit scheme at
Courant number 1 on its own grid) and carries 2% Gaussian noise, so that neither the fit's
discretisation nor its noise-free optimum is built into the answer."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from percussim.cli import main
from percussim.solver.calibrate import calibrate, record_noise
from percussim.solver.case import CaseError, parse_case
from percussim.solver.controller import simulate_rod
from percussim.solver.evaluate import Space
from percussim.solver.presets import preset_json
from percussim.solver.record import Record, parse_record, read_record, record_from_csv, record_to_csv
from percussim.solver.study import check_calibration, parse_calibration

TRUE = {"contact.stiffness": 8e11, "medium.stiffness": 2e9, "medium.damping": 1e5}
BOUNDS = {"contact.stiffness": [1e9, 1e15], "medium.stiffness": [1e7, 1e11], "medium.damping": [0.0, 1e6]}
NOISE = 0.02  # of the record's peak
GAUGE = 0.3  # m


def fig5_like(**medium) -> dict:
    """Fig. 5's striker, tool and contact on a stiffer medium with a damper, over 1.5 ms."""
    case = preset_json("fig5")
    case.pop("description")
    case["medium"] = {"stiffness": TRUE["medium.stiffness"], "damping": TRUE["medium.damping"], **medium}
    case["numerics"] = {"duration": 1.5e-3}
    return case


def other_setting_record(quantity: str, end: float = 1.5e-3, seed: int = 1) -> dict:
    """The true case's `quantity` by the σ-scheme on a fine grid, sampled at 1 MHz, with noise."""
    case = fig5_like()
    case["numerics"] = {"duration": end, "scheme": "sigma", "cells": 1200, "time_step": 1e-7}
    case["outputs"] = {"probes": [GAUGE]}
    run = simulate_rod(parse_case(case))
    t = np.arange(0.0, end, 1e-6)
    samples = {
        "contact_force": run.history["contact/force"],
        "medium_force": run.history["medium/force"],
        "stress": run.probe_stress[:, 0],
    }[quantity]
    values = np.interp(t, run.history["time"], samples)
    values += NOISE * np.abs(values).max() * np.random.default_rng(seed).standard_normal(len(t))
    return {
        "quantity": quantity,
        "time": t.tolist(),
        "values": values.tolist(),
        **({"x": GAUGE} if quantity == "stress" else {}),
    }


START = {"contact.stiffness": 1e11, "medium.stiffness": 5e8, "medium.damping": 4e5}


def start_case(fitted=tuple(START)) -> dict:
    """The case the fit starts from: the `fitted` values off by a factor of 4 to 8, the others
    true."""
    case = fig5_like()
    for name in fitted:
        part, field = name.split(".")
        case[part][field] = START[name]
    return case


def assert_recovered(fit: dict, names) -> None:
    for name in names:
        found = fit["parameters"][name]
        error = found["value"] / TRUE[name] - 1.0
        assert abs(error) <= 0.05, (name, found)
        assert abs(found["value"] - TRUE[name]) <= 3.0 * found["standard_error"], (name, found)
        assert found["low"] < TRUE[name] < found["high"] or abs(error) < 0.01, (name, found)


@pytest.mark.parametrize("quantity", ["contact_force", "stress"])
def test_two_parameters_are_recovered_within_5_percent_and_3_standard_errors(quantity):
    names = ["contact.stiffness", "medium.stiffness"]
    fit = calibrate(
        {
            "case": start_case(names),
            "record": other_setting_record(quantity),
            "parameters": {n: BOUNDS[n] for n in names},
        },
        processes=1,
    )
    assert_recovered(fit, names)
    assert fit["warnings"] == []
    # The misfit is the noise: nothing systematic is left.
    assert fit["nrmse"] == pytest.approx(fit["noise"], rel=0.15)
    assert fit["evaluations"] > 10
    fitted = parse_case(fit["case"])  # ready to run
    assert fitted.contact.stiffness == fit["parameters"]["contact.stiffness"]["value"]
    assert fitted.numerics.duration == fig5_like()["numerics"]["duration"]
    corr = np.array(fit["correlation"])
    assert corr.shape == (2, 2) and np.allclose(corr, corr.T) and np.allclose(np.diag(corr), 1.0)


@pytest.mark.parametrize("quantity", ["contact_force", "stress"])
def test_three_parameters_are_recovered_within_5_percent_and_3_standard_errors(quantity):
    fit = calibrate(
        {"case": start_case(), "record": other_setting_record(quantity, seed=3), "parameters": BOUNDS}, processes=1
    )
    assert_recovered(fit, BOUNDS)
    assert fit["warnings"] == []


def test_the_standard_errors_match_the_scatter_of_repeated_fits():
    """Ten records differing only in their noise: the values found scatter as the standard errors
    say (their ratio within 0.5–2, a loose band for ten samples)."""
    names = ["contact.stiffness", "medium.stiffness"]
    fits = [
        calibrate(
            {
                "case": start_case(names),
                "record": other_setting_record("stress", seed=seed),
                "parameters": {n: BOUNDS[n] for n in names},
            },
            processes=1,
        )
        for seed in range(10)
    ]
    for name in names:
        values = np.array([f["parameters"][name]["value"] for f in fits])
        stated = np.mean([f["parameters"][name]["standard_error"] for f in fits])
        assert 0.5 <= values.std(ddof=1) / stated <= 2.0, (name, values.std(ddof=1), stated)


def test_a_record_that_cannot_determine_a_parameter_is_warned_about():
    """The contact force before the wave's return from the medium (2L/a = 0.23 ms) says nothing
    of the medium."""
    fit = calibrate(
        {
            "case": start_case(("contact.stiffness", "medium.stiffness")),
            "record": other_setting_record("contact_force", end=0.2e-3),
            "parameters": {
                "contact.stiffness": BOUNDS["contact.stiffness"],
                "medium.stiffness": BOUNDS["medium.stiffness"],
            },
        },
        processes=1,
    )
    warned = [w for w in fit["warnings"] if w.startswith("medium.stiffness is not determined")]
    assert warned and "not unique" in warned[0]
    assert fit["parameters"]["medium.stiffness"]["standard_error"] is None
    assert abs(fit["parameters"]["contact.stiffness"]["value"] / TRUE["contact.stiffness"] - 1) < 0.05


def test_a_parameter_at_its_bound_is_warned_about():
    fit = calibrate(
        {
            "case": start_case(("contact.stiffness", "medium.stiffness")),
            "record": other_setting_record("stress"),
            "parameters": {"contact.stiffness": BOUNDS["contact.stiffness"], "medium.stiffness": [1e7, 1e9]},
        },
        processes=1,
    )
    assert any(w.startswith("medium.stiffness ended at its upper bound") for w in fit["warnings"])


def test_strongly_correlated_parameters_are_warned_about():
    """A Hertz contact's stiffness and exponent trade off against each other over one contact."""
    fit = calibrate(
        {
            "case": start_case(("contact.stiffness",)),
            "record": other_setting_record("contact_force", end=0.12e-3),
            "parameters": {"contact.stiffness": [1e10, 1e13], "contact.exponent": [0.3, 0.5]},
        },
        processes=1,
    )
    assert any("strongly correlated" in w and "contact.exponent" in w for w in fit["warnings"]), fit["warnings"]


def test_the_record_noise_estimate_reads_the_added_noise():
    record = other_setting_record("stress")
    peak_over_range = np.abs(record["values"]).max() / np.ptp(record["values"])
    assert record_noise(Record(**record)) == pytest.approx(NOISE * peak_over_range, rel=0.1)


# Bad records: refused with the reason, naming the field.


def good_record() -> dict:
    return {
        "quantity": "contact_force",
        "time": [i * 1e-6 for i in range(50)],
        "values": [math.sin(i / 10.0) * 1e5 for i in range(50)],
    }


@pytest.mark.parametrize(
    "change, field, words",
    [
        ({"time": [i * 1e-6 for i in range(49)] + [10e-6]}, "record.time[49]", "must increase"),
        ({"values": [1.0] * 20 + [float("nan")] + [1.0] * 29}, "record.values[20]", "finite"),
        (
            {"time": [i * 1e-6 for i in range(10)], "values": [float(i) for i in range(10)]},
            "record.time",
            "at least 20",
        ),
        ({"quantity": "stress"}, "record.x", "is required"),
        ({"quantity": "displacement"}, "record.quantity", ""),
        ({"values": [1.0] * 49}, "record.values", "one value per time"),
        ({"values": [1.0] * 3 + [True] + [1.0] * 46}, "record.values[3]", "must be a number, not true"),
        ({"time": ["0"] + [i * 1e-6 for i in range(1, 50)]}, "record.time[0]", 'not the string "0"'),
    ],
)
def test_bad_records_are_refused_naming_the_field(change, field, words):
    with pytest.raises(CaseError) as refused:
        parse_record(good_record() | change)
    fields = {e.field: e.message for e in refused.value.errors}
    assert field in fields, fields
    assert words in fields[field]


def test_a_gauge_off_the_tool_and_a_record_past_the_case_are_refused():
    record = other_setting_record("stress")
    off = dict(record, x=0.9)  # the tool is 0.6 m long
    with pytest.raises(CaseError) as refused:
        check_calibration(
            parse_calibration({"case": start_case(), "record": off, "parameters": {"contact.stiffness": [1e9, 1e13]}})
        )
    assert refused.value.errors[0].field == "record.x"
    assert "off the tool" in refused.value.errors[0].message
    late = dict(record, time=[t * 1000.0 for t in record["time"]])  # ms given as s
    with pytest.raises(CaseError) as refused:
        check_calibration(
            parse_calibration({"case": start_case(), "record": late, "parameters": {"contact.stiffness": [1e9, 1e13]}})
        )
    assert refused.value.errors[0].field == "record.time"
    assert "seconds" in refused.value.errors[0].message


@pytest.mark.parametrize("factor", [1e-3, 1e3])
def test_a_record_in_the_wrong_units_is_refused(factor):
    """kN instead of N (values 1000× too small) and N·1000 alike."""
    record = other_setting_record("contact_force")
    record["values"] = [v * factor for v in record["values"]]
    with pytest.raises(CaseError) as refused:
        calibrate({"case": start_case(), "record": record, "parameters": BOUNDS}, processes=1)
    error = refused.value.errors[0]
    assert error.field == "record.values" and "SI units" in error.message


def test_csv_round_trip_and_refusals(tmp_path):
    record = Record(**other_setting_record("stress"))
    again = record_from_csv(record_to_csv(record))
    assert again == record
    (tmp_path / "r.csv").write_text("time,force\n0,1\n")
    with pytest.raises(CaseError) as refused:
        read_record(tmp_path / "r.csv")
    assert refused.value.errors[0].field == "record.quantity"
    with pytest.raises(CaseError) as refused:
        record_from_csv("time,contact_force\n0,1\n1e-6,x\n")
    assert "line 3" in refused.value.errors[0].message


def test_parameters_must_be_continuous_fields_the_case_can_take():
    with pytest.raises(CaseError) as refused:
        check_calibration(
            parse_calibration(
                {
                    "case": start_case(),
                    "record": good_record(),
                    "parameters": {
                        "striker.colour": [1.0, 2.0],
                        "contact.exponent": [0.2, 0.9],
                        "contact.damping": [5.0, 1.0],
                    },
                }
            )
        )
    fields = {e.field for e in refused.value.errors}
    assert fields == {"parameters['contact.damping']"}  # low > high is seen first
    with pytest.raises(CaseError) as refused:
        check_calibration(
            parse_calibration(
                {
                    "case": start_case(),
                    "record": good_record(),
                    "parameters": {"striker.colour": [1.0, 2.0], "contact.exponent": [0.2, 0.9]},
                }
            )
        )
    fields = {e.field for e in refused.value.errors}
    assert "parameters['striker.colour'][0]" in fields and "parameters['contact.exponent'][1]" in fields


def test_the_unit_cube_is_logarithmic_for_positive_bounds():
    space = Space.of({"a": [1e9, 1e15], "b": [0.0, 10.0]}, "parameters")
    assert space.logarithmic.tolist() == [True, False]
    assert space.values(np.array([0.5, 0.5])) == pytest.approx([1e12, 5.0])
    values = np.array([3.3e10, 7.5])
    assert space.values(space.unit(values)) == pytest.approx(values)


def test_the_command_line_fits_and_refuses(tmp_path, capsys):
    record = Record(**other_setting_record("stress"))
    (tmp_path / "r.csv").write_text(record_to_csv(record))
    (tmp_path / "case.json").write_text(json.dumps(start_case(("contact.stiffness", "medium.stiffness"))))
    code = main(
        [
            "calibrate",
            str(tmp_path / "case.json"),
            "--record",
            str(tmp_path / "r.csv"),
            "--fit",
            "contact.stiffness=1e9:1e15",
            "--fit",
            "medium.stiffness=1e7:1e11",
            "--output",
            str(tmp_path / "fit.json"),
            "--plot",
            str(tmp_path / "fit.png"),
        ]
    )
    assert code == 0
    shown = json.loads(capsys.readouterr().out)
    assert abs(shown["parameters"]["medium.stiffness"]["value"] / TRUE["medium.stiffness"] - 1) < 0.05
    saved = json.loads((tmp_path / "fit.json").read_text())
    assert len(saved["series"]["model"]) == len(record.time)
    assert (tmp_path / "fit.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    (tmp_path / "bad.csv").write_text(record_to_csv(record).replace("\n1e-06,", "\n-1e-06,", 1))
    code = main(
        [
            "calibrate",
            str(tmp_path / "case.json"),
            "--record",
            str(tmp_path / "bad.csv"),
            "--fit",
            "contact.stiffness=1e9:1e15",
        ]
    )
    assert code == 2
    assert "record.time[1]: must increase" in capsys.readouterr().err
