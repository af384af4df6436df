"""The data behind the interactive plots: each series checked against the result's datasets read
with h5py (peaks kept exactly by the decimation, the energy budget closing, the stress field's
strides, the CSV's every sample), and over HTTP with its refusals."""

from __future__ import annotations

import csv
import io
import json
import math

import h5py
import numpy as np
import pytest
from conftest import BASE_CASE, merge, succeeded_job
from fastapi.testclient import TestClient

import percussim.solver.series as series_module
from percussim.common.store import JobStore
from percussim.solver.case import parse_case
from percussim.solver.io import write_result
from percussim.solver.plots import NotAvailable
from percussim.solver.presets import preset_json
from percussim.solver.series import SERIES, UnknownSeries, csv_chunks, dumps, problems, series
from percussim.solver.simulate import simulate
from percussim.testing.closed_forms import drilling


def _write(folder, name: str, case: dict) -> str:
    return str(write_result(simulate(parse_case(case)), folder / f"{name}.h5"))


@pytest.fixture(scope="module")
def results(tmp_path_factory) -> dict[str, str]:
    """The Fig. 9 preset on 40 cells (12 801 samples) with its four probes and fields every 20
    steps (`full`), without fields or probes (`bare`), without a medium (`free`); an elastic
    piston on rock, 3 blows (`blows`)."""
    folder = tmp_path_factory.mktemp("series")
    fig9 = merge(preset_json("fig9"), {"numerics": {"cells": 40}})
    return {
        "full": _write(folder, "full", merge(fig9, {"outputs": {"fields": True, "field_stride": 20}})),
        "bare": _write(folder, "bare", merge(fig9, {"outputs": None})),
        "free": _write(folder, "free", merge(fig9, {"medium": None, "outputs": None})),
        "blows": _write(folder, "blows", {**drilling(3, {"scheme": "explicit", "cells": 100}), "name": "blows"}),
    }


def _read(path: str, dataset: str) -> np.ndarray:
    with h5py.File(path) as f:
        return f[dataset][()]


def _summary(path: str) -> dict:
    with h5py.File(path) as f:
        return json.loads(f["summary"][()])


def _curves(data: dict) -> dict[str, dict]:
    return {curve["key"]: curve for curve in data["series"]}


def _samples_of(time: np.ndarray, curve: dict, full: np.ndarray) -> None:
    """Every point of `curve` is a sample of `full` against `time`, in time order."""
    rows = np.searchsorted(time, curve["x"])
    assert np.all(np.diff(rows) > 0)
    np.testing.assert_array_equal(time[rows], curve["x"])
    np.testing.assert_array_equal(full[rows], curve["y"])


@pytest.mark.parametrize("points", [2000, 301, 10])
def test_decimated_forces_keep_every_peak_and_both_ends_exactly(results, points):
    path = results["full"]
    time = _read(path, "time")
    data = series(path, "force", points=points)
    assert data["samples"] == len(time) == 12801 and data["decimated"] is True
    assert data["x"] == {"label": "time t", "unit": "s"} and data["y"] == {"label": "force", "unit": "N"}
    curves = _curves(data)
    assert list(curves) == ["contact_force", "medium_force", "external_force"]
    for key, dataset in (
        ("contact_force", "contact/force"),
        ("medium_force", "medium/force"),
        ("external_force", "external/force"),
    ):
        full, curve = _read(path, dataset), curves[key]
        assert len(curve["x"]) <= points + 2
        assert curve["y"].max() == full.max() and curve["y"].min() == full.min()
        assert (curve["x"][0], curve["y"][0]) == (time[0], full[0])
        assert (curve["x"][-1], curve["y"][-1]) == (time[-1], full[-1])
        _samples_of(time, curve, full)
    # The summary's peak is the vertex of a parabola through the samples about it, a little above.
    peak = _summary(path)["peak_contact_force"]["value"]
    assert curves["contact_force"]["y"].max() == pytest.approx(peak, rel=1e-5) and peak >= full.max()


def test_decimation_read_a_block_at_a_time_keeps_the_peaks_across_blocks(results, monkeypatch):
    """Blocks of 1000 rows (13 of them) give buckets that end at each block's end."""
    monkeypatch.setattr(series_module, "BLOCK_ROWS", 1000)
    path = results["full"]
    time, full = _read(path, "time"), _read(path, "contact/force")
    curve = _curves(series(path, "force", points=500))["contact_force"]
    assert len(curve["y"]) <= 502
    assert curve["y"].max() == full.max() and curve["y"].min() == full.min()
    _samples_of(time, curve, full)
    assert curve["x"][-1] == time[-1]


def test_points_0_is_every_sample_up_to_the_cap(results, monkeypatch):
    path = results["full"]
    time, full = _read(path, "time"), _read(path, "tool/working_end_displacement")
    data = series(path, "displacements", points=0)
    assert data["decimated"] is False
    curve = _curves(data)["working_end"]
    np.testing.assert_array_equal(curve["x"], time)
    np.testing.assert_array_equal(curve["y"], full)
    assert [c["label"] for c in data["series"]] == ["striker", "struck end of the tool", "working end of the tool"]
    monkeypatch.setattr(series_module, "MAX_POINTS", 1000)
    capped = series(path, "displacements", points=0)
    assert capped["decimated"] is True
    curve = _curves(capped)["working_end"]
    assert len(curve["y"]) <= 1002 and curve["y"].max() == full.max() and curve["y"].min() == full.min()


def test_the_probe_stresses_are_a_curve_a_probe_named_by_its_x(results):
    path = results["full"]
    stress, time = _read(path, "probes/stress"), _read(path, "time")
    data = series(path, "probes")
    assert data["y"] == {"label": "stress σ", "unit": "Pa"}
    assert [(c["key"], c["label"]) for c in data["series"]] == [
        ("probe_0", "x = 0.01 m"),
        ("probe_1", "x = 0.12 m"),
        ("probe_2", "x = 0.235 m"),
        ("probe_3", "x = 0.485 m"),
    ]
    for k, curve in enumerate(data["series"]):
        assert curve["y"].min() == stress[:, k].min() and curve["y"].max() == stress[:, k].max()
        _samples_of(time, curve, stress[:, k])


def test_the_force_penetration_loop_keeps_the_extremes_of_both_axes(results):
    path = results["full"]
    force, u = _read(path, "medium/force"), _read(path, "tool/working_end_displacement")
    data = series(path, "force_penetration", points=400)
    assert data["x"] == {"label": "penetration of the working end u_N", "unit": "m"}
    [curve] = data["series"]
    assert curve["key"] == "medium_force" and len(curve["x"]) <= 402
    assert curve["x"].max() == u.max() and curve["x"].min() == u.min()
    assert curve["y"].max() == force.max() and curve["y"].min() == force.min()
    assert (curve["x"][0], curve["y"][0], curve["x"][-1], curve["y"][-1]) == (u[0], force[0], u[-1], force[-1])


@pytest.mark.parametrize("name", ["full", "blows"])
def test_the_energy_terms_share_one_stride_and_add_up_to_the_input(results, name):
    """The input is ½·m1·W1² (the summary's initial energy less what later blows bring, which the
    launched history adds as they come) + the external work, read here from the datasets."""
    path = results[name]
    data = series(path, "energy", points=500)
    assert data["y"] == {"label": "energy", "unit": "J"}
    rows = data["samples"]
    step = math.ceil(rows / 500)
    picked = np.unique(np.r_[np.arange(0, rows, step), rows - 1])
    with h5py.File(path) as f:
        energy = f["energy"]
        launched = energy["launched"][()] - energy["launched"][-1] if "launched" in energy else 0.0
        supplied = (_summary(path)["energy"]["initial"] + energy["external_work"][()] + launched)[picked]
        stored = {key: energy[key][()][picked] for key in energy if key not in ("external_work", "launched")}
        time = f["time"][()][picked]
    curves = _curves(data)
    assert set(curves) == set(stored) | {"input", "numerical"}
    for curve in curves.values():
        np.testing.assert_array_equal(curve["x"], time)
    for key, values in stored.items():
        np.testing.assert_array_equal(curves[key]["y"], values)
    np.testing.assert_allclose(curves["input"]["y"], supplied, rtol=1e-13)
    total = sum(curves[key]["y"] for key in stored) + curves["numerical"]["y"]
    np.testing.assert_allclose(total, curves["input"]["y"], rtol=1e-12, atol=1e-12 * supplied.max())
    assert curves["numerical"]["y"][-1] == pytest.approx(
        _summary(path)["energy"]["numerical"], abs=1e-6 * supplied.max()
    )


def test_the_stress_field_is_read_with_strides_keeping_the_first_and_last(results):
    path = results["full"]
    with h5py.File(path) as f:
        stress, x, t = f["fields/stress"][()], f["fields/x"][()], f["fields/time"][()]
    assert stress.shape == (641, 41)
    data = series(path, "fields", times=100, stations=8)
    assert data["samples"] == {"times": 641, "stations": 41} and data["decimated"] is True
    assert data["x"] == {"label": "x along the tool", "unit": "m"} and data["stress_unit"] == "Pa"
    rows, columns = np.searchsorted(t, data["times"]), np.searchsorted(x, data["stations"])
    assert len(rows) <= 100 and len(columns) <= 8
    for picked, n in ((rows, 641), (columns, 41)):
        assert picked[0] == 0 and picked[-1] == n - 1
        assert len(set(np.diff(picked[:-1]))) == 1 and 0 < picked[-1] - picked[-2] <= picked[1]
    np.testing.assert_array_equal(data["stress"], stress[np.ix_(rows, columns)])
    whole = series(path, "fields", times=0, stations=0)
    assert whole["decimated"] is False
    np.testing.assert_array_equal(whole["stress"], stress)
    frames = len(series(path, "fields")["times"])  # 641 frames at most 300: every third, and the last
    assert frames == 215


def test_the_json_has_six_significant_digits_and_is_smaller(results):
    path = results["full"]
    data = series(path, "probes")
    text = dumps(data)
    loaded = json.loads(text)
    for curve, sent in zip(data["series"], loaded["series"]):
        np.testing.assert_allclose(sent["y"], curve["y"], rtol=5e-6, atol=0)
        assert sent["y"] == [float(f"{v:.6g}") for v in curve["y"]]
    plain = json.dumps(
        {**data, "series": [{**c, "x": c["x"].tolist(), "y": c["y"].tolist()} for c in data["series"]]},
        separators=(",", ":"),
    )
    assert len(text) < 0.65 * len(plain)
    assert json.loads(dumps({"v": np.array([1.0, np.nan, -np.inf])})) == {"v": [1.0, None, None]}


def _csv(path: str, name: str) -> list[list[str]]:
    return list(csv.reader(io.StringIO("".join(csv_chunks(path, name)))))


def test_the_csv_is_every_sample_to_the_last_bit(results, monkeypatch):
    monkeypatch.setattr(series_module, "CSV_VALUES", 20_000)  # 5000 rows of 4 columns a chunk
    path = results["full"]
    assert len(list(csv_chunks(path, "force"))) == 1 + 3  # the header, then the rows
    header, *rows = _csv(path, "force")
    assert header == ["time t (s)", "contact force (N)", "medium force (N)", "external force on the striker (N)"]
    table = np.array(rows, dtype=float)
    assert table.shape == (12801, 4)
    for k, dataset in enumerate(("time", "contact/force", "medium/force", "external/force")):
        np.testing.assert_array_equal(table[:, k], _read(path, dataset))
    header, *rows = _csv(path, "force_penetration")
    assert header == ["time t (s)", "penetration of the working end u_N (m)", "medium force (N)"]
    assert len(rows) == 12801


def test_the_fields_csv_is_a_row_a_frame_and_a_column_a_station(results):
    path = results["full"]
    with h5py.File(path) as f:
        stress, x, t = f["fields/stress"][()], f["fields/x"][()], f["fields/time"][()]
    header, *rows = _csv(path, "fields")
    assert header[0] == "time t (s)" and header[1:4] == ["x=0.0 m", "x=0.0125 m", "x=0.025 m"]
    assert [float(h[2:-2]) for h in header[1:]] == list(x)
    table = np.array(rows, dtype=float)
    np.testing.assert_array_equal(table[:, 0], t)
    np.testing.assert_array_equal(table[:, 1:], stress)


def test_what_a_result_lacks_is_refused_with_the_plots_reasons(results):
    # everything but a hammer at work's, which a single blow has not
    cycles = {"pressures", "striker_velocity"}
    full = problems(results["full"])
    assert {name: why for name, why in full.items() if name not in cycles} == dict.fromkeys(set(SERIES) - cycles)
    assert all("no hammer at work" in full[name] for name in cycles)
    bare = problems(results["bare"])
    assert bare["fields"] == "this result has no stress fields: run the case with outputs.fields = true"
    assert "run the case with outputs.probes" in bare["probes"]
    assert problems(results["free"])["force_penetration"].startswith("this case has no medium")
    assert [c["key"] for c in series(results["free"], "force")["series"]] == ["contact_force", "external_force"]
    with pytest.raises(NotAvailable, match="outputs.fields = true"):
        series(results["bare"], "fields")
    with pytest.raises(NotAvailable, match="no medium"):
        csv_chunks(results["free"], "force_penetration")
    with pytest.raises(UnknownSeries, match="the series are: force, displacements, probes, energy"):
        series(results["full"], "forces")


# --- over HTTP -------------------------------------------------------------------------------------


def _job(client: TestClient, case: dict = BASE_CASE) -> str:
    answer = client.post("/v1/jobs", json=case)
    assert answer.status_code == 202, answer.text
    return answer.json()["id"]


def _succeeded(client: TestClient, jobs: JobStore, result: str) -> str:
    return succeeded_job(client, jobs, result, merge(BASE_CASE, {"name": "my rod/2"}))


def test_http_lists_the_series_with_their_links_and_reasons(results, api_store):
    client, jobs = api_store
    job_id = _succeeded(client, jobs, results["bare"])
    answer = client.get(f"/v1/jobs/{job_id}/series")
    assert answer.status_code == 200
    listed = {s["name"]: s for s in answer.json()["series"]}
    assert list(listed) == list(SERIES)
    assert listed["force"] == {
        "name": "force",
        "title": "Contact force",
        "available": True,
        "reason": None,
        "links": {"json": f"/v1/jobs/{job_id}/series/force", "csv": f"/v1/jobs/{job_id}/series/force.csv"},
    }
    assert listed["fields"]["available"] is False and "outputs.fields = true" in listed["fields"]["reason"]


def test_http_serves_a_series_as_compact_json_and_every_sample_as_csv(results, api_store):
    client, jobs = api_store
    job_id = _succeeded(client, jobs, results["full"])
    answer = client.get(f"/v1/jobs/{job_id}/series/force", params={"points": 300})
    assert answer.status_code == 200 and answer.headers["content-type"] == "application/json"
    assert answer.content == dumps(series(results["full"], "force", points=300))
    sent = answer.json()
    assert sent["name"] == "force" and sent["case"] == "fig9" and sent["samples"] == 12801
    peak = _read(results["full"], "contact/force").max()
    assert max(_curves(sent)["contact_force"]["y"]) == float(f"{peak:.6g}")
    fields = client.get(f"/v1/jobs/{job_id}/series/fields", params={"times": 5, "stations": 3}).json()
    assert np.shape(fields["stress"]) == (5, 3) and fields["stations"] == [0, 0.2625, 0.5]  # h = 0.0125
    download = client.get(f"/v1/jobs/{job_id}/series/probes.csv")
    assert download.status_code == 200 and download.headers["content-type"] == "text/csv; charset=utf-8"
    assert download.headers["content-disposition"] == f'attachment; filename="my_rod_2-{job_id}-probes.csv"'
    assert download.text == "".join(csv_chunks(results["full"], "probes"))
    assert len(download.text.splitlines()) == 12802


def test_http_refuses_an_unknown_or_unavailable_series_and_bad_counts(results, api_store):
    client, jobs = api_store
    job_id = _succeeded(client, jobs, results["bare"])
    for suffix in ("", ".csv"):
        unknown = client.get(f"/v1/jobs/{job_id}/series/forces{suffix}")
        assert unknown.status_code == 404
        assert unknown.json()["detail"] == (
            "no series named 'forces'; the series are: force, displacements, probes, energy, force_penetration, "
            "pressures, striker_velocity, fields"
        )
        missing = client.get(f"/v1/jobs/{job_id}/series/probes{suffix}")
        assert missing.status_code == 404
        assert missing.json()["detail"].startswith(
            f"job {job_id} has no probes series: this result has no probes: run the case with outputs.probes"
        )
    for params, field, message in (
        ({"points": -1}, "query.points", "greater than or equal to 0"),
        ({"points": 10**7 + 1}, "query.points", "less than or equal to 10000000"),
        ({"points": "many"}, "query.points", "valid integer"),
        ({"times": 3}, "query.times", "the force series takes points, not times"),
    ):
        bad = client.get(f"/v1/jobs/{job_id}/series/force", params=params)
        assert bad.status_code == 422, bad.text
        [error] = bad.json()["detail"]
        assert error["field"] == field and message in error["message"]
    with_fields = _succeeded(client, jobs, results["full"])
    bad = client.get(f"/v1/jobs/{with_fields}/series/fields", params={"points": 3})
    assert bad.json()["detail"] == [
        {"field": "query.points", "message": "the fields series takes times and stations, not points"}
    ]


def test_http_answers_409_until_the_job_has_succeeded(api_store):
    client, _ = api_store
    job_id = _job(client)
    for path in ("series", "series/force", "series/force.csv", "series/fields"):
        answer = client.get(f"/v1/jobs/{job_id}/{path}")
        assert answer.status_code == 409 and "queued" in answer.json()["detail"], path
    assert client.get("/v1/jobs/nope/series/force").status_code == 404


def test_http_gives_a_jobs_case_whatever_its_status(api_store):
    """The case as submitted, with the defaults the service spelled out: what the page compares
    and loads back into its form; an unknown job is 404."""
    client, _ = api_store
    job_id = _job(client)
    case = client.get(f"/v1/jobs/{job_id}/case")
    assert case.status_code == 200
    assert case.json() == parse_case(BASE_CASE).model_dump(mode="json", exclude_none=True)
    assert client.get("/v1/jobs/nope/case").status_code == 404
