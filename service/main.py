"""`percussim serve`: the API in the foreground, with its own queue workers in embedded mode.

The workers are child processes in the same process group, so stopping the group stops them all;
on Ctrl-C or SIGTERM the service stops them itself before it exits. A worker that dies meanwhile
is started again; in embedded mode the job it was running is queued again, since the filesystem
broker lost its message with the worker (Redis delivers such a job again by itself). When an
embedded service starts, the queue is made again from the job records (`restore_queue`): the jobs a
crashed service left running, and any queued job whose message was lost, run too.
"""

from __future__ import annotations

import signal
import socket
import subprocess
import sys
import threading
import time

import uvicorn

from percussim.common.settings import Settings, settings
from percussim.common.store import QUEUED, RUNNING, JobStore

from .queue import JobQueue
from .recovery import requeue_or_fail

COLD_STOP_SECONDS = 5.0  # after the grace (`stop_grace`), how long a worker may take to stop its job
WATCH_SECONDS = 1.0  # how often the service looks for a worker that died


def _stop_requested(signum: int, frame) -> None:
    # Uvicorn stops serving on SIGINT/SIGTERM, then raises the signal again: leave through the
    # `finally` that stops the workers rather than die with them still running.
    raise SystemExit(0)


def _start_worker(name: str) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "percussim", "worker", "--name", name])


def _back_to_queue(jobs: JobStore, worker: str, death: str) -> list[str]:
    """Record as queued again the jobs the dead `worker` was running (`death` says how it died), or
    as failed those it died under too often (`requeue_or_fail`). Returns the ids queued again."""
    return [job_id for job_id in jobs.ids(RUNNING, worker=worker) if requeue_or_fail(jobs, job_id, worker, death)]


def _say_queued_again(again: list[str], worker: str, death: str) -> None:
    if again:
        print(f"percussim: queued again {len(again)} job(s) {worker} was running ({death})", flush=True)


def queue_again(settings: Settings, worker: str, death: str) -> list[str]:
    """Queue again the jobs the dead `worker` was running (`_back_to_queue`); returns their ids,
    none if the broker could not take them (they are then failed, saying why)."""
    jobs = JobStore(settings)
    again = _back_to_queue(jobs, worker, death)
    if (
        again
        and JobQueue(settings).enqueue_or_fail(jobs, again, "its worker died and the job could not be queued again")
        is not None
    ):
        return []
    _say_queued_again(again, worker, death)
    return again


def restore_queue(settings: Settings, workers: list[str]) -> list[str]:
    """Embedded mode, before any of this service's `workers` runs: the queue as the job records
    say it is. The jobs cut off running on them when the service last stopped (a crash, a power
    cut) are queued again (`_back_to_queue`); then every queued job gets one message, the
    folder's own dropped first, oldest job first. So a job whose message was lost another way (the
    service stopped between recording the job and publishing it, a message file removed by hand)
    runs too, and none runs twice. Returns the ids of the queued jobs."""
    jobs = JobStore(settings)
    death = "the service stopped while it ran"
    cut_off = {name: _back_to_queue(jobs, name, death) for name in workers}
    queue = JobQueue(settings)
    queue.purge()
    waiting = jobs.ids(QUEUED)
    if (
        waiting
        and queue.enqueue_or_fail(jobs, waiting, "the job could not be queued again when the service started")
        is not None
    ):
        return []
    for name, again in cut_off.items():
        _say_queued_again(again, name, death)
    return waiting


class _Workers:
    """The queue workers the service runs, watched: one that dies is started again."""

    def __init__(self, count: int, settings: Settings):
        self.settings = settings
        # Distinct names: each worker has its own heartbeat file and Celery node name.
        names = [f"percussim{k}@{socket.gethostname()}" for k in range(1, count + 1)]
        if settings.embedded:
            restore_queue(settings, names)
        self.processes = {name: _start_worker(name) for name in names}
        self._stopping = threading.Event()
        self._watcher = threading.Thread(target=self._watch, name="percussim-workers", daemon=True)
        self._watcher.start()

    def _watch(self) -> None:
        while not self._stopping.wait(WATCH_SECONDS):
            for name, process in self.processes.items():
                if process.poll() is not None:
                    print(
                        f"percussim: worker {name} exited (status {process.returncode}); starting it again", flush=True
                    )
                    if self.settings.embedded:
                        queue_again(self.settings, name, f"exit status {process.returncode}")
                    self.processes[name] = _start_worker(name)

    def stop(self) -> None:
        self._stopping.set()
        self._watcher.join()
        _stop_workers(list(self.processes.values()), grace=self.settings.stop_grace)


def _stop_workers(workers: list[subprocess.Popen], grace: float) -> None:
    """Celery's warm shutdown (SIGTERM): each worker lets its running job finish for `grace` s,
    then stops it and puts it back on the queue (`worker.app`); SIGKILL only for a worker that
    has still not exited `COLD_STOP_SECONDS` after that."""
    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, signal.SIG_IGN)  # a second Ctrl-C must not cut the cleanup short
    for worker in workers:
        if worker.poll() is None:
            worker.send_signal(signal.SIGTERM)
    deadline = time.monotonic() + grace + COLD_STOP_SECONDS
    for worker in workers:
        try:
            worker.wait(max(0.0, deadline - time.monotonic()))
        except subprocess.TimeoutExpired:
            worker.kill()
            worker.wait()


def run_service(
    host: str = "127.0.0.1", port: int = 8000, workers: int | None = None, start_workers: bool = True
) -> None:
    """Serve the API on `host:port`. Embedded mode starts `workers` queue workers (default 1);
    Redis mode starts none unless `workers` is given, since they run as `percussim worker`."""
    s = settings()
    if not start_workers:
        count = 0
    elif workers is not None:
        count = workers
    else:
        count = 1 if s.embedded else 0
    print(
        f"percussim: job page and API on http://{host}:{port}/ (API docs at /docs), queue {JobQueue(s).describe()}"
        f" with {count} worker(s) started here, results in {s.results_dir.resolve()}",
        flush=True,
    )
    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, _stop_requested)
    children = _Workers(count, s)
    try:
        uvicorn.run("percussim.service.app:app", host=host, port=port)
    finally:
        children.stop()
