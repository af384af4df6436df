"""The Celery app, configured from the environment (`common.settings`).

Jobs are acknowledged late and rejected when their worker is lost, so a job whose worker dies is
delivered again; each worker process takes one job at a time. A worker told to stop lets its
running job finish for `PERCUSSIM_STOP_GRACE` s, then stops it and puts it back on the queue
(`_stopping`), its beat lapsed (`JobStore.release`) for the next worker to take it at once. A
pool's child stops on its own worker's SIGTERM alone (`_stop_on_the_workers_signal_alone`).
"""

from __future__ import annotations

import os
import signal
import threading
from multiprocessing import get_context

from celery import Celery
from celery.signals import worker_init, worker_process_init, worker_ready, worker_shutdown, worker_shutting_down
from celery.utils.log import get_logger
from celery.worker.state import active_requests

from percussim.common.broker import RUN_JOB, broker_config, queue_folder
from percussim.common.settings import Settings, settings
from percussim.common.store import HEARTBEAT_SECONDS, JobStore, StoreFull, StoreUnavailable, WorkerRegistry

logger = get_logger(__name__)


def make_app(s: Settings) -> Celery:
    app = Celery("percussim", include=["percussim.worker.tasks"])
    app.conf.update(
        broker_config(s),
        **{
            "task_acks_late": True,
            "task_reject_on_worker_lost": True,
            "worker_prefetch_multiplier": 1,
            "task_time_limit": s.job_time_limit + 60,  # the hard stop behind the job's own limit
            "task_ignore_result": True,  # status and results live in the results store
            "broker_connection_retry_on_startup": True,
            # The filesystem transport cannot broadcast.
            "worker_enable_remote_control": not s.embedded,
        },
    )
    if s.embedded:
        queue_folder(s).mkdir(parents=True, exist_ok=True)
    return app


app = make_app(settings())
_stop = threading.Event()
# Set by the worker once it is stopping, seen by its pool's children (who inherit it at the fork).
_worker_stopping = get_context("fork").Event()
# Set once the worker hands its running jobs back: their processes stop renewing their beat.
handing_back = get_context("fork").Event()
FOREIGN_SIGTERM_WAIT = 1.0  # seconds a child, sent SIGTERM by another process, waits to see its worker stop too


@worker_init.connect
def _load_kernel(**_):
    """Load the compiled kernel from Numba's cache in the parent process, before the pool forks:
    every child starts with it, and a fresh worker's first job pays no loading."""
    from percussim.solver.controller import warm_up

    warm_up()


@worker_process_init.connect
def _stop_on_the_workers_signal_alone(**_):
    """A service manager may stop a service by SIGTERM to every one of its processes at once
    (systemd's default `KillMode=control-group`, `kill -TERM -PGID`). The worker then shuts down
    warm, letting its running job finish, but the pool's child running that job would die at once
    by the same signal: the job cut, run again, and the stop seconds longer. So a child blocks
    SIGTERM and a thread takes it: sent by the child's own worker (the pool's terminate, a hard
    time limit) or once that worker is gone, the child dies of it as before; sent by anyone else
    while the worker is stopping too (within `FOREIGN_SIGTERM_WAIT`), it is left to the worker,
    which stops the child when its job is done; sent by anyone else alone (someone stopping a
    runaway job's process by hand), the child dies of it. (Where the system cannot tell a
    signal's sender, `sigwaitinfo` is missing, as on macOS, the child keeps Celery's own
    handling.)"""
    if not hasattr(signal, "sigwaitinfo"):
        return
    worker = os.getppid()
    signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGTERM})  # in this thread and all it starts

    def take_sigterm():
        while True:
            sender = signal.sigwaitinfo({signal.SIGTERM}).si_pid
            if sender != worker and os.getppid() == worker and _worker_stopping.wait(FOREIGN_SIGTERM_WAIT):
                continue  # a stop sent to every process: the worker's own
            signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGTERM})
            signal.raise_signal(signal.SIGTERM)  # its default action: the child dies of it

    threading.Thread(target=take_sigterm, name="percussim-sigterm", daemon=True).start()


@worker_shutting_down.connect
def _stopping(how: str, **_):
    """The worker starts stopping. Its pool's children learn it: a SIGTERM they get from elsewhere
    meanwhile is this same stop's (`_stop_on_the_workers_signal_alone`). And Celery's warm
    shutdown (SIGTERM, a first Ctrl-C), which waits for the running job however long it takes, is
    given `stop_grace` s: then the worker asks itself for a cold shutdown (SIGQUIT), the job is
    stopped and, acknowledged late, goes back on the queue at once, for another worker or the
    service's next start. A service manager's own limit (systemd's `TimeoutStopSec`, Docker's
    `stop_grace_period`) longer than the grace then never kills a worker in its job, whose message
    would wait for the redelivery time."""
    first = not _worker_stopping.is_set()  # not a second SIGTERM (the group's and the service's)
    _worker_stopping.set()
    if how != "Warm" or not first:
        return
    grace = settings().stop_grace
    timer = threading.Timer(grace, _cut_after_the_grace, args=(grace,))
    timer.daemon = True  # an idle worker exits at once, not at the grace
    timer.start()


def _cut_after_the_grace(grace: float):
    """The grace is over and the worker still runs: say why, by the jobs it still runs (a study's
    part is its study's), hand its jobs back (their beat lapsed, for the next worker delivered one
    to take it at once: `JobStore.release`), then shut down cold."""
    requests = list(active_requests)
    running = sorted({str(request.args[0]) for request in requests if request.args})
    for job_id in running:
        logger.warning(
            "the running job %s outlasted PERCUSSIM_STOP_GRACE (%g s): stopping it; it goes back on the queue",
            job_id,
            grace,
        )
    if not running:
        logger.warning("no job running, yet not stopped after PERCUSSIM_STOP_GRACE (%g s): stopping now", grace)
    handing_back.set()
    try:
        jobs = JobStore(settings())
        for request in requests:
            if request.name == RUN_JOB and request.args:
                jobs.release(str(request.args[0]), request.hostname)
    except (StoreUnavailable, StoreFull) as error:
        logger.warning("the jobs handed back are taken again once their beat lapses: %s", error)
    os.kill(os.getpid(), signal.SIGQUIT)


@worker_ready.connect
def _start_heartbeat(sender, **_):
    registry = WorkerRegistry(settings().results_dir)
    name = sender.hostname

    def beat():
        while not _stop.is_set():
            registry.beat(name)
            _stop.wait(HEARTBEAT_SECONDS)

    threading.Thread(target=beat, name="percussim-heartbeat", daemon=True).start()


@worker_shutdown.connect
def _stop_heartbeat(**_):
    _stop.set()
