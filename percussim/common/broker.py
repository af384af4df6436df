"""Where jobs are queued, for given settings: shared by the workers and the API, no side effects.

With no broker URL the queue is Celery's filesystem transport under the results folder, each
message written whole before a worker can see it (`common.queue_files`); with one (Redis), the
transport options bound how long a dead connection can hold a caller.
"""

from __future__ import annotations

from pathlib import Path

from .settings import Settings

RUN_JOB = "percussim.run_job"  # the job task's name
EVALUATE_PART = "percussim.evaluate_part"  # a part of a study's batch of runs
CONNECT_TIMEOUT = 3.0  # seconds: an unreachable broker must not hold a request for long


def queue_folder(settings: Settings) -> Path:
    """The embedded broker's message folder."""
    return settings.broker_folder / "queue"


def broker_config(settings: Settings) -> dict:
    """Celery configuration of the broker the settings name."""
    if settings.embedded:
        folder = str(queue_folder(settings))
        return {
            "broker_url": "filesystem://",
            "broker_transport": "percussim.common.queue_files:Transport",
            # The control folder defaults to ./control: keep everything under the results folder.
            "broker_transport_options": {
                "data_folder_in": folder,
                "data_folder_out": folder,
                "control_folder": str(settings.broker_folder / "control"),
                "store_processed": False,
                "polling_interval": 0.05,
            },  # default 1 s: a second of latency
        }
    return {
        "broker_url": settings.broker_url,
        "broker_transport_options": {
            "visibility_timeout": settings.redelivery,  # a lost job is delivered again after this
            # and found within 5 s of it (kombu's default sweep is every 100 s)
            "unacked_restore_interval": 5,
            "unacked_restore_throttle": 1,
            "socket_connect_timeout": CONNECT_TIMEOUT,
            "socket_timeout": CONNECT_TIMEOUT,
        },
    }
