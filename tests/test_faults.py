"""Faults against the live stack (real redis-server, PostgreSQL, workers and API): a worker killed
mid-job, Redis restarted during a burst, PostgreSQL stopped during a burst, the API restarted, a
results store that cannot write (a real file size limit), a numerical failure, a burst of 1000.
Each test prints the counts it saw."""

from __future__ import annotations

import logging
import os
import resource
import signal
import subprocess
import threading
import time
from pathlib import Path

import h5py
import pytest
import redis as redis_client
from conftest import CHATTERS, LONG_WORK, SECONDS_OF_WORK, merge, report, running_again

from percussim.client import FINISHED
from percussim.solver.presets import preset_json
from percussim.testing.live_stack import RedisServer, Stack, children, command_line, wait_for

pytestmark = pytest.mark.slow  # a live stack, a browser or the solver's full reports


@pytest.fixture
def redis(tmp_path):
    server = RedisServer(tmp_path / "redis")
    server.start()
    yield server
    server.stop()


def statuses(stack: Stack, ids: list[str]) -> dict[str, int]:
    counts: dict[str, int] = {}
    for job_id in ids:
        status = stack.client.get(f"/v1/jobs/{job_id}").json()["status"]
        counts[status] = counts.get(status, 0) + 1
    return counts


def wait_all_finished(stack: Stack, ids: list[str], timeout: float) -> dict[str, int]:
    def finished() -> dict[str, int] | None:
        counts = statuses(stack, ids)
        return counts if sum(counts.get(s, 0) for s in FINISHED) == len(ids) else None

    return wait_for(finished, timeout, f"{len(ids)} jobs finished", interval=0.5)


def test_a_worker_killed_mid_job_gets_it_delivered_again_and_it_succeeds_once(redis, tmp_path, record_property):
    s = Stack(
        tmp_path,
        redis.url,
        workers=2,
        worker_env={"PERCUSSIM_JOB_TIME_LIMIT": "10", "PERCUSSIM_REDELIVERY_SECONDS": "12"},
    )
    try:
        job = s.client.post("/v1/jobs", json=SECONDS_OF_WORK).json()
        running = s.wait_status(job["id"], ("running",), timeout=30)
        wait_for(lambda: s.client.get(f"/v1/jobs/{job['id']}").json()["progress"] > 0.1, 30, "some progress")
        victim = running["worker"]
        s.workers[victim].stop(signal.SIGKILL)  # the worker and its pool, no chance to clean up
        record = s.wait_status(job["id"], FINISHED, timeout=90)
        report(
            record_property,
            f"\nkilled {victim} mid-job; the job then {record['status']} on {record['worker']} "
            f"after {record['attempts']} attempts",
        )
        assert record["status"] == "succeeded", (record, s.logs())
        assert record["worker"] != victim and record["attempts"] == 2
        folder = tmp_path / "results" / "jobs" / job["id"]
        assert sorted(p.name for p in folder.iterdir()) == ["case.json", "result.h5", "summary.json"]
        with h5py.File(folder / "result.h5") as f:
            assert f.attrs["format"] == "percussim-result" and len(f["contact/force"]) > 0
    finally:
        s.stop()


def test_a_job_whose_message_redis_lost_with_its_worker_runs_again_from_its_record(redis, tmp_path, record_property):
    """A worker killed mid-job and the job's message gone from Redis with it (what a worker cut while
    it hands its messages back can leave, Celery's issue #4354): no redelivery will come. Once the
    job's beat has been silent for the redelivery time and a margin, the API queues it again from
    its record, and the other worker runs it, once."""
    s = Stack(
        tmp_path, redis.url, workers=2, env={"PERCUSSIM_JOB_TIME_LIMIT": "10", "PERCUSSIM_REDELIVERY_SECONDS": "12"}
    )
    try:
        job = s.client.post("/v1/jobs", json=SECONDS_OF_WORK).json()
        running = s.wait_status(job["id"], ("running",), timeout=30)
        wait_for(lambda: s.client.get(f"/v1/jobs/{job['id']}").json()["progress"] > 0.1, 30, "some progress")
        victim = running["worker"]
        s.workers[victim].stop(signal.SIGKILL)
        broker = redis_client.Redis.from_url(redis.url)
        assert broker.hlen("unacked") == 1 and broker.llen("celery") == 0  # the job's message, not yet back
        broker.delete("unacked", "unacked_index")  # lost
        killed = time.monotonic()
        record = running_again(s.client, job["id"], timeout=90)
        taken = time.monotonic() - killed
        assert record["worker"] != victim, record
        record = s.wait_status(job["id"], FINISHED, timeout=60)
        assert record["status"] == "succeeded" and record["attempts"] == 2, (record, s.logs())
        log = (tmp_path / "api.log").read_text()
        assert f"job {job['id']} was running on {victim}, no sign of life for more than 27 s: queued again" in log, log
        report(
            record_property,
            f"\na worker killed mid-job and its message deleted from Redis: the job queued again from its "
            f"record and running on {record['worker']} {taken:.1f} s after the kill (redelivery 12 s + 15 s), "
            f"then {record['status']} after {record['attempts']} attempts",
        )
    finally:
        s.stop()


def test_the_embedded_service_starts_a_dead_worker_again_and_runs_its_job_again(tmp_path, record_property):
    """The default set-up: `percussim serve` with its own worker on the filesystem broker, which
    loses the message of a job whose worker dies; the service queues the job again."""
    s = Stack(tmp_path, None, workers=1)
    try:
        job = s.client.post("/v1/jobs", json=SECONDS_OF_WORK).json()
        running = s.wait_status(job["id"], ("running",), timeout=30)
        wait_for(lambda: s.client.get(f"/v1/jobs/{job['id']}").json()["progress"] > 0.1, 30, "some progress")
        serve = s.processes[0].popen.pid
        [worker] = [pid for pid in children(serve) if " worker " in command_line(pid)]
        for pid in [worker, *children(worker)]:  # the worker and its pool, no chance to clean up
            os.kill(pid, signal.SIGKILL)
        record = s.wait_status(job["id"], FINISHED, timeout=90)
        report(
            record_property,
            f"\nembedded worker killed mid-job: the service started it again; the job then "
            f"{record['status']} after {record['attempts']} attempts",
        )
        assert record["status"] == "succeeded" and record["attempts"] == 2, (record, s.logs())
        assert record["worker"] == running["worker"]  # the same worker, started again
        log = s.processes[0].log.read_text()
        assert f"worker {running['worker']} exited" in log and "queued again 1 job(s)" in log
        after = s.client.post("/v1/jobs", json=preset_json("fig3")).json()
        assert s.wait_status(after["id"], FINISHED, timeout=30)["status"] == "succeeded"
    finally:
        s.stop()


def test_a_job_running_when_the_embedded_service_crashed_runs_again_when_it_restarts(tmp_path, record_property):
    s = Stack(tmp_path, None, workers=1)
    try:
        job = s.client.post("/v1/jobs", json=SECONDS_OF_WORK).json()
        queued = [s.client.post("/v1/jobs", json=preset_json("fig3")).json()["id"] for _ in range(3)]
        s.wait_status(job["id"], ("running",), timeout=30)
        wait_for(lambda: s.client.get(f"/v1/jobs/{job['id']}").json()["progress"] > 0.1, 30, "some progress")
        messages = sorted((tmp_path / "results" / "broker" / "queue").glob("*.msg"))
        assert len(messages) == 3, messages  # the queued jobs' messages, on disk
        s.restart(while_down=messages[1].unlink)  # and one of them lost while down
        record = s.wait_status(job["id"], FINISHED, timeout=90)
        counts = wait_all_finished(s, queued, timeout=60)
        report(
            record_property,
            f"\nembedded service killed mid-job and started again, one queued job's message "
            f"removed meanwhile: the job {record['status']} after {record['attempts']} "
            f"attempts; the 3 queued behind it {counts}",
        )
        assert record["status"] == "succeeded" and record["attempts"] == 2, (record, s.logs())
        assert counts == {"succeeded": 3}, s.logs()  # the lost message's job too
        assert "queued again 1 job(s)" in (tmp_path / "api-restarted.log").read_text()
    finally:
        s.stop()


def test_a_stop_signalled_to_every_process_of_the_service_lets_the_running_job_finish_once(tmp_path, record_property):
    """systemd's default stop: SIGTERM to the service, its worker and the worker's pool at once.
    The worker shuts down warm and its pool's child, left running, finishes the job: it has
    succeeded, on its first run, when the service starts again."""
    s = Stack(tmp_path, None, workers=1)
    try:
        job = s.client.post("/v1/jobs", json=SECONDS_OF_WORK).json()
        s.wait_status(job["id"], ("running",), timeout=30)
        wait_for(lambda: s.client.get(f"/v1/jobs/{job['id']}").json()["progress"] > 0.1, 30, "some progress")
        s.restart(signal.SIGTERM, timeout=60)
        record = s.wait_status(job["id"], FINISHED, timeout=30)
        log = (tmp_path / "api.log").read_text()  # the service stopped, before its restart
        report(
            record_property,
            f"\nSIGTERM to every process of the embedded service mid-job: the job {record['status']} "
            f"after {record['attempts']} attempt(s)",
        )
        assert record["status"] == "succeeded" and record["attempts"] == 1, (record, s.logs())
        assert "Warm shutdown" in log and "Cold shutdown" not in log and "exited with 'signal" not in log
    finally:
        s.stop()


def a_long_job_running(stack: Stack) -> dict:
    """A job of `LONG_WORK` submitted and running, some progress made: its record as submitted."""
    job = stack.client.post("/v1/jobs", json=LONG_WORK).json()
    stack.wait_status(job["id"], ("running",), timeout=30)
    wait_for(lambda: stack.client.get(f"/v1/jobs/{job['id']}").json()["progress"] > 0.02, 30, "some progress")
    return job


def left_in_group(pid: int) -> list[str]:
    """The processes still in the process group `pid` leads."""
    return subprocess.run(["pgrep", "-g", str(pid)], capture_output=True, text=True).stdout.split()


def test_a_job_outlasting_the_stops_grace_is_cut_by_its_worker_and_runs_again_at_the_next_start(
    tmp_path, record_property
):
    """The same stop with a job longer than the grace (`PERCUSSIM_STOP_GRACE`, here 1 s): the
    worker then shuts down cold, and its SIGTERM the pool's child does take. The service exits by
    itself, leaving no process behind, and the job runs again when it starts."""
    s = Stack(tmp_path, None, workers=1, env={"PERCUSSIM_STOP_GRACE": "1"})
    try:
        job = a_long_job_running(s)
        service = s.processes[0].popen
        s.processes[0].signal(signal.SIGTERM, everyone=True)
        assert service.wait(60) == 0, s.logs()
        left = left_in_group(service.pid)
        assert left == [], (left, s.logs())
        log = (tmp_path / "api.log").read_text()
        assert f"the running job {job['id']} outlasted PERCUSSIM_STOP_GRACE (1 s)" in log, log[-3000:]
        assert "Cold shutdown" in log, log[-3000:]
        s.restart()
        record = running_again(s.client, job["id"])
        report(record_property, f"\na job cut at a stop after the grace: running again, attempt {record['attempts']}")
        assert s.client.delete(f"/v1/jobs/{job['id']}").status_code == 202
    finally:
        s.stop()


def test_a_worker_stopped_in_a_job_longer_than_its_grace_hands_the_job_to_another_at_once(
    redis, tmp_path, record_property
):
    """`docker stop` or systemd stopping a `percussim worker` (SIGTERM to its every process) in a
    job longer than the grace (here 1 s): the worker stops the job and exits within seconds, and
    the job goes back on the queue at once, where the next worker takes it, rather than waiting
    for the redelivery time (17 min by default) as it would after the manager's SIGKILL."""
    s = Stack(tmp_path, redis.url, workers=1, env={"PERCUSSIM_STOP_GRACE": "1"})
    try:
        job = a_long_job_running(s)
        worker = s.workers["w0@percussim"]
        start = time.monotonic()
        worker.signal(signal.SIGTERM, everyone=True)
        assert worker.popen.wait(30) == 0, s.logs()
        stopped = time.monotonic() - start
        left = left_in_group(worker.popen.pid)
        assert left == [], (left, s.logs())
        log = worker.log.read_text()
        assert f"the running job {job['id']} outlasted PERCUSSIM_STOP_GRACE (1 s)" in log, s.logs()
        assert "Cold shutdown" in log, s.logs()
        s.add_worker("w1")
        record = running_again(s.client, job["id"])
        assert record["worker"] == "w1@percussim", record
        report(
            record_property,
            f"\na worker stopped in a job after a 1-s grace: exited in {stopped:.1f} s; the job running "
            f"again on {record['worker']}, attempt {record['attempts']}",
        )
        assert s.client.delete(f"/v1/jobs/{job['id']}").status_code == 202
    finally:
        s.stop()


def gone(pid: int) -> bool:
    """The process has exited (a zombie not yet reaped counts as exited)."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] == "Z"
    except FileNotFoundError:
        return True


def test_a_worker_past_its_grace_with_no_job_running_blames_none_and_stops_cold(caplog):
    """A worker still there when its grace ends, its jobs done (slow to exit for another reason),
    says so rather than name a job it would cut, and asks itself for the cold shutdown."""
    from percussim.worker.app import _cut_after_the_grace, handing_back

    quits = []
    before = signal.signal(signal.SIGQUIT, lambda *_: quits.append(True))
    try:
        with caplog.at_level(logging.WARNING):
            _cut_after_the_grace(0.5)
    finally:
        signal.signal(signal.SIGQUIT, before)
        handing_back.clear()
    assert quits == [True]
    assert "no job running, yet not stopped after PERCUSSIM_STOP_GRACE (0.5 s): stopping now" in caplog.text
    assert "outlasted" not in caplog.text


def test_a_pool_process_sent_sigterm_alone_dies_and_its_job_runs_again(redis, tmp_path, record_property):
    """Someone stopping a runaway job's process by hand (`kill PID` on the pool's child): while its
    worker is not stopping, the child dies of it as a process does, and the job, its worker lost,
    runs again. (A SIGTERM to every process of a worker that stops is left to the worker: the
    stops above.)"""
    s = Stack(tmp_path, redis.url, workers=1)
    try:
        job = a_long_job_running(s)
        (child,) = children(s.workers["w0@percussim"].popen.pid)
        os.kill(child, signal.SIGTERM)
        wait_for(lambda: gone(child), 10, "the pool's process gone")
        record = wait_for(
            lambda: (r := s.client.get(f"/v1/jobs/{job['id']}").json())["attempts"] == 2 and r,
            60,
            "the job taken again",
        )
        report(
            record_property,
            f"\nSIGTERM to a pool process alone mid-job: it died; the job {record['status']}, attempt {record['attempts']}",
        )
        assert s.client.delete(f"/v1/jobs/{job['id']}").status_code in (202, 204)
    finally:
        s.stop()


def test_redis_restarted_during_a_burst_gives_503_with_retry_after_and_loses_no_accepted_job(
    redis, tmp_path, record_property
):
    s = Stack(tmp_path, redis.url, workers=1)
    try:
        accepted = [s.client.post("/v1/jobs", json=SECONDS_OF_WORK).json()["id"] for _ in range(3)]
        accepted += [s.client.post("/v1/jobs", json=preset_json("fig3")).json()["id"] for _ in range(20)]
        redis.stop()
        refused = [s.client.post("/v1/jobs", json=preset_json("fig3")) for _ in range(5)]
        assert all(a.status_code == 503 and a.headers["retry-after"].isdigit() for a in refused), [
            (a.status_code, a.text[:200]) for a in refused
        ]
        assert s.client.get("/readyz").status_code == 503
        redis.start()  # the same port and append-only file
        wait_for(lambda: s.client.get("/readyz").status_code == 200, 60, "readiness after Redis is back")
        after = [s.client.post("/v1/jobs", json=preset_json("fig3")) for _ in range(5)]
        assert all(a.status_code == 202 for a in after), "the API recovers without a restart"
        counts = wait_all_finished(s, accepted + [a.json()["id"] for a in after], timeout=180)
        report(
            record_property,
            f"\nRedis restarted: {len(accepted)} accepted before, 5 refused with 503 while down, "
            f"5 accepted after; outcomes {counts}",
        )
        assert counts == {"succeeded": len(accepted) + 5}, s.logs()
    finally:
        s.stop()


def test_postgresql_stopped_during_a_burst_gives_503_with_retry_after_and_loses_no_accepted_job(
    redis, postgres, tmp_path, record_property
):
    s = Stack(tmp_path, redis.url, workers=2, env={"PERCUSSIM_DATABASE_URL": postgres.database()})
    answers, done = [], threading.Event()

    def burst():
        while not done.is_set():
            try:
                answers.append(s.client.post("/v1/jobs", json=preset_json("fig3")))
            except Exception as error:  # noqa: BLE001 - a dropped connection is a failure, shown
                answers.append(error)
            time.sleep(0.01)

    client = threading.Thread(target=burst)
    try:
        client.start()
        wait_for(lambda: len(answers) >= 40, 60, "40 submissions")
        postgres.stop()
        during = len(answers)
        time.sleep(2.0)
        postgres.start()
        restarted = len(answers)
        wait_for(lambda: len(answers) >= restarted + 40, 60, "40 submissions after the restart")
        done.set()
        client.join()
        codes = [a.status_code if hasattr(a, "status_code") else repr(a) for a in answers]
        assert set(codes) <= {202, 503}, [c for c in codes if c not in (202, 503)][:5]
        refused = [a for a in answers if a.status_code == 503]
        assert refused and all(
            a.headers["retry-after"].isdigit() and "database" in a.json()["detail"] for a in refused
        ), [a.text[:200] for a in refused[:3]]
        assert codes[-20:] == [202] * 20, "the API recovers without a restart"
        accepted = [a.json()["id"] for a in answers if a.status_code == 202]
        counts = wait_all_finished(s, accepted, timeout=180)
        report(
            record_property,
            f"\nPostgreSQL stopped for 2 s during a burst: {len(answers)} submissions, {len(accepted)} "
            f"accepted ({during} answered before it was down), {len(refused)} refused with 503 and Retry-After, "
            f"none answered otherwise; the accepted ones {counts}",
        )
        assert counts == {"succeeded": len(accepted)}, s.logs()
        assert s.client.get("/v1/jobs?limit=1").json()["total"] == len(accepted), "no refused job was kept"
        # What the workers counted, through the metrics.
        metrics = dict(
            line.rsplit(" ", 1) for line in s.client.get("/metrics").text.splitlines() if not line.startswith("#")
        )
        assert float(metrics['percussim_jobs{status="succeeded"}']) == len(accepted)
        assert float(metrics["percussim_job_duration_seconds_count"]) == len(accepted)
        assert float(metrics["percussim_solver_seconds_per_node_step_count"]) == len(accepted)
        assert float(metrics["percussim_results_bytes"]) > 0.8e6 * len(accepted)  # 0.9 MB each
        assert float(metrics["percussim_queue_depth"]) == 0
    finally:
        done.set()
        client.join()
        try:
            postgres.start()
        except Exception:  # noqa: BLE001 - already running again
            pass
        s.stop()


def _limit_file_size(pid: int, limit: int) -> None:
    """Set RLIMIT_FSIZE (bytes; the hard limit kept) on `pid` and every process it started."""
    _, hard = resource.prlimit(pid, resource.RLIMIT_FSIZE)
    resource.prlimit(pid, resource.RLIMIT_FSIZE, (limit, hard))
    for child in children(pid):
        _limit_file_size(child, limit)


def test_a_store_that_cannot_write_fails_the_job_or_refuses_it_with_507_and_recovers(redis, tmp_path, record_property):
    """A real limit, the file size limit (RLIMIT_FSIZE): on the worker, a job whose result is
    larger ends failed with the reason and nothing half-written, and the worker goes on; on the
    API, nothing can be written, new jobs get 507 while the rest of the API answers."""
    s = Stack(tmp_path, redis.url, workers=1)
    big = merge(preset_json("fig3"), {"outputs": {"fields": True, "field_stride": 1}})  # 6.9 MB of result
    try:
        [worker] = s.workers.values()
        _limit_file_size(worker.popen.pid, 3_000_000)
        failed = s.client.post("/v1/jobs", json=big).json()
        record = s.wait_status(failed["id"], FINISHED, timeout=60)
        assert record["status"] == "failed", record
        assert record["error"].startswith("its results could not be written: ") and "File too large" in record["error"]
        folder = tmp_path / "results" / "jobs" / failed["id"]
        assert sorted(p.name for p in folder.iterdir()) == ["case.json"], "nothing half-written is left"
        small = s.client.post("/v1/jobs", json=preset_json("fig3")).json()  # 0.9 MB: under the limit
        assert s.wait_status(small["id"], FINISHED, timeout=60)["status"] == "succeeded", "the worker goes on"

        api = s.processes[0].popen.pid
        _limit_file_size(api, 0)
        refused = s.client.post("/v1/jobs", json=preset_json("fig3"))
        assert refused.status_code == 507, refused.text
        assert "cannot write" in refused.json()["detail"] and "File too large" in refused.json()["detail"]
        assert s.client.get(f"/v1/jobs/{small['id']}/summary").status_code == 200, "reading goes on"
        assert s.client.get("/healthz").status_code == 200
        assert s.client.get("/v1/jobs").json()["total"] == 2, "the refused job left no record"
        _limit_file_size(api, resource.RLIM_INFINITY)
        again = s.client.post("/v1/jobs", json=preset_json("fig3"))
        assert again.status_code == 202 and s.wait_status(again.json()["id"], FINISHED)["status"] == "succeeded"
        report(
            record_property,
            f"\nfile size limit: on the worker (3 MB) the 6.9-MB job {record['status']}: "
            f"{record['error']!r}, only its case left; on the API (0 bytes) a new job got "
            f"{refused.status_code}: {refused.json()['detail']!r}; limit lifted: the next job succeeded",
        )
    finally:
        s.stop()


def test_after_the_api_restarts_every_record_and_result_is_served(redis, tmp_path, record_property):
    s = Stack(tmp_path, redis.url, workers=1)
    try:
        ids = [s.client.post("/v1/jobs", json=preset_json(name)).json()["id"] for name in ("fig3", "fig9")]
        wait_all_finished(s, ids, timeout=60)
        before = {
            i: (
                s.client.get(f"/v1/jobs/{i}").json(),
                s.client.get(f"/v1/jobs/{i}/summary").json(),
                s.client.get(f"/v1/jobs/{i}/result.h5").content,
            )
            for i in ids
        }
        s.restart_api()
        for job_id, (record, summary, result) in before.items():
            assert s.client.get(f"/v1/jobs/{job_id}").json() == record
            assert s.client.get(f"/v1/jobs/{job_id}/summary").json() == summary
            assert s.client.get(f"/v1/jobs/{job_id}/result.h5").content == result
        assert s.client.get("/v1/jobs").json()["total"] == len(ids)
        report(record_property, f"\nAPI restarted: {len(ids)} records, summaries and results served as before")
    finally:
        s.stop()


def test_a_failure_as_it_runs_ends_the_job_failed_with_what_and_what_to_change(redis, tmp_path, record_property):
    s = Stack(tmp_path, redis.url, workers=1)
    try:
        job = s.client.post("/v1/jobs", json=CHATTERS)
        assert job.status_code == 202, job.text  # nothing to refuse up front
        record = s.wait_status(job.json()["id"], FINISHED, timeout=60)
        report(record_property, f"\nfailure as it runs: {record['status']}: {record['error']}")
        assert record["status"] == "failed"
        assert "the contact chattered on this grid (" in record["error"]
        assert "Leave numerics.cells, time_step and scheme out" in record["error"]
        assert s.client.get(f"/v1/jobs/{job.json()['id']}/summary").status_code == 409
    finally:
        s.stop()


def test_a_burst_of_1000_submissions_is_every_one_accounted_for(redis, tmp_path, record_property):
    s = Stack(tmp_path, redis.url, workers=2)
    try:
        start = time.monotonic()
        answers = [s.client.post("/v1/jobs", json=preset_json("fig3")) for _ in range(1000)]
        assert all(a.status_code == 202 for a in answers), {a.status_code for a in answers}
        ids = [a.json()["id"] for a in answers]
        counts = wait_all_finished(s, ids, timeout=600)
        report(record_property, f"\nburst: 1000 submitted, outcomes {counts} after {time.monotonic() - start:.1f} s")
        assert counts == {"succeeded": 1000}
        assert s.client.get("/v1/jobs").json()["total"] == 1000
    finally:
        s.stop()
