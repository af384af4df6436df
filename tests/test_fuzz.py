"""Bad input, generated, against the live stack (the real API on the embedded default, with a
real worker that runs whatever valid case gets through): schemathesis against our own OpenAPI
(valid and invalid requests for every operation) and hypothesis against the case. Never a 5xx;
every 422 names its field. The counts seen are printed.

Limits are set low, so that the valid cases the worker runs stay small.
"""

from __future__ import annotations

import json
from collections import Counter

import pytest
import schemathesis
from conftest import BASE_CASE, report
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.errors import Unsatisfiable

from percussim.testing.live_stack import Stack

pytestmark = pytest.mark.slow  # a live stack, a browser or the solver's full reports

STATUSES: Counter = Counter()
EXAMPLES = 100  # a generation mode and operation
SMALL = {"PERCUSSIM_MAX_NODE_STEPS": "2e6", "PERCUSSIM_MAX_OUTPUT_VALUES": "1e6", "PERCUSSIM_MAX_SWEEP_VARIANTS": "4"}


@pytest.fixture(scope="module")
def stack(tmp_path_factory):
    s = Stack(tmp_path_factory.mktemp("fuzz"), None, env=SMALL)
    yield s
    s.stop()


def check_answer(status: int, body: bytes, unavailable_allowed: bool = False) -> None:
    STATUSES[status] += 1
    assert status < 500 or (unavailable_allowed and status == 503), body[:500]
    if status == 422:
        detail = json.loads(body)["detail"]
        assert detail and all(e["field"] and e["message"] for e in detail), detail


@pytest.mark.parametrize("mode", list(schemathesis.GenerationMode))
def test_generated_requests_never_get_a_5xx_and_every_422_names_its_field(stack, mode):
    """Every operation of our OpenAPI, with requests that fit it (positive) and that break it."""
    schema = schemathesis.openapi.from_url(f"{stack.url}/openapi.json")
    fuzzed, unbreakable = [], []
    for operation in (result.ok() for result in schema.get_all_operations()):

        @given(case=operation.as_strategy(generation_mode=mode))
        @settings(max_examples=EXAMPLES, deadline=None, suppress_health_check=list(HealthCheck))
        def call(case):
            response = case.call()
            # /readyz answers 503 while the worker is busy between heartbeats: that is its job.
            check_answer(response.status_code, response.content, unavailable_allowed=operation.path == "/readyz")

        try:
            call()
            fuzzed.append(operation.label)
        except Unsatisfiable:  # no input a schema can call invalid (no body, any string as id)
            assert mode == schemathesis.GenerationMode.NEGATIVE
            unbreakable.append(operation.label)
    print(f"{mode.value}: {len(fuzzed)} operations fuzzed; without inputs to break: {unbreakable}")
    assert {"POST /v1/jobs", "POST /v1/sweeps", "GET /v1/jobs"} <= set(fuzzed)


FINITE = st.floats(allow_nan=False, allow_infinity=False)
ANY_JSON = st.recursive(
    st.none() | st.booleans() | FINITE | st.integers() | st.text(max_size=20),
    lambda children: st.lists(children, max_size=4) | st.dictionaries(st.text(max_size=10), children, max_size=4),
    max_leaves=20,
)
PATHS = [
    ("striker", "mass"),
    ("striker", "velocity"),
    ("tool", "length"),
    ("tool", "area"),
    ("contact", "exponent"),
    ("contact", "stiffness"),
    ("numerics", "duration"),
    ("numerics", "time_step"),
    ("numerics", "cells"),
    ("outputs", "probes"),
    ("tool", "profile"),
]
EXTREMES = st.sampled_from(
    [
        0,
        -1,
        1e-300,
        1e300,
        -1e300,
        2**63,
        -(2**63),
        10**400,
        "NaN",
        "Infinity",
        "1",
        True,
        [],
        {},
        None,
        [1.0] * 10_000,
        "x" * 10_000,
    ]
)


def test_a_case_with_any_field_replaced_by_anything_is_answered_in_words(stack):
    @given(path=st.sampled_from(PATHS), value=EXTREMES | ANY_JSON)
    @settings(max_examples=1500, deadline=None, suppress_health_check=list(HealthCheck))
    def replaced(path, value):
        case = json.loads(json.dumps(BASE_CASE))
        case[path[0]] = dict(case.get(path[0]) or {}, **{path[1]: value})
        response = stack.client.post(
            "/v1/jobs", content=json.dumps(case).encode(), headers={"content-type": "application/json"}
        )
        check_answer(response.status_code, response.content)

    replaced()


@pytest.mark.parametrize(
    "raw",
    [
        b'{"striker": {"mass": NaN, "velocity": 5}}',
        b'{"striker": {"mass": Infinity}}',
        b"-Infinity",
        b"[" * 10_000 + b"]" * 10_000,
        b'{"a":' * 5_000 + b"1" + b"}" * 5_000,
        b"",
        b"null",
        b"\xff\xfe",
        json.dumps({**BASE_CASE, "outputs": {"probes": [0.5] * 200_000}}).encode(),
    ],
)
def test_non_finite_numbers_deep_nesting_and_huge_arrays_get_4xx(stack, raw):
    response = stack.client.post("/v1/jobs", content=raw, headers={"content-type": "application/json"})
    check_answer(response.status_code, response.content)
    assert response.status_code in (413, 422), response.text[:300]


def test_print_the_counts(stack, record_property):
    """Runs last in this module: what the generated requests got, kept for the suite's summary;
    and no job the fuzzing queued failed other than for a reason in words."""
    total = sum(STATUSES.values())
    jobs = stack.client.get("/v1/jobs", params={"limit": 500}).json()
    outcomes = Counter(j["status"] for j in jobs["jobs"])
    report(
        record_property,
        f"\nfuzzing the live API: {total} requests, statuses {dict(sorted(STATUSES.items()))}; "
        f"{jobs['total']} jobs accepted, the last {len(jobs['jobs'])} {dict(outcomes)}",
    )
    assert total >= 1000  # each answer was checked as it came
    assert all(j["error"] for j in jobs["jobs"] if j["status"] == "failed")
