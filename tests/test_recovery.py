"""A running job's beat, and the jobs run again from their records: a job runs on one worker at a
time while its worker renews its beat; once the beat lapses another worker may take it; once it
has lapsed for longer than the broker's redelivery, the job is queued again from its record
(`service.recovery`), its message lost or not. The live version, a message lost for real in
Redis, is `tests/test_faults.py`."""

from __future__ import annotations

import json
import threading
import time

import pytest
import redis
from conftest import BASE_CASE

from percussim.common import store
from percussim.common.broker import queue_folder
from percussim.common.settings import Settings
from percussim.common.store import FAILED, QUEUED, RUNNING, JobStore
from percussim.service import recovery
from percussim.testing.live_stack import redis_server
from percussim.worker import tasks

LAPSE = 1.0  # s: ALIVE_WITHIN for these tests, so that a beat lapses within the test (renewed every third of it)


@pytest.fixture
def quick(monkeypatch):
    """Beats that lapse after LAPSE s, renewed every LAPSE/3 s, and recovery with no margin."""
    monkeypatch.setattr(store, "ALIVE_WITHIN", LAPSE)
    monkeypatch.setattr(tasks, "ALIVE_WITHIN", LAPSE)
    monkeypatch.setattr(tasks, "HEARTBEAT_SECONDS", LAPSE / 3)
    monkeypatch.setattr(recovery, "RESTORE_MARGIN", 0.0)


def test_a_job_runs_on_one_worker_while_its_beat_is_fresh(tmp_path, quick):
    jobs = JobStore(Settings(results_dir=tmp_path))
    job_id = jobs.create(BASE_CASE)["id"]
    first = jobs.start(job_id, "w1@x")
    assert first["attempts"] == 1 and first["worker"] == "w1@x"
    assert jobs.start(job_id, "w2@x") is None and jobs.held(job_id)  # a second delivery, refused
    jobs.release(job_id, "w2@x")  # not w2's to hand back
    assert jobs.held(job_id)
    time.sleep(LAPSE / 2)
    jobs.renew(job_id, "w1@x")
    time.sleep(LAPSE / 2 + 0.05)  # past the first beat's lapse, not the renewed one's
    assert jobs.held(job_id) and jobs.start(job_id, "w2@x") is None
    time.sleep(LAPSE)  # w1 died: its beat lapses
    assert not jobs.held(job_id)
    second = jobs.start(job_id, "w2@x")
    assert second["attempts"] == 2 and second["worker"] == "w2@x"
    jobs.renew(job_id, "w1@x")  # the dead worker's beat no longer counts
    jobs.release(job_id, "w2@x")  # handed back at a stop: the next worker takes it at once
    third = jobs.start(job_id, "w3@x")
    assert third["attempts"] == 3 and third["worker"] == "w3@x"


def test_a_delivery_waits_for_a_dead_workers_beat_to_lapse_and_leaves_a_live_workers_job(tmp_path, quick):
    jobs = JobStore(Settings(results_dir=tmp_path))
    dead, alive = jobs.create(BASE_CASE)["id"], jobs.create(BASE_CASE)["id"]
    jobs.start(dead, "w1@x")
    jobs.start(alive, "w1@x")
    stop = threading.Event()

    def heartbeat():  # w1 keeps running `alive` (and has died under `dead`)
        while not stop.wait(LAPSE / 3):
            jobs.renew(alive, "w1@x")

    beating = threading.Thread(target=heartbeat)
    beating.start()
    try:
        start = time.monotonic()
        taken = tasks._take(jobs, dead, "w2@x")
        waited = time.monotonic() - start
        assert taken["worker"] == "w2@x" and taken["attempts"] == 2
        assert 0.5 * LAPSE < waited < 3 * LAPSE, waited
        start = time.monotonic()
        assert tasks._take(jobs, alive, "w2@x") is None
        assert time.monotonic() - start >= LAPSE  # it waited to be sure
        assert jobs.get(alive)["worker"] == "w1@x" and jobs.get(alive)["attempts"] == 1
    finally:
        stop.set()
        beating.join()
    finished = jobs.create(BASE_CASE)["id"]
    jobs.start(finished, "w1@x")
    jobs.finish(finished, FAILED, error="x")
    start = time.monotonic()
    assert tasks._take(jobs, finished, "w2@x") is None and time.monotonic() - start < LAPSE  # no wait


def test_a_job_silent_past_the_redelivery_is_queued_again_from_its_record(tmp_path, quick):
    settings = Settings(results_dir=tmp_path, job_time_limit=0.2, redelivery_seconds=0.5)
    jobs = JobStore(settings)

    def running(worker: str, attempts: int) -> str:
        job_id = jobs.create(BASE_CASE)["id"]
        for _ in range(attempts):
            jobs.release(job_id, worker)
            assert jobs.start(job_id, worker)
        return job_id

    lost, doomed, alive = running("w1@x", 1), running("w1@x", recovery.MAX_ATTEMPTS), running("w2@x", 1)
    assert recovery.recover(settings) == []  # every beat fresh
    deadline = time.monotonic() + 0.5 + 0.3  # the redelivery, then a lapse more than the margin (none)
    while time.monotonic() < deadline:
        jobs.renew(alive, "w2@x")
        time.sleep(0.05)
    assert recovery.recover(settings) == [lost]
    assert jobs.get(lost)["status"] == QUEUED and jobs.get(lost)["attempts"] == 1
    failed = jobs.get(doomed)
    assert failed["status"] == FAILED and f"died {recovery.MAX_ATTEMPTS} times" in failed["error"]
    assert "w1@x: no sign of life for more than 0.5 s" in failed["error"], failed["error"]
    assert jobs.get(alive)["status"] == RUNNING
    assert len(list(queue_folder(settings).iterdir())) == 1  # one message, for the lost job
    assert recovery.recover(settings) == []  # queued once


def test_recovery_runs_beside_the_api(tmp_path, quick, monkeypatch):
    """The API's lifespan runs the recovery's passes: a job left running by a dead worker is queued
    again while the API serves, with no request made."""
    from fastapi.testclient import TestClient

    from percussim.service.app import create_app

    settings = Settings(results_dir=tmp_path, job_time_limit=0.2, redelivery_seconds=0.3)
    monkeypatch.setattr(recovery, "interval", lambda s: 0.1)
    jobs = JobStore(settings)
    job_id = jobs.create(BASE_CASE)["id"]
    jobs.start(job_id, "w1@x")
    with TestClient(create_app(settings)):
        deadline = time.monotonic() + 5
        while jobs.get(job_id)["status"] == RUNNING and time.monotonic() < deadline:
            time.sleep(0.05)
    assert jobs.get(job_id)["status"] == QUEUED


def test_a_pass_beside_the_api_that_fails_is_logged_and_the_next_runs(caplog):
    from percussim.service.background import periodically

    passes = []

    def work():
        passes.append(time.monotonic())
        if len(passes) == 1:
            raise RuntimeError("a broker in a state no one foresaw")
        if len(passes) == 2:
            raise store.StoreUnavailable("the database is unavailable: down")

    with periodically("recovery", 0.05, work):
        deadline = time.monotonic() + 5
        while len(passes) < 3 and time.monotonic() < deadline:
            time.sleep(0.02)
    assert len(passes) >= 3
    assert "recovery: the pass failed; trying again later" in caplog.text and "a broker in a state" in caplog.text
    assert "recovery: the database is unavailable: down; trying again later" in caplog.text


def delivered(queue) -> list[str]:
    """Take every message waiting in the queue: their jobs, in order."""
    with queue.app.connection_for_read() as connection:
        messages = connection.SimpleQueue("celery", no_ack=True)
        found = []
        while True:
            try:
                found.append(messages.get(timeout=0.2).payload[0][0])
            except messages.Empty:
                return found


def test_a_queued_job_whose_message_is_lost_is_published_again_while_others_wait(tmp_path, quick):
    """A broker that lost its last writes: a job recorded queued with no message. Once queued for
    longer than the silence it is published again, once, while the message of another job still
    waits; that job is not."""
    from percussim.service.queue import JobQueue

    settings = Settings(results_dir=tmp_path, job_time_limit=0.2, redelivery_seconds=0.5)
    jobs, queue = JobStore(settings), JobQueue(settings)
    lost = jobs.create(BASE_CASE)["id"]  # recorded; its message never reached the broker
    waiting = jobs.create(BASE_CASE)["id"]
    queue.enqueue(waiting)
    assert queue.held() == {waiting}
    assert recovery.recover(settings) == []  # too recent
    time.sleep(0.6)
    assert recovery.recover(settings) == [lost]
    assert queue.held() == {waiting, lost} and jobs.get(lost)["status"] == QUEUED
    assert recovery.recover(settings) == []  # queued again just now: not lost yet
    assert delivered(queue) == [waiting, lost]


def test_redis_holds_a_message_a_worker_took_and_not_one_it_lost(tmp_path, quick):
    """On a real Redis: of three queued jobs, one message waits, one is delivered to a worker that
    has not acknowledged it (Redis keeps it apart until then), one is gone from the list. Only the
    last job is published again."""
    from percussim.service.queue import JobQueue

    with redis_server(tmp_path / "redis") as url:
        settings = Settings(results_dir=tmp_path, broker_url=url, job_time_limit=0.2, redelivery_seconds=0.5)
        jobs, queue = JobStore(settings), JobQueue(settings)
        waiting, taken, lost = (jobs.create(BASE_CASE)["id"] for _ in range(3))
        queue.enqueue(waiting, taken, lost)
        broker = redis.Redis.from_url(url)
        [raw] = [raw for raw in broker.lrange("celery", 0, -1) if lost in json.loads(raw)["headers"]["argsrepr"]]
        assert broker.lrem("celery", 1, raw) == 1
        with queue.app.connection_for_read() as connection:
            worker = connection.SimpleQueue("celery", no_ack=False)  # as a worker takes a message
            message = worker.get(timeout=2)
            assert message.payload[0][0] in (waiting, taken)
            if message.payload[0][0] == waiting:  # the group may publish in any order
                waiting, taken = taken, waiting
            assert broker.llen("celery") == 1 and broker.hlen("unacked") == 1
            assert queue.held() == {waiting, taken}
            time.sleep(0.6)
            assert recovery.recover(settings) == [lost]
            assert queue.held() == {waiting, taken, lost}
            message.ack()
        assert queue.held() == {waiting, lost}
