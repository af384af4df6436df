"""The job task: run a stored job, by its kind, and store its status and answer.

A run (`kind` 'run') is the solver on its case, storing the summary and the HDF5 result. A
calibration or an optimisation runs its study, spreading its batches of runs over the workers
(`fanout`), and stores its answer and plot. Each shares the same life: queued → running →
succeeded, failed or cancelled, with progress, cancel and the time limit.
"""

from __future__ import annotations

import socket
import time
from typing import Callable

from percussim.solver.calibrate import calibrate
from percussim.solver.case import CaseError, parse_case
from percussim.solver.errors import Cancelled, NumericalFailure
from percussim.solver.io import remove_partial
from percussim.solver.optimize import optimize
from percussim.solver.simulate import simulate
from percussim.solver.study_plots import render_study

from .app import app
from .broker import EVALUATE_PART, RUN_JOB
from .fanout import QueueEvaluator, take_part
from .settings import settings
from .store import (CALIBRATION, CANCELLED, FAILED, FINISHED, OPTIMIZATION, RUN, RUNNING,
                    SUCCEEDED, JobStore, UnknownJob, WorkerRegistry, now)

PROGRESS_SECONDS = 0.25  # how often a running job's progress is written
ALIVE_WITHIN = 15.0  # s: workers whose heartbeat is this recent may take a study's parts
STUDIES = {CALIBRATION: (calibrate, "fit"), OPTIMIZATION: (optimize, "convergence")}


class TimeLimitExceeded(Exception):
    pass


@app.task(name=RUN_JOB)
def run_job(job_id: str) -> str:
    """Run job `job_id`. Idempotent: a job delivered again after it finished is left as it is,
    and one delivered again mid-run (its worker died) runs again and rewrites the same files."""
    s = settings()
    store = JobStore(s.results_dir)
    record = store.get(job_id)
    if record["status"] in FINISHED:
        return record["status"]
    if store.cancel_requested(job_id):
        store.update(job_id, status=CANCELLED, finished=now())
        return CANCELLED
    store.update(job_id, status=RUNNING, started=now(), attempts=record["attempts"] + 1,
                 worker=run_job.request.hostname or socket.gethostname(), progress=0.0)
    start = last_write = time.monotonic()  # a job shorter than PROGRESS_SECONDS writes none

    def progress(fraction: float) -> None:
        nonlocal last_write
        if time.monotonic() - last_write >= PROGRESS_SECONDS:
            store.update(job_id, progress=round(fraction, 4))
            last_write = time.monotonic()

    def cancelled() -> bool:
        if time.monotonic() - start > s.job_time_limit:
            raise TimeLimitExceeded
        return store.cancel_requested(job_id)

    work = _run if record.get("kind", RUN) == RUN else _study
    try:
        work(store, job_id, progress, cancelled)
    except Cancelled:
        store.update(job_id, status=CANCELLED, finished=now())
        return CANCELLED
    except TimeLimitExceeded:
        return _fail(store, job_id, f"the job ran past its time limit of {s.job_time_limit:g} s "
                                    "(PERCUSSIM_JOB_TIME_LIMIT): use a coarser grid or a shorter duration")
    except CaseError as error:
        return _fail(store, job_id, "the solver refused the case: " + str(error))
    except NumericalFailure as error:
        return _fail(store, job_id, str(error))
    store.update(job_id, status=SUCCEEDED, progress=1.0, finished=now())
    return SUCCEEDED


def _run(store: JobStore, job_id: str, progress: Callable[[float], None],
         cancelled: Callable[[], bool]) -> None:
    """A run: the solver on the job's case, its result streamed to the job's folder."""
    # A run streams its result to a temporary file renamed when complete; one whose worker died
    # left its temporary file behind.
    remove_partial(store.result_path(job_id))
    result = simulate(parse_case(store.case(job_id)), progress=progress, cancelled=cancelled,
                      limits=settings().limits(), result_path=store.result_path(job_id))
    store.write_summary(job_id, result.summary_json)


def _study(store: JobStore, job_id: str, progress: Callable[[float], None],
           cancelled: Callable[[], bool]) -> None:
    """A calibration or an optimisation: its batches spread over the live workers."""
    s = settings()
    solve, plot = STUDIES[store.get(job_id)["kind"]]
    workers = len(WorkerRegistry(s.results_dir).alive(within=ALIVE_WITHIN)) or 1
    evaluator = QueueEvaluator(store.batches(job_id), lambda batch, index: evaluate_part.apply_async(
        args=[job_id, batch, index], ignore_result=True), workers)
    try:
        answer = solve(store.request(job_id), evaluator=evaluator, progress=progress,
                       cancelled=cancelled, limits=s.limits())
    finally:
        evaluator.close()
    answer["runs_spread"] = evaluator.runs
    store.write_answer(job_id, answer)
    name = store.case(job_id).get("name") or "case"
    for fmt in ("png", "svg"):
        store.write_plot(job_id, plot, fmt, render_study(answer, plot, fmt, name=name))


@app.task(name=EVALUATE_PART)
def evaluate_part(job_id: str, batch: int, index: int) -> bool:
    """Run part `index` of batch `batch` of study `job_id`, unless the study or another worker
    has, or the study is over."""
    try:
        folder = JobStore(settings().results_dir).batches(job_id)
    except UnknownJob:
        return False
    return take_part(folder / str(int(batch)), int(index))


def _fail(store: JobStore, job_id: str, reason: str) -> str:
    store.update(job_id, status=FAILED, finished=now(), error=reason)
    return FAILED
