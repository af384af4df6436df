"""`percussim serve`: the API in the foreground, with its own queue workers in embedded mode.

The workers are child processes in the same process group, so stopping the group stops them all;
on Ctrl-C or SIGTERM the service stops them itself before it exits.
"""

from __future__ import annotations

import signal
import socket
import subprocess
import sys
import time

import uvicorn

from worker.settings import settings

from .queue import JobQueue

STOP_SECONDS = 10.0  # how long a worker may take to finish its running job when the service stops
COLD_STOP_SECONDS = 5.0  # then how long it may take to stop that job and requeue it


def _stop_requested(signum: int, frame) -> None:
    # Uvicorn stops serving on SIGINT/SIGTERM, then raises the signal again: leave through the
    # `finally` that stops the workers rather than die with them still running.
    raise SystemExit(0)


def _start_worker(k: int) -> subprocess.Popen:
    # Distinct names: each worker has its own heartbeat file and Celery node name.
    name = f"percussim{k}@{socket.gethostname()}"
    return subprocess.Popen([sys.executable, "-m", "solver", "worker", "--name", name])


def _stop_workers(workers: list[subprocess.Popen]) -> None:
    """Celery's warm shutdown (SIGTERM) lets a running job finish; after STOP_SECONDS its cold
    shutdown (SIGQUIT) stops the job and puts it back on the queue for the next worker; SIGKILL
    only for a worker that still has not exited."""
    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, signal.SIG_IGN)  # a second Ctrl-C must not cut the cleanup short
    for signum, seconds in ((signal.SIGTERM, STOP_SECONDS), (signal.SIGQUIT, COLD_STOP_SECONDS)):
        for worker in workers:
            if worker.poll() is None:
                worker.send_signal(signum)
        deadline = time.monotonic() + seconds
        for worker in workers:
            try:
                worker.wait(max(0.0, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                pass
    for worker in workers:
        if worker.poll() is None:
            worker.kill()
            worker.wait()


def run_service(host: str = "127.0.0.1", port: int = 8000, workers: int | None = None,
                start_workers: bool = True) -> None:
    """Serve the API on `host:port`. Embedded mode starts `workers` queue workers (default 1);
    Redis mode starts none unless `workers` is given, since they run as `percussim worker`."""
    s = settings()
    if not start_workers:
        count = 0
    elif workers is not None:
        count = workers
    else:
        count = 1 if s.embedded else 0
    print(f"percussim: job page and API on http://{host}:{port}/ (API docs at /docs), queue {JobQueue(s).describe()}"
          f" with {count} worker(s) started here, results in {s.results_dir.resolve()}", flush=True)
    for signum in (signal.SIGINT, signal.SIGTERM):
        signal.signal(signum, _stop_requested)
    children: list[subprocess.Popen] = []
    try:
        for k in range(1, count + 1):
            children.append(_start_worker(k))
        uvicorn.run("service.app:app", host=host, port=port)
    finally:
        _stop_workers(children)
