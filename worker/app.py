"""The Celery app, configured from the environment (`common.settings`).

Jobs are acknowledged late and rejected when their worker is lost, so a job whose worker dies is
delivered again; each worker process takes one job at a time.
"""

from __future__ import annotations

import threading

from celery import Celery
from celery.signals import worker_init, worker_ready, worker_shutdown

from percussim.common.broker import broker_config, queue_folder
from percussim.common.settings import Settings, settings
from percussim.common.store import WorkerRegistry

HEARTBEAT_SECONDS = 5.0


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


@worker_init.connect
def _load_kernel(**_):
    """Load the compiled kernel from Numba's cache in the parent process, before the pool forks:
    every child starts with it, and a fresh worker's first job pays no loading."""
    from percussim.solver.controller import warm_up

    warm_up()


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
