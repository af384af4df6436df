"""Bad input, generated: schemathesis against our own OpenAPI (valid and invalid requests for every
operation) and hypothesis against the case model. Never a 5xx; every 422 names its field.

Counts seen are printed (`pytest -s`).
"""

from __future__ import annotations

import json
import os
import tempfile
from collections import Counter

import pytest
import schemathesis
from fastapi.testclient import TestClient
from hypothesis import HealthCheck, given, settings, strategies as st

from conftest import BASE_CASE
from service.app import create_app
from worker.settings import Settings

os.environ.pop("PERCUSSIM_BROKER_URL", None)  # the embedded broker under a temporary folder
APP = create_app(Settings(results_dir=tempfile.mkdtemp(prefix="percussim-fuzz-")))
SCHEMA = schemathesis.openapi.from_asgi("/openapi.json", APP)
SCHEMA.config.generation.update(modes=list(schemathesis.GenerationMode), max_examples=150)
STATUSES: Counter = Counter()


def check_answer(response_status: int, body: bytes, unavailable_allowed: bool = False) -> None:
    STATUSES[response_status] += 1
    assert response_status < 500 or (unavailable_allowed and response_status == 503), body[:500]
    if response_status == 422:
        detail = json.loads(body)["detail"]
        assert detail and all(e["field"] and e["message"] for e in detail), detail


@SCHEMA.parametrize()
@settings(suppress_health_check=list(HealthCheck), deadline=None)
def test_generated_requests_never_get_a_5xx_and_every_422_names_its_field(case):
    response = case.call()
    # Readiness answers 503 by design here: no worker runs in this test.
    check_answer(response.status_code, response.content, unavailable_allowed=case.path == "/readyz")


CLIENT = TestClient(APP)
FINITE = st.floats(allow_nan=False, allow_infinity=False)
ANY_JSON = st.recursive(
    st.none() | st.booleans() | FINITE | st.integers() | st.text(max_size=20),
    lambda children: st.lists(children, max_size=4) | st.dictionaries(st.text(max_size=10), children, max_size=4),
    max_leaves=20)
PATHS = [("striker", "mass"), ("striker", "velocity"), ("tool", "length"), ("tool", "area"),
         ("contact", "exponent"), ("contact", "stiffness"), ("numerics", "duration"),
         ("numerics", "time_step"), ("numerics", "cells"), ("outputs", "probes"), ("tool", "profile")]
EXTREMES = st.sampled_from([0, -1, 1e-300, 1e300, -1e300, 2**63, -(2**63), 10**400, "NaN", "Infinity",
                            "1", True, [], {}, None, [1.0] * 10_000, "x" * 10_000])


def _post(raw: bytes) -> None:
    response = CLIENT.post("/v1/jobs", content=raw, headers={"content-type": "application/json"})
    check_answer(response.status_code, response.content)


@given(path=st.sampled_from(PATHS), value=EXTREMES | ANY_JSON)
@settings(max_examples=1500, deadline=None, suppress_health_check=list(HealthCheck))
def test_a_case_with_any_field_replaced_by_anything_is_answered_in_words(path, value):
    case = json.loads(json.dumps(BASE_CASE))
    case[path[0]] = dict(case.get(path[0]) or {}, **{path[1]: value})
    _post(json.dumps(case).encode())


@pytest.mark.parametrize("raw", [
    b'{"striker": {"mass": NaN, "velocity": 5}}', b'{"striker": {"mass": Infinity}}', b"-Infinity",
    b"[" * 10_000 + b"]" * 10_000, b'{"a":' * 5_000 + b"1" + b"}" * 5_000, b"", b"null", b"\xff\xfe",
    json.dumps({**BASE_CASE, "outputs": {"probes": [0.5] * 200_000}}).encode(),
])
def test_non_finite_numbers_deep_nesting_and_huge_arrays_get_4xx(raw):
    response = CLIENT.post("/v1/jobs", content=raw, headers={"content-type": "application/json"})
    check_answer(response.status_code, response.content)
    assert response.status_code in (413, 422), response.text[:300]


def test_print_the_counts(capsys):
    """Runs last in this module: what the generated requests got, printed past pytest's capture."""
    total = sum(STATUSES.values())
    with capsys.disabled():
        print(f"\nfuzzing: {total} requests, statuses {dict(sorted(STATUSES.items()))} "
              "(503: /readyz with no worker running)")
    assert total >= 1000  # each answer was checked as it came
