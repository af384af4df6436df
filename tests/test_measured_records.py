"""Records as measuring equipment writes them: evenly sampled (a start and a rate), time stamps
rounded to a few digits, and a clock that starts when the pulse triggers the recorder at its gauge
rather than at the impact. And a fit to such a record: a split Hopkinson bar's incident pulse,
made without the kernel (d'Alembert's solution of two uniform rods through a contact spring,
`closed_forms.rods_through_a_spring`), checked against the wave theory's reading of the record."""

from __future__ import annotations

import math

import numpy as np
import pytest

from percussim.cli import main
from percussim.solver.calibrate import calibrate
from percussim.solver.case import CaseError, parse_case
from percussim.solver.controller import simulate_rod
from percussim.solver.grid import explicit_numerics
from percussim.solver.record import (
    even_sampling,
    parse_record,
    printed_step,
    read_record,
    record_from_csv,
    record_to_csv,
)
from percussim.solver.study import OFFSET, check_calibration, fitted_bounds, parse_calibration
from percussim.testing.closed_forms import Hopkinson as H


def test_the_closed_form_pulse_is_the_kernels_on_a_fine_grid():
    """The record's maker against the solver on 4000 cells: within 0.5% of the plateau."""
    case = parse_case(H.case() | {"outputs": {"probes": [H.GAUGE]}})
    run = simulate_rod(case, numerics=explicit_numerics(case, 4000))
    times = np.arange(0.0, 6.0e-4, 1e-7)
    kernel = np.interp(times, run.history["time"], run.probe_stress[:, 0])
    plateau = H.RHO * H.C * H.VELOCITY / 2.0
    assert np.abs(H.gauge_stress(times) - kernel).max() <= 5e-3 * plateau
    assert -H.gauge_stress(times).min() == pytest.approx(plateau, rel=1e-3)


def test_a_triggered_shpb_record_is_fitted_within_3_standard_errors_and_2_percent_of_wave_theory():
    text, offset = H.triggered_record()
    record = record_from_csv(text)
    assert len(record.notes) == 1 and "rounding an even sampling" in record.notes[0]
    assert np.abs(record.instants - np.arange(len(record.values)) / H.RATE).max() < 1e-9
    assert not record.starts_at_rest()
    start = H.case(velocity=7.0, length=0.8, stiffness=2e9)
    fit = calibrate(
        {
            "case": start,
            "record": record.model_dump(exclude_none=True),
            "parameters": {
                "striker.velocity": [2.0, 10.0],
                "striker.length": [0.3, 1.0],
                "contact.stiffness": [1e8, 1e10],
            },
        },
        processes=1,
    )
    found = fit["parameters"]
    truth = {"striker.velocity": H.VELOCITY, "striker.length": H.STRIKER, OFFSET: offset}
    for name, value in truth.items():
        assert abs(found[name]["value"] - value) <= 3.0 * found[name]["standard_error"], (name, found[name])
    assert found["striker.velocity"]["value"] == pytest.approx(H.VELOCITY, rel=0.005)
    assert found["striker.length"]["value"] == pytest.approx(H.STRIKER, rel=0.005)
    reading = H.reading(record.instants, record.values)
    assert found["striker.velocity"]["value"] == pytest.approx(reading["velocity"], rel=0.02)
    # The half-amplitude width of a pulse whose 20-µs front a contact spring makes is longer than
    # 2·L_s/c by the spring's unloading (`half_width_excess`: 23 mm of L_s, 3.8%), and so is the
    # impulse's (the striker rebounds): the wave theory's length is 2% off the truth or more. The
    # fit's length is within 2% of the reading less that excess, and the fitted model, read the
    # same way, gives the record's reading within 2%.
    excess = H.C * H.half_width_excess() / 2.0
    assert reading["half_width_length"] - excess == pytest.approx(H.STRIKER, rel=0.005)
    assert found["striker.length"]["value"] == pytest.approx(reading["half_width_length"] - excess, rel=0.02)
    model = H.reading(np.asarray(fit["series"]["time"]), fit["series"]["model"])
    for name in reading:
        assert model[name] == pytest.approx(reading[name], rel=0.02), name
    # the rise: the contact's stiffness within 10%
    assert found["contact.stiffness"]["value"] == pytest.approx(H.STIFFNESS, rel=0.1)
    assert fit["record"]["time_offset"] == found[OFFSET]["value"]
    assert fit["warnings"] == record.notes, fit["warnings"]
    assert fit["nrmse"] == pytest.approx(fit["noise"], rel=0.2)


@pytest.mark.parametrize("factor", [1e-3, 1.0 / H.E], ids=["1000 times too small", "strain, not stress"])
def test_a_record_in_other_units_is_refused_naming_its_units(factor):
    """Values 1000× too small (a prefix off: kPa read as Pa), or the gauge's strain itself."""
    text, _ = H.triggered_record()
    record = record_from_csv(text)
    small = record.model_dump(exclude_none=True) | {"values": [v * factor for v in record.values]}
    with pytest.raises(CaseError) as refused:
        check_calibration(
            parse_calibration({"case": H.case(), "record": small, "parameters": {"striker.velocity": [2.0, 10.0]}})
        )
    error = refused.value.errors[0]
    assert error.field == "record.values" and "SI units" in error.message and "(Pa)" in error.message


# Evenly sampled records


def test_a_start_and_a_rate_give_the_instants_and_survive_json_and_csv():
    values = [math.sin(k / 7.0) for k in range(50)]
    record = parse_record({"quantity": "contact_force", "time_start": 2e-6, "sample_rate": 1e6, "values": values})
    assert record.instants == pytest.approx(2e-6 + np.arange(50) * 1e-6)
    assert record.notes == []
    assert parse_record(record.model_dump(exclude_none=True)) == record
    text = record_to_csv(record)
    assert text.startswith("# time_start = 2e-06\n# sample_rate = 1000000.0\ncontact_force\n")
    assert record_from_csv(text) == record


def test_csv_comments_and_command_line_flags_give_the_sampling(tmp_path):
    values = "\n".join(f"{math.sin(k / 7.0):.6f}" for k in range(40))
    path = tmp_path / "r.csv"
    path.write_text(f"# recorded 2026-11-27, channel 3\n# sample_rate = 1e6\nstruck_end_velocity\n{values}\n")
    assert read_record(path).instants[-1] == pytest.approx(39e-6)
    path.write_text(f"struck_end_velocity\n{values}\n")
    with pytest.raises(CaseError) as refused:
        read_record(path)
    assert refused.value.errors[0].field == "record.time" and "sample_rate" in refused.value.errors[0].message
    flagged = read_record(path, sample_rate=2e6, time_offset=1e-5)
    assert flagged.instants[-1] == pytest.approx(19.5e-6) and flagged.time_offset == 1e-5
    path.write_text(f"# sample_rate = 1e6\nstruck_end_velocity\n{values}\n")
    with pytest.raises(CaseError) as refused:
        read_record(path, sample_rate=2e6)
    assert refused.value.errors[0].field == "record.sample_rate"


@pytest.mark.parametrize(
    "change, field, words",
    [
        ({"sample_rate": 1e6}, "record.sample_rate", "cannot be given with time"),
        ({"time_start": 0.0}, "record.time_start", "cannot be given with time"),
        ({"time": None}, "record.time", "is required"),
        ({"time": None, "time_start": 1e-6}, "record.sample_rate", "is required with time_start"),
        ({"time": None, "sample_rate": 0.0}, "record.sample_rate", "must be > 0"),
        ({"time": [-1e-3 + k * 1e-6 for k in range(50)]}, "record.time", "must reach past the impact"),
    ],
)
def test_inconsistent_clocks_are_refused_naming_the_field(change, field, words):
    base = {
        "quantity": "contact_force",
        "time": [k * 1e-6 for k in range(50)],
        "values": [math.sin(k / 7.0) for k in range(50)],
    }
    data = {key: value for key, value in (base | change).items() if value is not None}
    with pytest.raises(CaseError) as refused:
        parse_record(data)
    fields = {e.field: e.message for e in refused.value.errors}
    assert field in fields and words in fields[field], fields


@pytest.mark.parametrize("start", [0.0, 1e-4, -2e-5])
@pytest.mark.parametrize("digits", [2, 3, 4])
def test_a_rounded_even_sampling_is_rebuilt_within_2_ns(start, digits):
    """At 12.5 MHz (80 ns a sample), times of 2 to 4 significant digits: up to 125 samples share a
    time."""
    exact = start + np.arange(3000) / H.RATE
    rounded = [float(f"{t:.{digits}g}") for t in exact]
    record = parse_record(
        {"quantity": "contact_force", "time": rounded, "values": [math.sin(k / 50.0) for k in range(3000)]}
    )
    assert np.abs(record.instants - exact).max() < 2e-9
    assert "repeats" in record.notes[0] and "(1.25e+07 Hz" in record.notes[0]


@pytest.mark.parametrize(
    "time, bad",
    [
        # a repeat that is no rounding: one instant written twice in a record printed to 9 digits
        ([k * 1e-6 for k in range(30)] + [29e-6] + [k * 1e-6 for k in range(31, 60)], 30),
        # a step back
        ([k * 1e-6 for k in range(30)] + [28.5e-6] + [k * 1e-6 for k in range(31, 60)], 30),
        # rounded (five samples a printed time), but not evenly sampled: a gap of 25 samples
        ([float(f"{1e-5 + k * 2e-7 + (5e-6 if k > 30 else 0.0):.2g}") for k in range(60)], 1),
    ],
)
def test_times_that_are_not_a_rounded_even_sampling_are_refused(time, bad):
    with pytest.raises(CaseError) as refused:
        parse_record({"quantity": "contact_force", "time": time, "values": [math.sin(k / 7.0) for k in range(60)]})
    error = refused.value.errors[0]
    assert error.field == f"record.time[{bad}]" and "must increase" in error.message


def test_the_printed_step_is_the_last_digits_unit():
    assert printed_step(1.23e-5) == pytest.approx(1e-7)
    assert printed_step(0.5) == pytest.approx(0.1)
    assert printed_step(1.0 / 3.0) == pytest.approx(1e-16, rel=0.5)
    assert even_sampling([0.0, 0.0, 1.0]) is None  # two samples at 0 are no rounding of 0, 0.5, 1


# Records triggered at arrival


def test_a_record_at_rest_keeps_the_impact_as_its_time_zero_and_a_triggered_one_fits_its_offset():
    text, offset = H.triggered_record()
    triggered = record_from_csv(text)
    bounds = fitted_bounds(
        parse_calibration(
            {
                "case": H.case(),
                "record": triggered.model_dump(exclude_none=True),
                "parameters": {"striker.velocity": [2.0, 10.0]},
            }
        )
    )
    low, high = bounds[OFFSET]
    assert low < H.GAUGE / H.C < offset < high < H.GAUGE / H.C + 40e-6
    at_rest = parse_record(
        {
            "quantity": "stress",
            "x": H.GAUGE,
            "time_start": 0.0,
            "sample_rate": H.RATE,
            "values": H.gauge_stress(np.arange(0.0, 4e-4, 1.0 / H.RATE)).tolist(),
        }
    )
    assert at_rest.starts_at_rest()
    assert OFFSET not in fitted_bounds(
        parse_calibration(
            {
                "case": H.case(),
                "record": at_rest.model_dump(exclude_none=True),
                "parameters": {"striker.velocity": [2.0, 10.0]},
            }
        )
    )


def test_a_known_offset_is_used_and_cannot_be_fitted_too():
    text, offset = H.triggered_record()
    record = record_from_csv(text).model_dump(exclude_none=True) | {"time_offset": offset}
    fit = calibrate(
        {"case": H.case(velocity=7.0), "record": record, "parameters": {"striker.velocity": [2.0, 10.0]}}, processes=1
    )
    assert set(fit["parameters"]) == {"striker.velocity"}
    assert fit["parameters"]["striker.velocity"]["value"] == pytest.approx(H.VELOCITY, rel=0.01)
    assert fit["record"]["time_offset"] == offset
    with pytest.raises(CaseError) as refused:
        check_calibration(parse_calibration({"case": H.case(), "record": record, "parameters": {OFFSET: [0.0, 3e-4]}}))
    assert refused.value.errors[0].field == f"parameters[{OFFSET!r}]"


def test_the_command_line_reads_an_evenly_sampled_record_with_flags(tmp_path, capsys):
    import json

    text, offset = H.triggered_record()
    record = record_from_csv(text)
    (tmp_path / "r.csv").write_text(f"stress@{H.GAUGE}\n" + "\n".join(f"{v!r}" for v in record.values) + "\n")
    (tmp_path / "case.json").write_text(json.dumps(H.case(velocity=7.0)))
    code = main(
        [
            "calibrate",
            str(tmp_path / "case.json"),
            "--record",
            str(tmp_path / "r.csv"),
            "--sample-rate",
            str(H.RATE),
            "--time-offset",
            repr(offset),
            "--fit",
            "striker.velocity=2:10",
        ]
    )
    assert code == 0, capsys.readouterr().err
    shown = json.loads(capsys.readouterr().out)
    assert shown["parameters"]["striker.velocity"]["value"] == pytest.approx(H.VELOCITY, rel=0.01)
