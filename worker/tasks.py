"""The job task: run a stored job, by its kind, and store its status and answer.

A run (`kind` 'run') is the solver on its case, storing the summary and the HDF5 result. A
study (a calibration, an optimisation, a bearing graph, a drivability) runs, spreading its batches
of runs over the workers (`fanout`), and stores its answer and plot. Each shares the same life: queued → running →
succeeded, failed or cancelled, with progress, cancel and the time limit.
"""

from __future__ import annotations

import os
import socket
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import TypeVar

from celery.exceptions import Reject

from percussim.common.broker import EVALUATE_PART, RUN_JOB
from percussim.common.metrics import job_observations
from percussim.common.settings import settings
from percussim.common.store import (
    ALIVE_WITHIN,
    BEARING_GRAPH,
    CALIBRATION,
    CANCELLED,
    DRIVABILITY,
    FAILED,
    HEARTBEAT_SECONDS,
    OPTIMIZATION,
    RUN,
    SIGNAL_MATCH,
    STUDY_PLOT,
    SUCCEEDED,
    JobStore,
    StoreFull,
    StoreUnavailable,
    UnknownJob,
    WorkerRegistry,
)
from percussim.solver.calibrate import calibrate
from percussim.solver.case import CaseError, parse_case
from percussim.solver.errors import Cancelled, NumericalFailure
from percussim.solver.io import remove_partial
from percussim.solver.optimize import optimize
from percussim.solver.pile_studies import bearing_graph, drivability
from percussim.solver.signal_match import signal_match
from percussim.solver.simulate import simulate
from percussim.solver.study_plots import render_study

from .app import app, handing_back
from .fanout import QueueEvaluator, take_part

T = TypeVar("T")

PROGRESS_SECONDS = 0.25  # how often a running job's progress is written
CANCEL_POLL_SECONDS = 0.1  # how often a running job asks whether it was cancelled
STORE_RETRY_SECONDS = 60.0  # how long a job's end waits for a database that went away
STUDIES = {
    CALIBRATION: calibrate,
    OPTIMIZATION: optimize,
    BEARING_GRAPH: bearing_graph,
    DRIVABILITY: drivability,
    SIGNAL_MATCH: signal_match,
}


class TimeLimitExceeded(Exception):
    pass


def _stored(action: Callable[[], T]) -> T:
    """`action` on the records, tried again while the database is away; after
    STORE_RETRY_SECONDS the job's message goes back to the queue, to run again later."""
    deadline, pause = time.monotonic() + STORE_RETRY_SECONDS, 0.1
    while True:
        try:
            return action()
        except StoreUnavailable as error:
            if time.monotonic() > deadline:
                raise Reject(str(error), requeue=True) from error
            time.sleep(pause)
            pause = min(2 * pause, 5.0)


@app.task(name=RUN_JOB)
def run_job(job_id: str) -> str:
    """Run job `job_id`. Idempotent: a job delivered again after it finished is left as it is,
    and one delivered again mid-run (its worker died) runs again and rewrites the same files."""
    s = settings()
    store = JobStore(s)
    worker = run_job.request.hostname or socket.gethostname()
    record = _take(store, job_id, worker)
    if record is None:
        # Finished already (or removed), running on a live worker, or a cancel was asked while it
        # ran on a worker that died.
        if _stored(lambda: store.cancel_requested(job_id)):
            _stored(lambda: store.finish(job_id, CANCELLED))
        return "not started"
    start = last_write = last_poll = time.monotonic()  # a job shorter than PROGRESS_SECONDS writes none

    def progress(fraction: float) -> None:
        nonlocal last_write
        if time.monotonic() - last_write >= PROGRESS_SECONDS:
            last_write = time.monotonic()
            try:
                store.set_progress(job_id, round(fraction, 4))
            except StoreUnavailable:
                pass  # progress is for show; the job's end waits for the database

    def cancelled() -> bool:
        nonlocal last_poll
        if time.monotonic() - start > s.job_time_limit:
            raise TimeLimitExceeded
        if time.monotonic() - last_poll < CANCEL_POLL_SECONDS:
            return False
        last_poll = time.monotonic()
        try:
            return store.cancel_requested(job_id)
        except StoreUnavailable:
            return False

    work = _run if record["kind"] == RUN else _study
    try:
        with _beating(store, job_id, worker):
            solver_seconds, node_steps = work(store, job_id, progress, cancelled)
    except Cancelled:
        return _end(store, job_id, CANCELLED)
    except TimeLimitExceeded:
        return _end(
            store,
            job_id,
            FAILED,
            f"the job ran past its time limit of {s.job_time_limit:g} s "
            "(PERCUSSIM_JOB_TIME_LIMIT): use a coarser grid or a shorter duration",
        )
    except CaseError as error:
        return _end(store, job_id, FAILED, "the solver refused the case: " + str(error))
    except NumericalFailure as error:
        return _end(store, job_id, FAILED, str(error))
    except OSError as error:  # the disk is full, a file size limit is reached
        store.remove_results(job_id)
        remove_partial(store.result_path(job_id))
        return _end(
            store, job_id, FAILED, f"its results could not be written: {_reason(error)}; nothing of them was kept"
        )
    return _end(
        store,
        job_id,
        SUCCEEDED,
        progress=1.0,
        result_bytes=store.size(job_id),
        then=job_observations(time.monotonic() - start, solver_seconds, node_steps),
    )


def _take(store: JobStore, job_id: str, worker: str) -> dict | None:
    """The job started on `worker` (`JobStore.start`), or None. A message delivered while the job's
    beat is still fresh (its worker died within the last ALIVE_WITHIN s, or the job was queued
    again from its record while its own message waited) waits for the beat to lapse: a dead
    worker's job then runs here, a live worker's is not run twice."""
    deadline = time.monotonic() + ALIVE_WITHIN + HEARTBEAT_SECONDS
    while (record := _stored(lambda: store.start(job_id, worker))) is None:
        if time.monotonic() > deadline or not _stored(lambda: store.held(job_id)):
            return None
        time.sleep(HEARTBEAT_SECONDS / 5)
    return record


@contextmanager
def _beating(store: JobStore, job_id: str, worker: str) -> Iterator[None]:
    """The job's beat renewed every HEARTBEAT_SECONDS while the block runs it here, until the worker
    hands it back (`app.handing_back`). A thread: the kernel returns to Python every few ms."""
    stop = threading.Event()

    def renew():
        while not stop.wait(HEARTBEAT_SECONDS) and not handing_back.is_set():
            try:
                store.renew(job_id, worker)
            except (StoreUnavailable, StoreFull):
                pass  # a beat missed; recovery waits far longer than a few missed beats

    thread = threading.Thread(target=renew, name="percussim-beat", daemon=True)
    thread.start()
    try:
        yield
    finally:
        stop.set()
        thread.join()


def _reason(error: OSError) -> str:
    # h5py's own text names its temporary file and buffers: the system's words say it all.
    return os.strerror(error.errno) if error.errno else str(error)


def _end(store: JobStore, job_id: str, status: str, error: str | None = None, **values) -> str:
    """Finish the job as `status` (`JobStore.complete`), waiting for the database if it is away."""
    return _stored(lambda: store.complete(job_id, status, error, **values))


def _run(
    store: JobStore, job_id: str, progress: Callable[[float], None], cancelled: Callable[[], bool]
) -> tuple[float, float]:
    """A run: the solver on the job's case, its result streamed to the job's folder. Returns the
    solver's seconds and node-steps."""
    # A run streams its result to a temporary file renamed when complete; one whose worker died
    # left its temporary file behind.
    remove_partial(store.result_path(job_id))
    start = time.monotonic()
    result = simulate(
        parse_case(store.case(job_id)),
        progress=progress,
        cancelled=cancelled,
        limits=settings().limits(),
        result_path=store.result_path(job_id),
    )
    seconds = time.monotonic() - start
    store.write_summary(job_id, result.summary_json)
    return seconds, sum((run["cells"] + 1) * run["steps"] for run in result.summary["runs"])


def _study(
    store: JobStore, job_id: str, progress: Callable[[float], None], cancelled: Callable[[], bool]
) -> tuple[float, float]:
    """A study: its batches spread over the live workers."""
    s = settings()
    kind = _stored(lambda: store.get(job_id))["kind"]
    solve, plot = STUDIES[kind], STUDY_PLOT[kind]
    workers = len(WorkerRegistry(s.results_dir).alive(within=ALIVE_WITHIN)) or 1
    evaluator = QueueEvaluator(
        store.batches(job_id),
        lambda batch, index: evaluate_part.apply_async(args=[job_id, batch, index], ignore_result=True),
        workers,
    )
    try:
        answer = solve(
            store.request(job_id), evaluator=evaluator, progress=progress, cancelled=cancelled, limits=s.limits()
        )
    finally:
        evaluator.close()
    answer["runs_spread"] = evaluator.runs
    store.write_answer(job_id, answer)
    name = store.case(job_id).get("name") or "case"
    for fmt in ("png", "svg"):
        store.write_plot(job_id, plot, fmt, render_study(answer, plot, fmt, name=name))
    return 0.0, 0.0  # its runs are spread over workers: not one solver's time


@app.task(name=EVALUATE_PART)
def evaluate_part(job_id: str, batch: int, index: int) -> bool:
    """Run part `index` of batch `batch` of study `job_id`, unless the study or another worker
    has, or the study is over."""
    try:
        folder = JobStore(settings()).batches(job_id)
    except UnknownJob:
        return False
    return take_part(folder / str(int(batch)), int(index))
