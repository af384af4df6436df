"""The HTTP API without a worker: validation, the job records, errors, presets, health, OpenAPI.

Jobs are published to the embedded broker under the test's folder, where no worker takes them, so
a submitted job stays queued.
"""

from __future__ import annotations

import json
import time

import pytest
from conftest import BASE_CASE, merge
from fastapi.testclient import TestClient

from percussim.common.broker import queue_folder
from percussim.common.settings import Settings
from percussim.common.store import FAILED, SUCCEEDED, JobStore, WorkerRegistry
from percussim.service.app import create_app
from percussim.service.main import queue_again, restore_queue
from percussim.service.queue import JobQueue
from percussim.service.recovery import MAX_ATTEMPTS
from percussim.solver.presets import PRESETS_ENV, preset_json, preset_names
from percussim.solver.simulate import simulate

# Only what a test sets: nothing from the caller's shell.
pytestmark = pytest.mark.usefixtures("clean_environment")


def _client(tmp_path, **settings) -> TestClient:
    return TestClient(create_app(Settings(results_dir=tmp_path, **settings)))


@pytest.fixture
def client(tmp_path) -> TestClient:
    return _client(tmp_path)


def _submit(client: TestClient, case: dict = BASE_CASE) -> dict:
    answer = client.post("/v1/jobs", json=case)
    assert answer.status_code == 202, answer.text
    return answer.json()


PROFILE = {"area": None, "profile": {"x": [0.0, 0.6, 1.2], "area": [0.01, 0.01, -1.0]}}


@pytest.mark.parametrize(
    "changes, field, message",
    [
        ({"contact": {"exponent": 0.9}}, "contact.exponent", "must be ≤ 0.5"),
        ({"tool": PROFILE}, "tool.profile.area[2]", "must be > 0.0"),
        ({"striker": None}, "striker", "is required, unless a history drives the struck end (struck_end)"),
        ({"colour": "red"}, "colour", "is not a known field"),
        ({"force": {"kind": "pulse", "amplitude": 1e3}}, "force.duration", "is required"),
        ({"force": {"kind": "square", "amplitude": 1e3}}, "force", "kind must be one of 'sine', 'abs_sine', 'pulse'"),
        ({"numerics": {"cells": 10.5}}, "numerics.cells", "must be a whole number"),
        # a boolean or a numeric string is not read as a number ("mass": true was 1 kg)
        ({"striker": {"mass": True}}, "striker.mass", "must be a number, not true"),
        ({"striker": {"mass": "2"}}, "striker.mass", 'must be a number, not the string "2"'),
        ({"numerics": {"scheme": "explicit", "cells": False}}, "numerics.cells", "must be a whole number, not false"),
        ({"outputs": {"probes": [0.1, "0.2"]}}, "outputs.probes[1]", 'must be a number, not the string "0.2"'),
        ({"outputs": {"fields": 1}}, "outputs.fields", "must be true or false"),
        ({"outputs": {"probes": [0.1, 2.0]}}, "outputs.probes[1]", "must lie on the tool, 0 ≤ x ≤ tool.length = 1.2 m"),
        ({"numerics": {"scheme": "implicit"}}, "numerics.scheme", "Input should be 'paper', 'sigma' or 'explicit'"),
        (
            {"numerics": {"tolerance": 1e-3}},
            "numerics.tolerance",
            "cannot be combined with numerics.time_step: under a tolerance the solver chooses the grid; "
            "give one or the other",
        ),
        (
            {"numerics": {"scheme": "explicit", "time_step": 1e-5}},
            "numerics.time_step",
            "the explicit scheme needs a Courant number a·τ/h ≤ 1, and τ = 1e-05 s on 100 cells gives "
            "4.324: set numerics.time_step ≤ 2.313e-06 s, use fewer cells, or numerics.scheme = 'sigma'",
        ),
    ],
)
def test_an_invalid_case_gets_422_naming_the_field(client, changes, field, message):
    answer = client.post("/v1/jobs", json=merge(BASE_CASE, changes))
    assert answer.status_code == 422
    assert answer.json() == {"detail": [{"field": field, "message": message}]}


def test_every_invalid_field_is_named_at_once(client):
    answer = client.post("/v1/jobs", json=merge(BASE_CASE, {"striker": {"mass": 0}, "contact": {"exponent": -1}}))
    assert answer.status_code == 422
    assert {e["field"] for e in answer.json()["detail"]} == {"striker.mass", "contact.exponent"}


@pytest.mark.parametrize(
    "content, headers, message",
    [
        ("{not json", {"content-type": "application/json"}, "is not valid JSON"),
        ("[1, 2]", {"content-type": "application/json"}, "must be a JSON object"),
        (json.dumps(BASE_CASE), {"content-type": "text/plain"}, "sent as application/json"),
        ("", {"content-type": "application/json"}, "must be a JSON object"),
    ],
)
def test_a_body_that_is_not_a_json_object_is_named_body(client, content, headers, message):
    answer = client.post("/v1/jobs", content=content, headers=headers)
    assert answer.status_code == 422
    [error] = answer.json()["detail"]
    assert error["field"] == "body" and message in error["message"]


def test_a_case_over_the_limits_is_refused_up_front_naming_the_limit(tmp_path):
    client = _client(tmp_path, max_cells=50, max_steps=1000)
    answer = client.post("/v1/jobs", json=BASE_CASE)  # 100 cells, 1205 steps
    assert answer.status_code == 422
    errors = {e["field"]: e["message"] for e in answer.json()["detail"]}
    assert "limit of 50" in errors["numerics.cells"]
    assert "limit of 1000" in errors["numerics.time_step"]
    assert client.get("/v1/jobs").json()["total"] == 0, "a refused case creates no job"


def test_a_submitted_job_is_queued_with_its_links_and_published(client, tmp_path):
    answer = client.post("/v1/jobs", json=BASE_CASE)
    assert answer.status_code == 202
    job = answer.json()
    assert job["status"] == "queued" and job["progress"] == 0.0 and job["name"] == "test"
    assert job["started"] is None and job["finished"] is None and job["error"] is None
    assert job["links"] == {
        "self": f"/v1/jobs/{job['id']}",
        "summary": f"/v1/jobs/{job['id']}/summary",
        "result": f"/v1/jobs/{job['id']}/result.h5",
        "plots": f"/v1/jobs/{job['id']}/plots",
    }
    assert answer.headers["location"] == job["links"]["self"]
    assert client.get(job["links"]["self"]).json() == job
    stored = JobStore(Settings(results_dir=tmp_path)).case(job["id"])
    assert stored["striker"] == BASE_CASE["striker"] and stored["numerics"]["gamma"] == 0.5
    messages = list((tmp_path / "broker" / "queue").glob("*.msg"))
    assert len(messages) == 1 and job["id"] in messages[0].read_text()


def test_summary_and_result_are_409_until_the_job_succeeds(client):
    job = _submit(client)
    for what in ("summary", "result.h5"):
        answer = client.get(f"/v1/jobs/{job['id']}/{what}")
        assert answer.status_code == 409
        assert "queued" in answer.json()["detail"]


def test_a_failed_job_names_its_error_in_the_409(client, tmp_path):
    job = _submit(client)
    JobStore(Settings(results_dir=tmp_path)).finish(job["id"], FAILED, error="the kernel diverged")
    answer = client.get(f"/v1/jobs/{job['id']}/summary")
    assert answer.status_code == 409
    assert "failed" in answer.json()["detail"] and "the kernel diverged" in answer.json()["detail"]


def test_a_succeeded_job_serves_its_summary_and_hdf5_file(client, tmp_path):
    job = _submit(client, merge(BASE_CASE, {"name": "my rod/2"}))
    store = JobStore(Settings(results_dir=tmp_path))
    summary = simulate(BASE_CASE).summary
    store.write_summary(job["id"], json.dumps(summary))
    store.result_path(job["id"]).write_bytes(b"\x89HDF\r\n\x1a\n fake")
    assert store.start(job["id"], "w1@x") and store.finish(job["id"], SUCCEEDED, progress=1.0)
    assert client.get(f"/v1/jobs/{job['id']}/summary").json() == summary
    download = client.get(f"/v1/jobs/{job['id']}/result.h5")
    assert download.status_code == 200
    assert download.headers["content-type"] == "application/x-hdf5"
    assert f'filename="my_rod_2-{job["id"]}.h5"' in download.headers["content-disposition"]
    assert download.content == b"\x89HDF\r\n\x1a\n fake"


def test_delete_cancels_a_queued_job_then_removes_it_once_finished(client, tmp_path):
    job = _submit(client)
    answer = client.delete(f"/v1/jobs/{job['id']}")
    assert answer.status_code == 202
    assert answer.json()["status"] == "cancelled" and answer.json()["finished"] is not None
    assert client.get(f"/v1/jobs/{job['id']}").json()["status"] == "cancelled"
    store = JobStore(Settings(results_dir=tmp_path))
    assert store.cancel_requested(job["id"]) and not store.start(job["id"], "w1@x"), (
        "a worker taking it later must skip it"
    )
    refused = client.post(f"/v1/jobs/{job['id']}/cancel")
    assert refused.status_code == 409 and "cancelled" in refused.json()["detail"]
    assert (tmp_path / "jobs" / job["id"] / "case.json").is_file(), "a cancel removes nothing"
    again = client.delete(f"/v1/jobs/{job['id']}")
    assert again.status_code == 204 and again.content == b""
    assert client.get(f"/v1/jobs/{job['id']}").status_code == 404
    assert not (tmp_path / "jobs" / job["id"]).exists(), "its files go with it"
    assert client.delete(f"/v1/jobs/{job['id']}").status_code == 404
    assert client.get("/v1/jobs").json()["total"] == 0


def test_delete_of_a_running_job_asks_the_worker_to_stop(client, tmp_path):
    job = _submit(client)
    store = JobStore(Settings(results_dir=tmp_path))
    assert store.start(job["id"], "w1@x")
    answer = client.post(f"/v1/jobs/{job['id']}/cancel")
    assert answer.status_code == 202 and answer.json()["status"] == "running"
    assert answer.json()["cancel_requested"] and store.cancel_requested(job["id"])
    assert not store.finish(job["id"], SUCCEEDED), "a finish after the cancel does not win"
    assert store.finish(job["id"], "cancelled") and not store.finish(job["id"], FAILED, error="late")
    assert client.get(f"/v1/jobs/{job['id']}").json()["status"] == "cancelled", "a finished record never changes"


@pytest.mark.parametrize("job_id", ["AAAAAAAAAAAAAAAAAAAAAA", "short", "A" * 23, "a.b"])
@pytest.mark.parametrize("method, suffix", [("GET", ""), ("GET", "/summary"), ("GET", "/result.h5"), ("DELETE", "")])
def test_an_unknown_or_malformed_id_is_404(client, job_id, method, suffix):
    answer = client.request(method, f"/v1/jobs/{job_id}{suffix}")
    assert answer.status_code == 404
    assert job_id in answer.json()["detail"]


def test_the_job_list_is_paginated_newest_first(client):
    ids = [_submit(client)["id"] for _ in range(5)]
    page = client.get("/v1/jobs", params={"offset": 1, "limit": 2}).json()
    assert page["total"] == 5 and page["offset"] == 1 and page["limit"] == 2
    assert [j["id"] for j in page["jobs"]] == ids[::-1][1:3]
    assert [j["id"] for j in client.get("/v1/jobs").json()["jobs"]] == ids[::-1]


@pytest.mark.parametrize(
    "params, field", [({"limit": 0}, "query.limit"), ({"limit": 501}, "query.limit"), ({"offset": -1}, "query.offset")]
)
def test_the_job_list_refuses_a_bad_page(client, params, field):
    answer = client.get("/v1/jobs", params=params)
    assert answer.status_code == 422
    assert [e["field"] for e in answer.json()["detail"]] == [field]


def test_presets_are_listed_and_served_as_case_json(client):
    listed = client.get("/v1/presets").json()
    assert [p["name"] for p in listed] == preset_names() and "fig3" in preset_names()
    assert all(p["description"] for p in listed)
    assert client.get("/v1/presets/fig3").json() == preset_json("fig3")
    unknown = client.get("/v1/presets/nope")
    assert unknown.status_code == 404 and "fig3" in unknown.json()["detail"]


def test_openapi_offers_every_preset_as_an_example_case(client):
    post = client.get("/openapi.json").json()["paths"]["/v1/jobs"]["post"]
    examples = post["requestBody"]["content"]["application/json"]["examples"]
    assert list(examples) == preset_names()
    assert examples["fig9"]["value"] == preset_json("fig9")
    assert post["responses"]["422"]["content"]["application/json"]["schema"]["$ref"].endswith("/FieldErrors")
    assert client.get("/docs").status_code == 200


def test_an_empty_presets_folder_leaves_the_api_working(tmp_path, monkeypatch):
    empty = tmp_path / "presets"
    empty.mkdir()
    monkeypatch.setenv(PRESETS_ENV, str(empty))
    client = _client(tmp_path / "results")
    assert client.get("/v1/presets").json() == []
    post = client.get("/openapi.json").json()["paths"]["/v1/jobs"]["post"]
    assert "examples" not in post["requestBody"]["content"]["application/json"]
    assert client.post("/v1/jobs", json=BASE_CASE).status_code == 202


def test_healthz(client):
    answer = client.get("/healthz")
    assert answer.status_code == 200 and answer.json() == {"status": "ok"}


def test_readyz_needs_a_recent_worker_heartbeat(client, tmp_path):
    (tmp_path / "broker" / "queue").mkdir(parents=True)  # the embedded broker, as a worker makes it
    answer = client.get("/readyz")
    assert answer.status_code == 503
    assert "no worker" in answer.json()["reason"] and answer.json()["workers"] == []
    registry = WorkerRegistry(tmp_path)
    stale = registry.folder / "old@host.json"
    stale.write_text(json.dumps({"name": "old@host", "time": time.time() - 60}))
    assert client.get("/readyz").status_code == 503, "a heartbeat a minute old is a lost worker"
    registry.beat("w1@host")
    ready = client.get("/readyz")
    assert ready.status_code == 200
    assert ready.json()["status"] == "ready" and ready.json()["workers"] == ["w1@host"]


def test_readyz_needs_the_embedded_broker_folder(client, tmp_path):
    WorkerRegistry(tmp_path).beat("w1@host")
    answer = client.get("/readyz")
    assert answer.status_code == 503 and "broker" in answer.json()["reason"]


def test_an_unreachable_broker_is_503_and_the_job_is_marked_failed(tmp_path, caplog):
    caplog.set_level("DEBUG")
    client = _client(tmp_path, broker_url="redis://:secret@127.0.0.1:1/0")  # nothing listens on port 1
    answer = client.post("/v1/jobs", json=BASE_CASE)
    assert "secret" not in caplog.text, "the broker's password is in a log"
    assert answer.status_code == 503
    assert answer.headers["retry-after"].isdigit()
    assert "secret" not in answer.text and "nothing was queued" in answer.json()["detail"]
    [job] = client.get("/v1/jobs").json()["jobs"]
    assert job["status"] == "failed" and "could not be queued" in job["error"]
    ready = client.get("/readyz")
    assert ready.status_code == 503 and "unreachable" in ready.json()["reason"]


SWEEP = {
    "case": preset_json("fig5"),
    "parameters": {"striker.velocity": [3.0, 5.0, 7.0], "contact.stiffness": [4e11, 8e11]},
}


def test_a_sweep_queues_one_job_a_variant_and_shows_its_table(client, tmp_path):
    answer = client.post("/v1/sweeps", json=SWEEP)
    assert answer.status_code == 202, answer.text
    sweep = answer.json()
    assert answer.headers["location"] == f"/v1/sweeps/{sweep['id']}"
    assert sweep["total"] == 6 and sweep["counts"] == {"queued": 6} and not sweep["finished"]
    assert [r["values"] for r in sweep["rows"]][:2] == [
        {"striker.velocity": 3.0, "contact.stiffness": 4e11},
        {"striker.velocity": 3.0, "contact.stiffness": 8e11},
    ]
    jobs = JobStore(Settings(results_dir=tmp_path))
    assert jobs.case(sweep["rows"][5]["job"])["striker"]["velocity"] == 7.0
    assert len(list((tmp_path / "broker" / "queue").iterdir())) == 6, "one message a variant"
    # A variant that succeeded fills its row from its summary.
    first = sweep["rows"][0]["job"]
    jobs.write_summary(
        first,
        json.dumps(
            {
                "co_impact_time": 2e-4,
                "peak_contact_force": {"value": 4e5},
                "max_compressive_stress": {"value": 5e7},
                "max_tensile_stress": {"value": 1e7},
                "striker_rebound_velocity": -0.4,
                "energy": {"to_medium": 1.7, "transfer_efficiency": 0.2},
                "contacts_total": 5,
                "error_estimate": {"peak_contact_force": 3e-3, "worst": 4e-3},
                "warnings": [],
            }
        ),
    )
    assert jobs.start(first, "w1@x") and jobs.finish(first, SUCCEEDED, progress=1.0)
    row = client.get(f"/v1/sweeps/{sweep['id']}").json()["rows"][0]
    assert row["status"] == "succeeded" and row["peak_contact_force"] == 4e5 and row["contacts"] == 5
    assert row["estimated_error"] == 4e-3 and row["transfer_efficiency"] == 0.2


def test_openapi_offers_sweeps_of_the_new_fields_that_are_accepted(client):
    post = client.get("/openapi.json").json()["paths"]["/v1/sweeps"]["post"]
    examples = post["requestBody"]["content"]["application/json"]["examples"]
    swept = {path for example in examples.values() for path in example["value"]["parameters"]}
    assert {"striker.length", "medium.unloading_stiffness", "medium.quake", "blows.count"} <= swept
    for name, example in examples.items():
        answer = client.post("/v1/sweeps", json=example["value"])
        assert answer.status_code == 202, (name, answer.text)
        assert "permanent_penetration" in answer.json()["columns"]


def test_a_sweep_with_a_bad_variant_is_refused_naming_the_parameter_and_queues_nothing(client, tmp_path):
    bad = merge(SWEEP, {"parameters": {"tool.area": [0.01, -1.0]}})
    answer = client.post("/v1/sweeps", json=bad)
    assert answer.status_code == 422
    assert answer.json()["detail"] == [{"field": "parameters['tool.area'][1]", "message": "tool.area: must be > 0.0"}]
    assert client.get("/v1/jobs").json()["total"] == 0


@pytest.mark.parametrize(
    "body, field, message",
    [
        (
            {"case": merge(BASE_CASE, {"striker": {"mass": -1}}), "parameters": {"striker.velocity": [1.0]}},
            "case.striker.mass",
            "must be > 0",
        ),
        ({"case": BASE_CASE}, "parameters", "is required"),
        ({"case": BASE_CASE, "parameters": {}}, "parameters", "at least 1"),
    ],
)
def test_a_malformed_sweep_names_the_field(client, body, field, message):
    answer = client.post("/v1/sweeps", json=body)
    assert answer.status_code == 422
    [e] = answer.json()["detail"]
    assert e["field"] == field and message in e["message"], e


def test_a_sweep_over_the_variant_limit_is_refused_naming_it(tmp_path):
    client = _client(tmp_path, max_sweep_variants=4)
    answer = client.post("/v1/sweeps", json=SWEEP)
    assert answer.status_code == 422
    [e] = answer.json()["detail"]
    assert e["field"] == "parameters" and "6 variants (3 × 2) exceed the limit of 4" in e["message"]


def test_cancelling_a_sweep_cancels_its_queued_variants(client):
    sweep = client.post("/v1/sweeps", json=SWEEP).json()
    answer = client.delete(f"/v1/sweeps/{sweep['id']}")
    assert answer.status_code == 202
    assert answer.json()["counts"] == {"cancelled": 6} and answer.json()["finished"]
    assert client.get("/v1/sweeps/not-a-sweep-id-at-all00").status_code == 404


def test_an_unreachable_broker_fails_every_variant_with_503(tmp_path):
    client = _client(tmp_path, broker_url="redis://127.0.0.1:1/0")
    answer = client.post("/v1/sweeps", json=SWEEP)
    assert answer.status_code == 503 and answer.headers["retry-after"].isdigit()
    jobs = client.get("/v1/jobs").json()["jobs"]
    assert len(jobs) == 6 and all(j["status"] == "failed" for j in jobs)


def test_an_oversized_body_is_refused_with_413_naming_the_limit(tmp_path):
    client = _client(tmp_path, max_body_bytes=4096)
    big = merge(BASE_CASE, {"description": "x" * 5000})
    answer = client.post("/v1/jobs", json=big)
    assert answer.status_code == 413
    assert answer.json()["detail"] == [
        {"field": "body", "message": "is larger than the limit of 4096 bytes (PERCUSSIM_MAX_BODY_BYTES)"}
    ]
    # Sent in chunks without a Content-Length, the bytes are counted as they come.
    chunks = (json.dumps(big)[k : k + 1000].encode() for k in range(0, len(json.dumps(big)), 1000))
    answer = client.post("/v1/jobs", content=chunks, headers={"content-type": "application/json"})
    assert answer.status_code == 413
    assert client.get("/v1/jobs").json()["total"] == 0
    assert client.post("/v1/jobs", json=BASE_CASE).status_code == 202  # under the limit: as before


def test_a_dead_workers_jobs_are_queued_again_until_it_has_died_under_one_too_often(tmp_path):
    """What `percussim serve` does when one of its embedded workers dies: the filesystem broker
    lost the messages of the jobs it was running."""
    settings, jobs = Settings(results_dir=tmp_path), JobStore(Settings(results_dir=tmp_path))

    def running(worker: str, attempts: int) -> str:
        job_id = jobs.create(BASE_CASE)["id"]
        for _ in range(attempts):  # started again after each death, its beat lapsed
            jobs.release(job_id, worker)
            assert jobs.start(job_id, worker)
        jobs.set_progress(job_id, 0.4)
        return job_id

    lost, doomed, elsewhere = running("w1@x", 1), running("w1@x", MAX_ATTEMPTS), running("w2@x", 1)
    assert queue_again(settings, "w1@x", "exit status -9") == [lost]
    assert jobs.get(lost)["status"] == "queued" and jobs.get(lost)["progress"] == 0.0
    failed = jobs.get(doomed)
    assert (
        failed["status"] == FAILED
        and f"died {MAX_ATTEMPTS} times" in failed["error"]
        and "the last time: exit status -9" in failed["error"]
    )
    assert jobs.get(elsewhere)["status"] == "running"
    assert len(list(queue_folder(settings).iterdir())) == 1  # one message, for the lost job


def test_an_embedded_service_starting_again_gives_every_queued_job_one_message(tmp_path):
    """What `percussim serve` does before its embedded workers start: the queue made again from
    the records, whatever messages the folder held."""
    settings, jobs = Settings(results_dir=tmp_path), JobStore(Settings(results_dir=tmp_path))
    queue = JobQueue(settings)
    published = jobs.create(BASE_CASE)["id"]
    queue.enqueue(published)
    lost = jobs.create(BASE_CASE)["id"]  # recorded, its message never written (or removed)
    cut_off = jobs.create(BASE_CASE)["id"]
    jobs.start(cut_off, "w1@x")
    elsewhere = jobs.create(BASE_CASE)["id"]
    jobs.start(elsewhere, "w2@x")
    done = jobs.create(BASE_CASE)["id"]
    queue.enqueue(done)
    jobs.start(done, "w2@x")
    jobs.finish(done, SUCCEEDED)

    assert restore_queue(settings, ["w1@x"]) == [published, lost, cut_off]  # oldest first
    with queue.app.connection_for_read() as connection:
        messages = connection.SimpleQueue("celery", no_ack=True)
        delivered = [messages.get(timeout=1).payload[0][0] for _ in range(3)]
        with pytest.raises(messages.Empty):
            messages.get(timeout=0.2)
    assert sorted(delivered) == sorted([published, lost, cut_off])
    assert jobs.get(cut_off)["status"] == "queued" and jobs.get(elsewhere)["status"] == "running"


def test_a_dead_workers_job_that_cannot_be_queued_again_ends_failed_saying_why(tmp_path):
    settings = Settings(results_dir=tmp_path, broker_url="redis://127.0.0.1:1/0")  # nothing listens
    jobs = JobStore(Settings(results_dir=tmp_path))
    job_id = jobs.create(BASE_CASE)["id"]
    jobs.start(job_id, "w1@x")
    assert queue_again(settings, "w1@x", "exit status -9") == []
    record = jobs.get(job_id)
    assert record["status"] == FAILED
    assert record["error"].startswith("its worker died and the job could not be queued again: ")


def test_openapi_documents_the_summary_with_units(client):
    spec = client.get("/openapi.json").json()
    answer = spec["paths"]["/v1/jobs/{job_id}/summary"]["get"]["responses"]["200"]
    assert answer["content"]["application/json"]["schema"]["$ref"].endswith("/Summary")
    schemas = spec["components"]["schemas"]
    assert schemas["PeakForce"]["properties"]["value"]["description"] == "N"
    assert schemas["Energy"]["properties"]["to_medium"]["description"].endswith(", J")
    assert set(schemas["Summary"]["required"]) >= {"co_impact_time", "energy", "error_estimate", "warnings"}
