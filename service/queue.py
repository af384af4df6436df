"""The service's side of the job queue: publish a job, tell which jobs the broker holds and whether
it is reachable.

The API only publishes; it never imports the worker's Celery app, whose module configures itself
from the environment when imported. Publishing with an app made from the service's own settings
keeps `create_app(Settings(...))` on the broker those settings name (tests use a temporary
folder); `common.broker` gives both sides the same broker configuration.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import redis.exceptions
from celery import Celery, group
from kombu.exceptions import OperationalError
from kombu.utils.url import maybe_sanitize_url

from percussim.common.broker import CONNECT_TIMEOUT, RUN_JOB, broker_config, queue_folder
from percussim.common.settings import Settings
from percussim.common.store import FAILED, JobStore

# What publishing raises when the broker cannot be reached (kombu wraps most of them).
BROKER_ERRORS = (OperationalError, redis.exceptions.ConnectionError, redis.exceptions.TimeoutError, OSError)


class JobQueue:
    """Publishes `percussim.run_job` messages to the broker the workers consume."""

    def __init__(self, settings: Settings):
        self.settings = settings
        self.app = Celery("percussim-api", set_as_current=False)
        self.app.conf.update(broker_config(settings))

    @property
    def queue_folder(self) -> Path:
        """The embedded broker's message folder."""
        return queue_folder(self.settings)

    def describe(self) -> str:
        """The broker in words, with any password masked."""
        if self.settings.embedded:
            return f"embedded (filesystem broker in {self.settings.broker_folder})"
        return maybe_sanitize_url(self.settings.broker_url)

    def _folder_made(self) -> None:
        if self.settings.embedded:
            # The worker creates the folder too; the API may be up before any worker is.
            self.queue_folder.mkdir(parents=True, exist_ok=True)

    def enqueue(self, *job_ids: str) -> None:
        """Publish the jobs, fanned out over the workers as one Celery group; raises one of
        `BROKER_ERRORS` if the broker cannot take them."""
        self._folder_made()
        group(self.app.signature(RUN_JOB, args=[job_id], ignore_result=True) for job_id in job_ids).apply_async()

    def purge(self) -> int:
        """Drop every message waiting in the queue; returns how many."""
        self._folder_made()
        return self.app.control.purge()

    def enqueue_or_fail(self, jobs: JobStore, job_ids: list[str], failure: str) -> Exception | None:
        """Publish the jobs; if the broker cannot take them, record in each that it failed
        (`failure`: why it could not run, before the broker's error) rather than leave it
        queued forever, and return the broker's error."""
        try:
            self.enqueue(*job_ids)
        except BROKER_ERRORS as error:
            for job_id in job_ids:
                jobs.finish(job_id, FAILED, error=f"{failure}: {error}")
            return error
        return None

    def depth(self) -> int:
        """Messages waiting in the queue for a worker."""
        self._folder_made()
        with self.app.connection_for_read() as connection:
            # Declared, not only looked up: before the first message there is no queue yet.
            return connection.default_channel.queue_declare(self.app.conf.task_default_queue).message_count

    def held(self) -> set[str]:
        """The jobs whose messages the broker holds: waiting for a worker, or (Redis) delivered to
        one and not yet acknowledged, which Redis keeps apart until the job ends. kombu has no way
        to look at a queue without taking from it, so each transport's store is read as kombu
        keeps it: the embedded queue's files, Redis's lists (one for each priority) and its hash of
        unacknowledged messages."""
        self._folder_made()
        queue = self.app.conf.task_default_queue
        with self.app.connection_for_read() as connection:
            channel = connection.default_channel
            if self.settings.embedded:
                payloads = []
                for path in self.queue_folder.glob(f"*.{queue}.msg"):
                    try:
                        payloads.append(json.loads(path.read_bytes()))
                    except FileNotFoundError:  # a worker took it meanwhile
                        continue
            else:
                client = channel.client
                keys = {channel._q_for_pri(queue, priority) for priority in channel.priority_steps}
                payloads = [json.loads(raw) for key in keys for raw in client.lrange(key, 0, -1)]
                payloads += [json.loads(raw)[0] for raw in client.hvals(channel.unacked_key)]
            return {
                channel.Message(payload, channel=channel).decode()[0][0]
                for payload in payloads
                if payload["headers"].get("task") == RUN_JOB
            }

    def problem(self) -> str | None:
        """Why the broker cannot be reached now, or None if it can."""
        if self.settings.embedded:
            folder = self.queue_folder
            if not (folder.is_dir() and os.access(folder, os.W_OK)):
                return f"the embedded broker folder {folder} is missing or not writable"
            return None
        try:
            with self.app.connection_for_write() as connection:
                connection.ensure_connection(max_retries=1, interval_start=0, timeout=CONNECT_TIMEOUT)
        except BROKER_ERRORS as error:
            return f"the broker {self.describe()} is unreachable: {error}"
        return None
