"""Security of the API: optional keys that see only their own jobs, no secret stored, no path built
from user input, CORS only where configured."""

from __future__ import annotations

import os

import pytest
from conftest import BASE_CASE, merge
from fastapi.testclient import TestClient

from percussim.common.settings import Settings
from percussim.service.app import create_app
from percussim.solver.presets import preset_json

# Only what a test sets: nothing from the caller's shell.
pytestmark = pytest.mark.usefixtures("clean_environment")

ALICE, BOB = "alice-key-0123456789", "bob-key-9876543210"


@pytest.fixture
def keyed(tmp_path) -> TestClient:
    return TestClient(create_app(Settings(results_dir=tmp_path, api_keys=f"{ALICE}, {BOB}")))


def test_without_a_known_key_every_v1_call_is_401(keyed):
    for method, path in (
        ("post", "/v1/jobs"),
        ("get", "/v1/jobs"),
        ("get", "/v1/presets"),
        ("post", "/v1/sweeps"),
        ("get", "/v1/jobs/AAAAAAAAAAAAAAAAAAAAAA"),
    ):
        for headers in ({}, {"X-API-Key": "guess"}):
            answer = getattr(keyed, method)(path, headers=headers, **({"json": BASE_CASE} if method == "post" else {}))
            assert answer.status_code == 401, (method, path, headers)
            assert "X-API-Key" in answer.json()["detail"] and answer.headers["www-authenticate"]
    # Health and the API's description stay open: probes and clients need them to start.
    assert keyed.get("/healthz").status_code == 200
    assert keyed.get("/openapi.json").status_code == 200


def test_a_key_sees_only_its_own_jobs_and_sweeps(keyed, tmp_path):
    alice, bob = {"X-API-Key": ALICE}, {"X-API-Key": BOB}
    job = keyed.post("/v1/jobs", json=BASE_CASE, headers=alice).json()
    sweep = keyed.post(
        "/v1/sweeps", headers=alice, json={"case": preset_json("fig5"), "parameters": {"striker.velocity": [3.0, 5.0]}}
    ).json()
    assert keyed.get(f"/v1/jobs/{job['id']}", headers=alice).status_code == 200
    for path in (
        f"/v1/jobs/{job['id']}",
        f"/v1/jobs/{job['id']}/summary",
        f"/v1/jobs/{job['id']}/result.h5",
        f"/v1/sweeps/{sweep['id']}",
    ):
        assert keyed.get(path, headers=bob).status_code == 404, path  # as if it did not exist
    assert keyed.delete(f"/v1/jobs/{job['id']}", headers=bob).status_code == 404
    assert keyed.delete(f"/v1/sweeps/{sweep['id']}", headers=bob).status_code == 404
    assert keyed.get("/v1/jobs", headers=bob).json()["total"] == 0
    assert keyed.get("/v1/jobs", headers=alice).json()["total"] == 3  # the job and two variants
    # No file of the results store holds a key.
    for path in tmp_path.rglob("*"):
        if path.is_file():
            text = path.read_bytes()
            assert ALICE.encode() not in text and BOB.encode() not in text, path


@pytest.mark.parametrize("keys", [None, "", " , "])  # unset, or empty as docker-compose passes it
def test_without_keys_configured_the_api_is_open(tmp_path, keys):
    client = TestClient(create_app(Settings(results_dir=tmp_path, api_keys=keys)))
    assert client.post("/v1/jobs", json=BASE_CASE).status_code == 202


@pytest.mark.parametrize(
    "path",
    [
        "/v1/jobs/..%2F..%2F..%2Fetc%2Fpasswd",
        "/v1/jobs/../../etc/passwd",
        "/v1/jobs/%2e%2e/summary",
        "/v1/jobs/..%2Fjobs/result.h5",
        "/v1/presets/..%2F..%2Fpyproject",
        "/v1/presets/%2Fetc%2Fpasswd",
        "/v1/sweeps/..%2F..%2Fjobs",
        "/v1/jobs/" + "A" * 21 + "%00",
    ],
)
def test_no_path_is_built_from_user_input(tmp_path, path):
    client = TestClient(create_app(Settings(results_dir=tmp_path)))
    (tmp_path / "secret.json").write_text('{"secret": 1}')
    answer = client.get(path)
    assert answer.status_code == 404, (path, answer.text)
    assert "secret" not in answer.text and "root:" not in answer.text


def test_a_downloaded_file_name_is_made_from_safe_characters(tmp_path):
    from percussim.service.jobs import _download_name

    assert _download_name({"id": "X", "name": "../../etc/passwd"}) == "etc_passwd-X.h5"
    assert _download_name({"id": "X", "name": 'a"b\r\nc'}) == "a_b_c-X.h5"


def test_cors_answers_only_the_configured_origins(tmp_path):
    preflight = {
        "Origin": "https://design.example",
        "Access-Control-Request-Method": "POST",
        "Access-Control-Request-Headers": "content-type,x-api-key",
    }
    closed = TestClient(create_app(Settings(results_dir=tmp_path)))
    assert "access-control-allow-origin" not in closed.options("/v1/jobs", headers=preflight).headers
    open_ = TestClient(create_app(Settings(results_dir=tmp_path, cors_origins="https://design.example")))
    answer = open_.options("/v1/jobs", headers=preflight)
    assert answer.status_code == 200
    assert answer.headers["access-control-allow-origin"] == "https://design.example"
    other = open_.options("/v1/jobs", headers=preflight | {"Origin": "https://elsewhere.example"})
    assert other.headers.get("access-control-allow-origin") != "https://elsewhere.example"


def test_keys_logs_and_paths_on_the_live_stack(tmp_path):
    """The same through the running server and a real worker: the key's job runs, another key
    cannot see it, no log holds a key, and encoded traversals reach no file."""
    from percussim.testing.live_stack import RedisServer, Stack

    redis = RedisServer(tmp_path / "redis")
    redis.start()
    s = Stack(tmp_path, redis.url, env={"PERCUSSIM_API_KEYS": f"{ALICE},{BOB}", "PERCUSSIM_MAX_CELLS": "150"})
    try:
        alice, bob = {"X-API-Key": ALICE}, {"X-API-Key": BOB}
        assert s.client.post("/v1/jobs", json=preset_json("fig3")).status_code == 401
        job = s.client.post("/v1/jobs", json=preset_json("fig3"), headers=alice).json()
        s.client.headers.update(alice)
        assert s.wait_status(job["id"], ("succeeded", "failed"))["status"] == "succeeded"
        assert s.client.get(f"/v1/jobs/{job['id']}/result.h5", headers=bob).status_code == 404
        assert s.client.get(f"/v1/jobs/{job['id']}/result.h5").status_code == 200
        # A case over a configured limit is refused up front, naming it.
        over = s.client.post("/v1/jobs", json=merge(preset_json("fig3"), {"numerics": {"cells": 200}}))
        assert (
            over.status_code == 422
            and {
                "field": "numerics.cells",
                "message": "200 cells exceed the limit of 150 (PERCUSSIM_MAX_CELLS raises it)",
            }
            in over.json()["detail"]
        )
        for path in (
            "/v1/jobs/..%2F..%2F..%2Fetc%2Fpasswd",
            "/v1/jobs/%2E%2E%2Fapi.log/summary",
            "/v1/presets/..%2F..%2Fpyproject",
        ):
            answer = s.client.get(path)
            assert answer.status_code == 404 and "root:" not in answer.text, path
        logs = "".join(p.log.read_text(errors="replace") for p in s.processes)
        assert "GET /v1/jobs" in logs or "POST /v1/jobs" in logs  # the access log is there to search
        assert ALICE not in logs and BOB not in logs
        print(f"\nlive security: 401 without a key, 404 for another key, {len(logs)} bytes of logs without a key")
    finally:
        s.stop()
        redis.stop()


def test_job_ids_are_unguessable(tmp_path):
    """128 random bits each (secrets.token_urlsafe): distinct, and no two share a long prefix."""
    client = TestClient(create_app(Settings(results_dir=tmp_path)))
    ids = [client.post("/v1/jobs", json=BASE_CASE).json()["id"] for _ in range(200)]
    assert len(set(ids)) == 200
    assert all(len(i) == 22 and i.replace("-", "").replace("_", "").isalnum() for i in ids)
    longest_shared = max(len(os.path.commonprefix([a, b])) for a, b in zip(sorted(ids), sorted(ids)[1:]))
    assert longest_shared <= 4, "ids that share a long prefix are not random"
