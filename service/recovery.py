"""Jobs whose worker died run again, even where the broker lost their message.

Celery delivers a dead worker's job again after the redelivery time (`PERCUSSIM_REDELIVERY_SECONDS`),
and an embedded service queues again the jobs of a worker it saw die (`service.main`). A message can
still be lost (Redis and a worker cut while it hands its messages back, Celery's issue #4354). So a
job recorded running whose beat has lapsed for longer than the redelivery time and
`RESTORE_MARGIN` (by then Celery would have delivered it again) is queued again from its record by
a thread beside the API (`background`); one whose worker died under it `MAX_ATTEMPTS` times fails,
saying so: a case that kills its worker must not kill every worker in turn. A job queued that long
whose message the broker does not hold is published again too, however many others wait. A
message the broker did keep as well is harmless: a worker delivered a job that another runs, with
a fresh beat, does not run it (`worker.tasks._take`). Every change is conditional, so API
replicas doing the same queue each job once.
"""

from __future__ import annotations

import logging
from datetime import datetime, timedelta

from percussim.common.settings import Settings
from percussim.common.store import FAILED, JobStore, now

from .queue import JobQueue

MAX_ATTEMPTS = 3  # runs of a job whose worker died under it, before the job is failed
RESTORE_MARGIN = 15.0  # s: the broker's sweep of unacknowledged messages (5 s) and a heartbeat (5 s), and slack
log = logging.getLogger("percussim.recovery")


def requeue_or_fail(
    jobs: JobStore, job_id: str, worker: str, death: str, lapsed_before: datetime | None = None
) -> bool:
    """Record as queued again the job the dead `worker` was running (`death` says how it died; with
    `lapsed_before`, only if it has had no beat since), or as failed if it died under it
    MAX_ATTEMPTS times. True if it is queued again: the caller publishes it."""
    attempts = jobs.get(job_id)["attempts"]
    if attempts >= MAX_ATTEMPTS:
        jobs.finish(
            job_id,
            FAILED,
            error=(
                f"its worker died {attempts} times while running it (the last time: {death}): "
                "a case that needs more memory than the machine has, or a crash; try a coarser grid "
                "or fewer outputs"
            ),
        )
        return False
    return jobs.requeue(job_id, worker, lapsed_before)


def silence(settings: Settings) -> float:
    """Seconds without a beat after which a running job is queued again from its record."""
    return settings.redelivery + RESTORE_MARGIN


def recover(settings: Settings) -> list[str]:
    """One pass: queue again the running jobs silent for longer than `silence`, then the queued
    jobs whose message is lost (`_unpublished`); returns their ids (none if the broker could not
    take them: they are then failed, saying why)."""
    jobs = JobStore(settings)
    before = now() - timedelta(seconds=silence(settings))
    death = f"no sign of life for more than {silence(settings):g} s"
    again = []
    for job_id, worker in jobs.lapsed(before):
        if requeue_or_fail(jobs, job_id, worker, f"{worker}: {death}", lapsed_before=before):
            again.append(job_id)
            log.warning("job %s was running on %s, %s: queued again", job_id, worker, death)
    queue = JobQueue(settings)
    again += _unpublished(jobs, queue, before)  # those just queued again are not among them
    failure = "its worker died or its message was lost, and it could not be queued again"
    if again and queue.enqueue_or_fail(jobs, again, failure) is not None:
        return []
    return again


def _unpublished(jobs: JobStore, queue: JobQueue, before: datetime) -> list[str]:
    """The jobs queued since before then whose message the broker does not hold: theirs were lost
    (a broker that lost its last writes), for a worker that takes a message starts its job at
    once. The jobs are read before the messages, so that a message taken in between is counted
    lost, never a lost one held: its job is then published twice, which is harmless. Each is
    marked queued again now, by one caller of several."""
    waiting = jobs.unpublished(before)
    if not waiting:
        return []
    held = queue.held()
    again = [job_id for job_id in waiting if job_id not in held and jobs.queued_again(job_id, before)]
    for job_id in again:
        log.warning("job %s waited queued with no message in the broker: queued again", job_id)
    return again


def interval(settings: Settings) -> float:
    """Seconds between passes: a small part of the silence (or half a minute)."""
    return min(max(silence(settings) / 8, 1.0), 30.0)
