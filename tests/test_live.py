"""The service against a live stack: real redis-server, real Celery workers, the real API.

The same flow runs in Redis mode and in the embedded default (no external server).
"""

from __future__ import annotations

import io
import time
from datetime import datetime

import h5py
import numpy as np
import pytest

from percussim.solver.case import parse_case
from percussim.solver.presets import load_preset, preset_json
from percussim.solver.simulate import simulate
from percussim.testing import merge
from percussim.testing.live_stack import Stack, redis_server, wait_for

pytestmark = pytest.mark.slow  # a live stack, a browser or the solver's full reports

# A job of several seconds: long enough to watch progress and to cancel it while it runs.
LONG = {
    "numerics": {"duration": 1.5, "cells": 600, "time_step": 8.3e-7},
    "outputs": {"history_stride": 100, "probes": []},
}


@pytest.fixture(scope="module")
def redis_url(tmp_path_factory):
    with redis_server(tmp_path_factory.mktemp("redis")) as url:
        yield url


@pytest.fixture(scope="module", params=["redis", "embedded"])
def stack(request, tmp_path_factory):
    broker = request.getfixturevalue("redis_url") if request.param == "redis" else None
    s = Stack(tmp_path_factory.mktemp(request.param), broker)
    yield s
    s.stop()


def _submit(stack: Stack, case: dict) -> dict:
    answer = stack.client.post("/v1/jobs", json=case)
    assert answer.status_code == 202, answer.text
    assert answer.json()["status"] == "queued"
    return answer.json()


@pytest.mark.parametrize("preset", ["fig3", "fig9"])
def test_a_preset_runs_to_the_same_summary_as_the_solver(stack, preset):
    job = _submit(stack, preset_json(preset))
    record = stack.wait_status(job["id"], ("succeeded", "failed"))
    assert record["status"] == "succeeded", (record, stack.logs())
    assert record["progress"] == 1.0
    direct = simulate(load_preset(preset))
    summary = stack.client.get(f"/v1/jobs/{job['id']}/summary").json()
    assert summary == direct.summary
    download = stack.client.get(f"/v1/jobs/{job['id']}/result.h5")
    assert download.status_code == 200
    with h5py.File(io.BytesIO(download.content)) as f:
        np.testing.assert_array_equal(f["contact/force"][()], direct.history["contact/force"])
        np.testing.assert_array_equal(f["probes/stress"][()], direct.probe_stress)
        assert f.attrs["format"] == "percussim-result"


def test_a_tolerance_job_runs_the_ladder_and_reports_its_estimate(stack):
    case = merge(
        preset_json("fig9"), {"numerics": {"time_step": None, "cells": None, "gamma": None, "tolerance": 1e-3}}
    )
    job = _submit(stack, case)
    record = stack.wait_status(job["id"], ("succeeded", "failed"))
    assert record["status"] == "succeeded", (record, stack.logs())
    summary = stack.client.get(f"/v1/jobs/{job['id']}/summary").json()
    assert summary["error_estimate"]["worst"] <= 1e-3 and len(summary["runs"]) >= 2
    assert summary["scheme"] == "explicit" and summary["why"]
    with h5py.File(io.BytesIO(stack.client.get(f"/v1/jobs/{job['id']}/result.h5").content)) as f:
        assert f["probes/stress"].shape[1] == 4  # the finest run kept the outputs asked


def test_a_sweep_fans_out_over_two_workers_into_one_table(redis_url, tmp_path):
    s = Stack(tmp_path, redis_url, workers=2)
    try:
        parameters = {"striker.velocity": [3.0, 5.0, 7.0], "contact.stiffness": [4e11, 8e11]}
        answer = s.client.post("/v1/sweeps", json={"case": preset_json("fig5"), "parameters": parameters})
        assert answer.status_code == 202, answer.text
        sweep = wait_for(
            lambda: (v := s.client.get(f"/v1/sweeps/{answer.json()['id']}").json())["finished"] and v, 60, "the sweep"
        )
        assert sweep["counts"] == {"succeeded": 6}, (sweep, s.logs())
        workers = {s.client.get(f"/v1/jobs/{row['job']}").json()["worker"] for row in sweep["rows"]}
        print(f"sweep: 6 variants on workers {sorted(workers)}")
        assert len(workers) == 2, "both workers took variants"
        for row in sweep["rows"]:
            direct = simulate(
                parse_case(
                    merge(
                        preset_json("fig5"),
                        {
                            "striker": {"velocity": row["values"]["striker.velocity"]},
                            "contact": {"stiffness": row["values"]["contact.stiffness"]},
                        },
                    )
                )
            ).summary
            assert row["peak_contact_force"] == direct["peak_contact_force"]["value"]
            assert row["co_impact_time"] == direct["co_impact_time"]
    finally:
        s.stop()


def test_an_oversized_body_gets_413_from_the_running_server(stack):
    answer = stack.client.post("/v1/jobs", json=merge(preset_json("fig3"), {"description": "x" * 3_000_000}))
    assert answer.status_code == 413 and "limit of 2000000 bytes" in answer.json()["detail"][0]["message"]


def test_an_invalid_case_gets_422_naming_the_field(stack):
    answer = stack.client.post("/v1/jobs", json=merge(preset_json("fig3"), {"contact": {"exponent": 0.9}}))
    assert answer.status_code == 422
    assert {"field": "contact.exponent", "message": "must be ≤ 0.5"} in answer.json()["detail"]


def test_progress_rises_and_cancel_stops_running_and_queued_jobs(stack):
    running = _submit(stack, merge(preset_json("fig3"), LONG))
    first = stack.wait_status(running["id"], ("running",), timeout=60)
    seen = [first["progress"]]
    while len(set(seen)) < 3 and stack.client.get(f"/v1/jobs/{running['id']}").json()["status"] == "running":
        time.sleep(0.3)
        seen.append(stack.client.get(f"/v1/jobs/{running['id']}").json()["progress"])
    assert seen == sorted(seen) and len(set(seen)) >= 3, seen  # progress rises while it runs
    queued = _submit(stack, preset_json("fig3"))  # the only worker is busy: it waits
    assert stack.client.get(f"/v1/jobs/{queued['id']}").json()["status"] == "queued"
    assert stack.client.delete(f"/v1/jobs/{queued['id']}").status_code == 202
    assert stack.client.get(f"/v1/jobs/{queued['id']}").json()["status"] == "cancelled"
    assert stack.client.delete(f"/v1/jobs/{running['id']}").status_code == 202
    stopped = stack.wait_status(running["id"], ("cancelled", "succeeded", "failed"), timeout=30)
    assert stopped["status"] == "cancelled" and stopped["progress"] < 1.0
    # The cancelled queued job never runs, and the worker is free for the next job.
    after = _submit(stack, preset_json("fig3"))
    assert stack.wait_status(after["id"], ("succeeded", "failed"))["status"] == "succeeded"
    assert stack.client.get(f"/v1/jobs/{queued['id']}").json()["started"] is None
    assert stack.client.get(f"/v1/jobs/{running['id']}/summary").status_code == 409
    cancelled = stack.client.get("/v1/jobs?status=cancelled").json()
    assert (
        {j["id"] for j in cancelled["jobs"]}
        == {queued["id"], running["id"]}
        == {
            j["id"]
            for j in stack.client.get("/v1/jobs?status=cancelled&limit=1").json()["jobs"]
            + stack.client.get(stack.client.get("/v1/jobs?status=cancelled&limit=1").json()["next"]).json()["jobs"]
        }
    )
    # A finished job is removed with its files: 204, then 404.
    folder = stack.folder / "results" / "jobs" / after["id"]
    assert (folder / "result.h5").is_file()
    assert stack.client.delete(f"/v1/jobs/{after['id']}").status_code == 204
    assert stack.client.get(f"/v1/jobs/{after['id']}").status_code == 404 and not folder.exists()


def test_a_case_the_solver_refuses_ends_failed_with_the_reason(redis_url, tmp_path):
    """A worker configured with a smaller limit than the API refuses the case when it runs it."""
    s = Stack(tmp_path, redis_url, worker_env={"PERCUSSIM_MAX_CELLS": "150"})
    try:
        job = _submit(s, merge(preset_json("fig3"), {"numerics": {"cells": 200}}))
        record = s.wait_status(job["id"], ("succeeded", "failed"))
        assert record["status"] == "failed"
        assert "numerics.cells" in record["error"] and "limit of 150" in record["error"]
        conflict = s.client.get(f"/v1/jobs/{job['id']}/summary")
        assert conflict.status_code == 409
    finally:
        s.stop()


def test_a_job_past_its_time_limit_ends_failed_with_the_reason(redis_url, tmp_path):
    s = Stack(tmp_path, redis_url, worker_env={"PERCUSSIM_JOB_TIME_LIMIT": "1"})
    try:
        job = _submit(s, merge(preset_json("fig3"), LONG))
        record = s.wait_status(job["id"], ("succeeded", "failed", "cancelled"), timeout=60)
        assert record["status"] == "failed"
        assert "time limit of 1 s" in record["error"]
        started, finished = (datetime.fromisoformat(record[k]) for k in ("started", "finished"))
        assert (finished - started).total_seconds() < 5  # stopped between chunks, not at the end
    finally:
        s.stop()


def test_a_calibration_runs_as_a_job_and_recovers_the_parameters(stack):
    """A record made by the σ-scheme on a finer grid with 2% noise: the fit through the service
    recovers what the solver's own fit does, with its plot; a bad record is refused with 422."""
    from test_calibrate import TRUE, other_setting_record, start_case

    names = ("contact.stiffness", "medium.stiffness")
    request = {
        "case": start_case(names),
        "record": other_setting_record("stress"),
        "parameters": {"contact.stiffness": [1e9, 1e15], "medium.stiffness": [1e7, 1e11]},
    }
    answer = stack.client.post("/v1/calibrations", json=request)
    assert answer.status_code == 202, answer.text
    assert answer.headers["Location"] == answer.json()["links"]["self"]
    done = stack.wait_status(answer.json()["id"], ("succeeded", "failed"))
    assert done["status"] == "succeeded", (done, stack.logs())
    fit = stack.client.get(answer.json()["links"]["self"]).json()["fit"]
    for name in names:
        found = fit["parameters"][name]
        assert abs(found["value"] / TRUE[name] - 1.0) < 0.05
        assert abs(found["value"] - TRUE[name]) <= 3 * found["standard_error"]
    assert stack.client.get(answer.json()["links"]["plot_png"]).content[:4] == b"\x89PNG"
    late = dict(request["record"], time=[t * 1e3 for t in request["record"]["time"]])
    refused = stack.client.post("/v1/calibrations", json=request | {"record": late})
    assert refused.status_code == 422
    assert refused.json()["detail"][0]["field"] == "record.time"


def test_an_optimisation_spreads_its_runs_over_the_workers_and_keeps_its_limit(redis_url, tmp_path):
    """Runs of tens of milliseconds (a 1.5-m rod on thousands of cells) go to the other worker too;
    the answer keeps the stress limit when checked under the tolerance."""
    from test_optimize import short_rock_drill

    s = Stack(tmp_path, redis_url, workers=2)
    try:
        allowable = 250e6
        answer = s.client.post(
            "/v1/optimizations",
            json={
                "case": short_rock_drill(),
                "variables": {"striker.length": [0.1, 0.6], "striker.velocity": [5.0, 20.0]},
                "objective": {"maximize": "energy.to_medium"},
                "limits": {"max_compressive_stress": {"max": allowable}},
                "max_evaluations": 120,
            },
        )
        assert answer.status_code == 202, answer.text
        done = s.wait_status(answer.json()["id"], ("succeeded", "failed"), timeout=300)
        assert done["status"] == "succeeded", (done, s.logs())
        optimum = s.client.get(answer.json()["links"]["self"]).json()["optimum"]
        assert optimum["summary"]["max_compressive_stress"]["value"] <= allowable
        spread = optimum["runs_spread"]
        print(f"optimisation: {optimum['evaluations']} runs, spread {spread}")
        assert spread["other_workers"] > 0 and spread["here"] > 0
        assert s.client.get(answer.json()["links"]["plot_svg"]).text.startswith("<?xml")
    finally:
        s.stop()


def test_a_running_optimisation_can_be_cancelled(stack):
    from test_optimize import short_rock_drill

    answer = stack.client.post(
        "/v1/optimizations",
        json={
            "case": short_rock_drill(),
            "variables": {"striker.length": [0.1, 0.6]},
            "objective": {"maximize": "energy.transfer_efficiency"},
            "max_evaluations": 5000,
        },
    )
    assert answer.status_code == 202, answer.text
    study = answer.json()["links"]["self"]
    wait_for(lambda: stack.client.get(study).json()["status"] == "running", 60, "the optimisation")
    assert stack.client.delete(study).status_code == 202
    done = stack.wait_status(answer.json()["id"], ("cancelled", "succeeded", "failed"))
    assert done["status"] == "cancelled", done
    assert stack.client.get(study).json()["optimum"] is None
