"""Shared case builders, jobs and waits for the tests."""

from __future__ import annotations

import os
import shutil

import pytest

from percussim.solver.presets import preset_json
from percussim.testing import merge
from percussim.testing.live_stack import wait_for
from percussim.testing.reference import LinearImpact

pytest_plugins = ["browser"]  # the job page's fixtures (stack, browser, open_page, page)

STEEL = {"youngs_modulus": 2.1e11, "density": 7800.0}


BASE_CASE = {
    "name": "test",
    "striker": {"mass": 20.0, "velocity": 5.0},
    "tool": {"length": 1.2, "area": 0.014209, **STEEL},
    "contact": {"stiffness": 1e11, "exponent": 0.5, "tension_stiffness": 3e4, "damping": 1.2e3},
    "medium": {"stiffness": 2e8, "damping": 1e3},
    "numerics": {"duration": 1e-3, "time_step": 8.3e-7, "cells": 100, "gamma": 0.5},
}

# About 3 s of work on a live stack's worker: long enough to kill its worker, or cut it off, in
# the middle.
SECONDS_OF_WORK = merge(
    preset_json("fig3"),
    {
        "numerics": {"duration": 0.5, "cells": 600, "time_step": 8.3e-7},
        "outputs": {"history_stride": 100, "probes": []},
    },
)
# Ten times as long: far longer than the 1-s grace the stop tests give, so that a job stopped
# mid-way has seconds left, not one that may end within the grace's last instant.
LONG_WORK = merge(SECONDS_OF_WORK, {"numerics": {"duration": 5.0}})


def running_again(client, job_id: str, timeout: float = 60) -> dict:
    """The record of a job delivered a second time, once it runs (attempt 2)."""

    def again():
        record = client.get(f"/v1/jobs/{job_id}").json()
        return record if record["status"] == "running" and record["attempts"] == 2 else None

    return wait_for(again, timeout, f"job {job_id} running again")


# A contact stiff in tension that the σ-scheme's end masses ring against on 60 cells: it passes
# every check made up front and is refused as it runs, once it has chattered.
CHATTERS = merge(
    BASE_CASE, {"numerics": {"scheme": "sigma", "cells": 60, "time_step": None}, "contact": {"tension_stiffness": 1e12}}
)


@pytest.fixture
def clean_environment(monkeypatch):
    """Only what a test sets: no broker URL, limits, keys or presets folder from the caller's shell."""
    for name in list(os.environ):
        if name.startswith("PERCUSSIM_"):
            monkeypatch.delenv(name)


@pytest.fixture
def api_store(tmp_path, clean_environment):
    """The API in-process on a fresh results folder, and that folder's job store."""
    from fastapi.testclient import TestClient

    from percussim.common.settings import Settings
    from percussim.common.store import JobStore
    from percussim.service.app import create_app

    settings = Settings(results_dir=tmp_path)
    return TestClient(create_app(settings)), JobStore(settings)


def succeeded_job(client, jobs, result: str, case: dict | None = None) -> str:
    """A job submitted through the API, then given the result file `result` as a worker would
    have written it."""
    import h5py

    from percussim.common.store import SUCCEEDED

    answer = client.post("/v1/jobs", json=case or BASE_CASE)
    assert answer.status_code == 202, answer.text
    job_id = answer.json()["id"]
    shutil.copy(result, jobs.result_path(job_id))
    with h5py.File(result) as f:
        jobs.write_summary(job_id, f["summary"][()].decode())
    jobs.start(job_id, "w1@x")
    jobs.finish(job_id, SUCCEEDED, progress=1.0)
    return job_id


def report(record_property, text: str) -> None:
    """Keep what a test saw for the suite's summary (`pytest_terminal_summary`): the output carries
    the counts, whichever process ran the test."""
    record_property(REPORTED, text.strip())


REPORTED = "percussim-report"
_reported: dict[tuple[str, str], None] = {}  # (test, text), in the order they came


def pytest_runtest_logreport(report):
    # a test's properties travel with each of its reports (call, teardown), from pytest-xdist's
    # workers too
    for name, text in report.user_properties:
        if name == REPORTED:
            _reported[report.nodeid, text] = None


def pytest_terminal_summary(terminalreporter):
    if _reported:
        terminalreporter.section("what the tests saw")
        for nodeid, text in _reported:
            terminalreporter.write_line(f"{nodeid}: {text}")


@pytest.fixture
def linear_impact() -> LinearImpact:
    return LinearImpact()


@pytest.fixture(scope="session")
def postgres():
    """One real PostgreSQL server for the session (the system's package); each test that wants a
    database asks it for a new one (`postgres.database()`)."""
    from percussim.testing.live_stack import postgres_server

    with postgres_server() as server:
        yield server


@pytest.fixture(params=["sqlite", "postgresql"])
def records(request, tmp_path):
    """Settings on each database the service runs on: the embedded SQLite file in the results
    folder, and a new database on a real PostgreSQL server."""
    from percussim.common.settings import Settings

    url = request.getfixturevalue("postgres").database() if request.param == "postgresql" else None
    return Settings(results_dir=tmp_path / "results", database_url=url)
