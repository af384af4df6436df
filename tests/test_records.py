"""The job and sweep records in a real database, SQLite and PostgreSQL alike: transitions that
only one racer wins, listing and filters on indexes, deletion and retention, the metrics'
counters, and the import of a store that kept its records in folders."""

from __future__ import annotations

import json
import statistics
import threading
import time
from collections import Counter
from datetime import UTC, datetime, timedelta

import pytest
from conftest import BASE_CASE, merge, report
from fastapi.testclient import TestClient
from sqlalchemy import text

from percussim.common.database import _open, database
from percussim.common.metrics import job_observations
from percussim.common.settings import Settings
from percussim.common.store import CANCELLED, FAILED, QUEUED, RUNNING, SUCCEEDED, JobStore, SweepStore, UnknownJob
from percussim.service.app import create_app
from percussim.service.retention import delete_expired
from percussim.solver.simulate import simulate

SUMMARY = json.dumps({"peak_contact_force": {"value": 1.0}})


def running_job(jobs: JobStore, case: dict = BASE_CASE) -> str:
    job_id = jobs.create(case)["id"]
    assert jobs.start(job_id, "w1@x")
    return job_id


def test_a_job_goes_queued_running_finished_and_then_never_changes(records):
    jobs = JobStore(records)
    job_id = jobs.create(BASE_CASE)["id"]
    assert jobs.get(job_id)["status"] == QUEUED and jobs.case(job_id) == BASE_CASE
    assert not jobs.finish(job_id, SUCCEEDED), "a queued job cannot succeed"
    assert jobs.start(job_id, "w1@x") and jobs.set_progress(job_id, 0.5)
    record = jobs.get(job_id)
    assert record["status"] == RUNNING and record["attempts"] == 1 and record["progress"] == 0.5
    assert not jobs.start(job_id, "w2@x"), "delivered again while its worker runs it"
    jobs.release(job_id, "w1@x")  # its worker stopped it and handed it back (or died, and its beat lapsed)
    assert jobs.start(job_id, "w2@x"), "delivered again after its worker stopped"
    assert jobs.get(job_id)["attempts"] == 2 and jobs.get(job_id)["worker"] == "w2@x"
    assert jobs.finish(job_id, SUCCEEDED, progress=1.0, result_bytes=123)
    done = jobs.get(job_id)
    assert done["status"] == SUCCEEDED and done["finished"] >= done["started"] >= done["created"]
    for change in (
        lambda: jobs.start(job_id, "w3@x"),
        lambda: jobs.set_progress(job_id, 0.1),
        lambda: jobs.finish(job_id, FAILED, error="late"),
        lambda: jobs.requeue(job_id, "w2@x"),
        lambda: jobs.request_cancel(job_id),
        lambda: jobs.renew(job_id, "w2@x"),
        lambda: jobs.release(job_id, "w2@x"),
    ):
        assert not change()
    assert jobs.get(job_id) == done, "a finished job's record never changes"


def test_a_cancel_then_a_finish_ends_cancelled_with_nothing_of_the_run_kept(records):
    jobs = JobStore(records)
    job_id = running_job(jobs)
    assert jobs.request_cancel(job_id)["cancel_requested"]
    jobs.write_summary(job_id, SUMMARY)
    jobs.result_path(job_id).write_bytes(b"result")
    assert jobs.complete(job_id, SUCCEEDED, progress=1.0) == CANCELLED
    assert jobs.get(job_id)["status"] == CANCELLED
    assert sorted(p.name for p in jobs.folder(job_id).iterdir()) == ["case.json"]


def test_a_job_is_owned_by_its_key(records):
    alice, bob = JobStore(records, owner="alice"), JobStore(records, owner="bob")
    job_id = alice.create(BASE_CASE)["id"]
    for action in (bob.get, bob.request_cancel):
        with pytest.raises(UnknownJob):
            action(job_id)
    alice.start(job_id, "w1@x")
    alice.finish(job_id, SUCCEEDED)
    assert not bob.delete(job_id) and alice.get(job_id)["status"] == SUCCEEDED
    assert bob.list()[0] == 0 and alice.list()[0] == 1 and JobStore(records).list()[0] == 1


def test_listing_pages_by_creation_time_and_filters(records):
    client = TestClient(create_app(records))
    jobs, sweeps = JobStore(records), SweepStore(JobStore(records))
    made = [jobs.create(merge(BASE_CASE, {"name": f"case {k % 3}"}))["id"] for k in range(25)]
    sweep = sweeps.create("swept", ["striker.velocity"], [({"striker.velocity": v}, BASE_CASE) for v in (3, 5)])
    for job_id in made[:4]:
        jobs.start(job_id, "w1@x")
    jobs.finish(made[0], SUCCEEDED)
    newest_first = [v["job"] for v in reversed(sweep["variants"])] + made[::-1]

    pages, path = [], "/v1/jobs?limit=10"
    while path:
        page = client.get(path).json()
        assert page["total"] == 27
        pages.append([job["id"] for job in page["jobs"]])
        path = page["next"]
    assert [len(p) for p in pages] == [10, 10, 7]
    assert sum(pages, []) == newest_first
    assert [j["id"] for j in client.get("/v1/jobs?offset=12&limit=5").json()["jobs"]] == newest_first[12:17]

    def ids(query: str) -> list[str]:
        answer = client.get(f"/v1/jobs?{query}")
        assert answer.status_code == 200, answer.text
        return [job["id"] for job in answer.json()["jobs"]]

    assert ids("status=succeeded") == [made[0]]
    assert ids("status=running") == made[1:4][::-1]
    assert ids("name=case%201") == [made[k] for k in range(24, -1, -1) if k % 3 == 1]
    assert ids(f"sweep={sweep['id']}") == newest_first[:2]
    assert ids("status=queued&name=case%200&limit=3") == [made[24], made[21], made[18]]
    first = client.get("/v1/jobs?status=queued&limit=3").json()
    assert "status=queued" in first["next"] and ids(first["next"].split("?", 1)[1]) == newest_first[3:6]
    bad = client.get("/v1/jobs?status=done").json()["detail"][0]
    assert bad["field"] == "query.status"
    assert client.get("/v1/jobs?cursor=nonsense").json()["detail"][0]["field"] == "query.cursor"


def test_the_listings_queries_use_an_index():
    """SQLite's plan for each listing: an index, never a scan of the table and a sort."""
    import tempfile
    from pathlib import Path

    settings = Settings(results_dir=Path(tempfile.mkdtemp()))
    with database(settings).connect() as connection:
        for where in ("", "WHERE status = 'queued'", "WHERE name = 'x'", "WHERE owner = 'k'"):
            plan = " ".join(
                row[-1]
                for row in connection.execute(
                    text(f"EXPLAIN QUERY PLAN SELECT * FROM jobs {where} ORDER BY created DESC, id DESC LIMIT 20")
                )
            )
            assert "USING INDEX" in plan and "TEMP B-TREE" not in plan, (where, plan)
        plan = " ".join(
            row[-1] for row in connection.execute(text("EXPLAIN QUERY PLAN SELECT * FROM jobs WHERE sweep = 'x'"))
        )
        assert "USING INDEX ix_jobs_sweep" in plan, plan


def test_delete_removes_a_finished_job_and_a_purged_sweep_with_its_jobs(records):
    client = TestClient(create_app(records))
    jobs = JobStore(records)
    job_id = running_job(jobs)
    answer = client.delete(f"/v1/jobs/{job_id}")
    assert answer.status_code == 202 and answer.json()["cancel_requested"], "running: cancelled, not removed"
    assert jobs.complete(job_id, CANCELLED) == CANCELLED
    assert client.delete(f"/v1/jobs/{job_id}").status_code == 204
    assert client.get(f"/v1/jobs/{job_id}").status_code == 404 and not jobs.folder(job_id).exists()

    sweep = client.post("/v1/sweeps", json={"case": BASE_CASE, "parameters": {"striker.velocity": [3.0, 5.0]}}).json()
    variants = [row["job"] for row in sweep["rows"]]
    refused = client.delete(f"/v1/sweeps/{sweep['id']}?purge=true")
    assert refused.status_code == 409 and "2 variant(s) not finished" in refused.json()["detail"]
    assert client.delete(f"/v1/sweeps/{sweep['id']}").json()["counts"] == {"cancelled": 2}
    alone = client.delete(f"/v1/jobs/{variants[0]}")
    assert alone.status_code == 409 and "purge=true" in alone.json()["detail"]
    assert client.delete(f"/v1/sweeps/{sweep['id']}?purge=true").status_code == 204
    assert client.get(f"/v1/sweeps/{sweep['id']}").status_code == 404
    for job_id in variants:
        assert client.get(f"/v1/jobs/{job_id}").status_code == 404 and not jobs.folder(job_id).exists()
    assert client.get("/v1/jobs").json()["total"] == 0


def test_retention_deletes_what_finished_before_the_ttl_and_keeps_the_rest(records):
    settings = records.model_copy(update={"result_ttl": 0.5})
    jobs = JobStore(settings)
    old, running, queued = running_job(jobs), running_job(jobs), jobs.create(BASE_CASE)["id"]
    jobs.finish(old, SUCCEEDED)
    sweep = SweepStore(jobs).create("s", ["striker.velocity"], [({"striker.velocity": 3.0}, BASE_CASE)])
    variant = sweep["variants"][0]["job"]
    jobs.start(variant, "w1@x")
    jobs.finish(variant, FAILED, error="x")
    assert delete_expired(settings) == (0, 0), "nothing is old enough yet"
    time.sleep(0.6)
    recent = running_job(jobs)
    jobs.finish(recent, SUCCEEDED)
    assert delete_expired(settings) == (1, 1)
    assert {r["id"] for r in jobs.list()[1]} == {running, queued, recent}
    assert not jobs.folder(old).exists() and not jobs.folder(variant).exists()


def test_the_retention_thread_runs_beside_the_api(records):
    settings = records.model_copy(update={"result_ttl": 0.3})
    jobs = JobStore(settings)
    job_id = running_job(jobs)
    jobs.finish(job_id, SUCCEEDED)
    with TestClient(create_app(settings)) as client:  # the lifespan starts the thread
        deadline = time.monotonic() + 10
        while client.get(f"/v1/jobs/{job_id}").status_code == 200 and time.monotonic() < deadline:
            time.sleep(0.05)
        assert client.get(f"/v1/jobs/{job_id}").status_code == 404


def test_metrics_count_jobs_and_add_every_workers_histograms(records):
    jobs = JobStore(records)
    running_job(jobs)
    jobs.create(BASE_CASE)
    for seconds in (0.02, 0.05, 2.0, 5000.0):
        job_id = running_job(jobs)
        jobs.complete(job_id, SUCCEEDED, then=job_observations(seconds, solver_seconds=seconds / 10, node_steps=1e7))
    lost = running_job(jobs)
    jobs.request_cancel(lost)
    assert jobs.complete(lost, SUCCEEDED, then=job_observations(1.0, 0.1, 1e7)) == CANCELLED, "not counted"
    text = TestClient(create_app(records)).get("/metrics").text
    lines = dict(line.rsplit(" ", 1) for line in text.splitlines() if not line.startswith("#"))
    assert float(lines['percussim_jobs{status="running"}']) == 1
    assert float(lines['percussim_jobs{status="queued"}']) == 1
    assert float(lines['percussim_jobs{status="succeeded"}']) == 4
    assert float(lines['percussim_jobs{status="cancelled"}']) == 1
    assert float(lines["percussim_queue_depth"]) == 0, "created in the store, never published"
    assert float(lines['percussim_job_duration_seconds_bucket{le="0.03"}']) == 1
    assert float(lines['percussim_job_duration_seconds_bucket{le="0.1"}']) == 2
    assert float(lines['percussim_job_duration_seconds_bucket{le="1000.0"}']) == 3
    assert float(lines['percussim_job_duration_seconds_bucket{le="+Inf"}']) == 4
    assert float(lines["percussim_job_duration_seconds_sum"]) == pytest.approx(5002.07)
    # 2e-10, 5e-10, 2e-8 and 5e-5 s per node-step
    assert float(lines['percussim_solver_seconds_per_node_step_bucket{le="1e-09"}']) == 2
    assert float(lines['percussim_solver_seconds_per_node_step_bucket{le="2e-08"}']) == 3
    assert float(lines['percussim_solver_seconds_per_node_step_bucket{le="1e-06"}']) == 3
    assert float(lines["percussim_solver_seconds_per_node_step_count"]) == 4
    assert float(lines["percussim_results_disk_free_bytes"]) > 0


@pytest.mark.slow
def test_200_racing_cancels_and_finishes_never_both_win(records, record_property):
    """A worker finishing a job (summary written, then the transition) against a client's DELETE
    at the same moment: what DELETE answered, the final status and the files agree."""
    client = TestClient(create_app(records))
    jobs = JobStore(records)
    outcomes, delete_seconds = Counter(), []
    for k in range(200):
        job_id = running_job(jobs)
        start, answers = threading.Barrier(2), {}
        # The worker's side is faster than an HTTP call, by how much depends on the machine's
        # load: spread its start over the DELETEs' median time so far, so that either
        # side comes first in some of the races.
        window = statistics.median(delete_seconds) if delete_seconds else 0.006

        def finish():
            start.wait()
            time.sleep((k % 20) / 20 * window)
            jobs.write_summary(job_id, SUMMARY)
            answers["worker"] = jobs.complete(job_id, SUCCEEDED, progress=1.0)

        def delete():
            start.wait()
            began = time.perf_counter()
            answers["delete"] = client.delete(f"/v1/jobs/{job_id}").status_code
            delete_seconds.append(time.perf_counter() - began)

        threads = [threading.Thread(target=finish), threading.Thread(target=delete)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        after = client.get(f"/v1/jobs/{job_id}")
        if answers["delete"] == 202:  # the cancel came first: the finish lost
            assert answers["worker"] == CANCELLED and after.json()["status"] == CANCELLED
            assert client.get(f"/v1/jobs/{job_id}/summary").status_code == 409
            assert not (jobs.folder(job_id) / "summary.json").exists()
        else:  # the finish came first; DELETE then removed the finished job
            assert answers == {"worker": SUCCEEDED, "delete": 204}, answers
            assert after.status_code == 404 and not jobs.folder(job_id).exists()
        outcomes[(answers["delete"], answers["worker"])] += 1
    report(
        record_property,
        f"\n{records.database_url and 'PostgreSQL' or 'SQLite'}: 200 cancel/finish races: "
        + ", ".join(f"DELETE {d} with the worker's {w}: {n}" for (d, w), n in sorted(outcomes.items()))
        + f"; DELETE took {1e3 * statistics.median(delete_seconds):.1f} ms (median)",
    )
    assert sum(outcomes.values()) == 200
    assert outcomes[(202, CANCELLED)] >= 10 and outcomes[(204, SUCCEEDED)] >= 10, "both orders were raced"


@pytest.mark.slow
def test_1000_concurrent_progress_writes_stop_at_the_finish(records, record_property):
    """Eight threads write a running job's progress 1000 times in all while it is cancelled and
    its worker ends it: nothing is lost or contradicted, and no write changes it once finished."""
    jobs = JobStore(records)
    job_id = running_job(jobs)
    accepted, refused, errors = Counter(), Counter(), []
    go = threading.Barrier(9)

    def writer(k: int):
        go.wait()
        for n in range(125):
            try:
                (accepted if jobs.set_progress(job_id, (k * 125 + n) / 1000) else refused)[k] += 1
            except Exception as error:  # noqa: BLE001 - any is a failure, counted and shown
                errors.append(repr(error))

    threads = [threading.Thread(target=writer, args=(k,)) for k in range(8)]
    for t in threads:
        t.start()
    go.wait()
    time.sleep(0.05)
    assert jobs.request_cancel(job_id)["cancel_requested"]
    jobs.write_summary(job_id, SUMMARY)
    final = jobs.complete(job_id, SUCCEEDED, progress=1.0)
    frozen = jobs.get(job_id)
    for t in threads:
        t.join()
    assert not errors, errors[:3]
    assert final == CANCELLED and frozen["status"] == CANCELLED
    assert not (jobs.folder(job_id) / "summary.json").exists()
    assert jobs.get(job_id) == frozen, "no progress write changed the finished record"
    total = sum(accepted.values()) + sum(refused.values())
    report(
        record_property,
        f"\n{records.database_url and 'PostgreSQL' or 'SQLite'}: {total} concurrent progress writes: "
        f"{sum(accepted.values())} while running, {sum(refused.values())} refused once finished; "
        f"final status {frozen['status']}, no summary",
    )
    assert total == 1000


def test_a_store_that_kept_its_records_in_folders_is_imported_once(tmp_path):
    """The folder layout before the database: jobs/<id>/job.json (and `cancel`), sweeps/<id>.json."""
    root = tmp_path / "results"
    made = datetime(2026, 1, 2, 3, 4, 5, tzinfo=UTC)
    old = {}
    for k, status in enumerate((SUCCEEDED, QUEUED, RUNNING, CANCELLED)):
        job_id = f"{'ABCD'[k] * 21}{k}"
        folder = root / "jobs" / job_id
        folder.mkdir(parents=True)
        (folder / "case.json").write_text(json.dumps(BASE_CASE))
        old[job_id] = {
            "id": job_id,
            "name": "test",
            "kind": "run",
            "status": status,
            "progress": 0.0,
            "created": (made + timedelta(minutes=k)).isoformat(),
            "started": None,
            "finished": None,
            "error": None,
            "attempts": 0,
            "worker": None,
            "owner": None,
        }
        (folder / "job.json").write_text(json.dumps(old[job_id]))
    ids = list(old)
    (root / "jobs" / ids[2] / "cancel").write_text("")
    summary = simulate(BASE_CASE).summary
    (root / "jobs" / ids[0] / "summary.json").write_text(json.dumps(summary))
    (root / "sweeps").mkdir()
    (root / "sweeps" / f"{'S' * 22}.json").write_text(
        json.dumps(
            {
                "id": "S" * 22,
                "name": "old sweep",
                "created": made.isoformat(),
                "parameters": ["striker.velocity"],
                "variants": [{"values": {"striker.velocity": 3.0}, "job": ids[3]}],
                "owner": None,
            }
        )
    )

    settings = Settings(results_dir=root)
    client = TestClient(create_app(settings))
    listed = client.get("/v1/jobs").json()
    assert listed["total"] == 4 and [j["id"] for j in listed["jobs"]] == ids[::-1]
    assert client.get(f"/v1/jobs/{ids[0]}/summary").json() == summary
    assert client.get(f"/v1/jobs/{ids[2]}").json()["cancel_requested"]
    assert client.get(f"/v1/jobs/{ids[0]}").json()["created"] == "2026-01-02T03:04:05Z"
    assert client.get(f"/v1/sweeps/{'S' * 22}").json()["rows"][0]["job"] == ids[3]
    assert [j["id"] for j in client.get(f"/v1/jobs?sweep={'S' * 22}").json()["jobs"]] == [ids[3]]
    # Opened again (another process), the store imports nothing a second time.
    _open.cache_clear()
    assert JobStore(settings).list()[0] == 4


def test_a_job_running_across_the_upgrade_that_adds_its_beat_has_one_from_its_start(records):
    """Records from before a running job had a beat: each running one gets the time of its start
    (or of its creation, if it has none), so that it is taken again, or queued again, once that
    lapses; the others none."""
    from alembic import command
    from alembic.config import Config
    from sqlalchemy import create_engine

    url = records.database_url or f"sqlite:///{records.results_dir / 'percussim.db'}"
    records.results_dir.mkdir(parents=True)
    config = Config()
    config.set_main_option("script_location", "percussim.common:migrations")
    started = datetime(2026, 1, 2, 3, 4, 5, tzinfo=UTC)
    with create_engine(url).connect() as connection:
        config.attributes |= {"connection": connection, "results_dir": records.results_dir}
        command.upgrade(config, "0002")
        for job_id, status, start in (
            ("R" * 22, RUNNING, started),
            ("N" * 22, RUNNING, None),
            ("Q" * 22, QUEUED, None),
        ):
            connection.execute(
                text(
                    "INSERT INTO jobs (id, kind, status, progress, created, started, attempts, worker, cancel_requested)"
                    " VALUES (:id, 'run', :status, 0, :created, :started, 1, 'w1@x', false)"
                ),
                {"id": job_id, "status": status, "created": started - timedelta(minutes=1), "started": start},
            )
        connection.commit()
    jobs = JobStore(records)  # opened: migrated to the head
    with database(records).connect() as connection:
        beats = dict(connection.execute(text("SELECT id, beat FROM jobs")).all())
    as_time = lambda value: datetime.fromisoformat(str(value)).replace(tzinfo=UTC)  # noqa: E731
    assert as_time(beats["R" * 22]) == started and as_time(beats["N" * 22]) == started - timedelta(minutes=1)
    assert beats["Q" * 22] is None
    assert jobs.start("R" * 22, "w2@x")["attempts"] == 2  # long lapsed
    assert [job_id for job_id, _ in jobs.lapsed(datetime.now(UTC) - timedelta(minutes=1))] == ["N" * 22]
