"""The job task: run the solver on a stored case and store its status, summary and result."""

from __future__ import annotations

import socket
import time

from percussim.solver.case import CaseError, parse_case
from percussim.solver.errors import Cancelled, NumericalFailure
from percussim.solver.io import remove_partial
from percussim.solver.simulate import simulate

from .app import app
from .broker import RUN_JOB
from .settings import settings
from .store import CANCELLED, FAILED, FINISHED, RUNNING, SUCCEEDED, JobStore, now

PROGRESS_SECONDS = 0.25  # how often a running job's progress is written


class TimeLimitExceeded(Exception):
    pass


@app.task(name=RUN_JOB)
def run_job(job_id: str) -> str:
    """Solve job `job_id`. Idempotent: a job delivered again after it finished is left as it is,
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

    # A run streams its result to a temporary file renamed when complete; one whose worker died
    # left its temporary file behind.
    remove_partial(store.result_path(job_id))
    try:
        result = simulate(parse_case(store.case(job_id)), progress=progress, cancelled=cancelled,
                          limits=s.limits(), result_path=store.result_path(job_id))
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
    store.write_summary(job_id, result.summary_json)
    store.update(job_id, status=SUCCEEDED, progress=1.0, finished=now())
    return SUCCEEDED


def _fail(store: JobStore, job_id: str, reason: str) -> str:
    store.update(job_id, status=FAILED, finished=now(), error=reason)
    return FAILED
