"""POST /v1/cases/check: for any body, the problems POST /v1/jobs would answer in its 422, and no
job made."""

from __future__ import annotations

import json

import pytest
from conftest import BASE_CASE, merge
from fastapi.testclient import TestClient

from percussim.common.settings import Settings
from percussim.service.app import create_app

# Only what a test sets: nothing from the caller's shell.
pytestmark = pytest.mark.usefixtures("clean_environment")


@pytest.fixture
def client(tmp_path) -> TestClient:
    # 100 cells and 1205 steps in BASE_CASE: over these cells, under these steps.
    return TestClient(create_app(Settings(results_dir=tmp_path, max_cells=80, max_steps=5000)))


def _jobs(client: TestClient) -> int:
    return client.get("/v1/jobs").json()["total"]


BAD = {
    "a string for a number": merge(BASE_CASE, {"striker": {"mass": "2"}}),
    "a negative mass": merge(BASE_CASE, {"striker": {"mass": -1.0}}),
    "an exponent over 0.5": merge(BASE_CASE, {"contact": {"exponent": 0.9}}),
    "an unknown field": merge(BASE_CASE, {"colour": "red"}),
    "a profile whose x does not increase": merge(
        BASE_CASE, {"tool": {"area": None, "profile": {"x": [0.0, 0.6, 0.5], "area": [0.01, 0.01, 0.01]}}}
    ),
    "more cells than the limit": BASE_CASE,
    "more steps than the limit": merge(BASE_CASE, {"numerics": {"duration": 1e-2, "cells": 50}}),
    "no striker": merge(BASE_CASE, {"striker": None}),
    "several fields at once": merge(
        BASE_CASE, {"striker": {"mass": 0}, "contact": {"exponent": -1}, "numerics": {"cells": 10.5}}
    ),
    "a Courant number over 1": merge(BASE_CASE, {"numerics": {"scheme": "explicit", "time_step": 1e-5, "cells": 50}}),
    "a list": [1, 2],
    "a number": 3,
    "null": None,
}


@pytest.mark.parametrize("body", BAD.values(), ids=BAD.keys())
def test_the_check_names_what_submitting_would_refuse_and_makes_no_job(client, body):
    checked = client.post("/v1/cases/check", json=body)
    submitted = client.post("/v1/jobs", json=body)
    assert submitted.status_code == 422, submitted.text
    assert checked.status_code == 200
    assert checked.json() == {"valid": False, "problems": submitted.json()["detail"]}
    assert _jobs(client) == 0


def test_the_problems_are_the_fields_and_the_limits_in_the_services_words(client):
    """Not only the same as the submission's: what an engineer reads."""
    problems = client.post("/v1/cases/check", json=BAD["several fields at once"]).json()["problems"]
    assert problems == [
        {"field": "striker.mass", "message": "must be > 0.0"},
        {"field": "contact.exponent", "message": "must be ≥ 0.0"},
        {"field": "numerics.cells", "message": "must be a whole number"},
    ]
    [over] = client.post("/v1/cases/check", json=BASE_CASE).json()["problems"]
    assert over["field"] == "numerics.cells" and "100 cells exceed the limit of 80" in over["message"]
    [profile] = client.post("/v1/cases/check", json=BAD["a profile whose x does not increase"]).json()["problems"]
    assert profile["field"].startswith("tool.profile.x") and "strictly increasing" in profile["message"]


def test_a_valid_case_is_valid_and_makes_no_job(client):
    case = merge(BASE_CASE, {"numerics": {"cells": 50}})
    answer = client.post("/v1/cases/check", json=case)
    assert answer.status_code == 200
    assert answer.json() == {"valid": True, "problems": []}
    assert _jobs(client) == 0
    assert client.post("/v1/jobs", json=case).status_code == 202  # as the check said


@pytest.mark.parametrize(
    "content, headers",
    [
        ("", {"content-type": "application/json"}),
        (json.dumps(BASE_CASE), {"content-type": "text/plain"}),
    ],
)
def test_an_empty_body_or_one_not_sent_as_json_is_a_problem_of_the_body(client, content, headers):
    checked = client.post("/v1/cases/check", content=content, headers=headers)
    submitted = client.post("/v1/jobs", content=content, headers=headers)
    assert checked.status_code == 200 and submitted.status_code == 422
    assert checked.json()["problems"] == submitted.json()["detail"]
    assert checked.json()["problems"][0]["field"] == "body"


def test_a_body_that_is_not_json_is_refused_as_submitting_refuses_it(client):
    checked = client.post("/v1/cases/check", content="{not json", headers={"content-type": "application/json"})
    submitted = client.post("/v1/jobs", content="{not json", headers={"content-type": "application/json"})
    assert checked.status_code == submitted.status_code == 422
    assert checked.json() == submitted.json()
    assert checked.json()["detail"][0]["message"].startswith("is not valid JSON")


def test_the_check_needs_a_key_when_the_service_has_keys(tmp_path):
    client = TestClient(create_app(Settings(results_dir=tmp_path, api_keys="alice-key")))
    assert client.post("/v1/cases/check", json=BASE_CASE).status_code == 401
    answer = client.post("/v1/cases/check", json=BASE_CASE, headers={"X-API-Key": "alice-key"})
    assert answer.status_code == 200 and answer.json()["valid"] is True
