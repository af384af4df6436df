"""Retention (`PERCUSSIM_RESULT_TTL`): finished jobs and sweeps older than that are deleted with
their files, by a thread beside the API, a batch at a time, so requests never wait for it. Every
deletion is conditional, so API replicas doing the same at once delete each job once."""

from __future__ import annotations

import logging
import threading
from contextlib import asynccontextmanager
from datetime import timedelta

from percussim.common.settings import Settings
from percussim.common.store import JobStore, StoreFull, StoreUnavailable, SweepStore, now

BATCH = 200  # jobs or sweeps deleted per query
log = logging.getLogger("percussim.retention")


def delete_expired(settings: Settings) -> tuple[int, int]:
    """One pass: delete what finished more than `result_ttl` seconds ago. Returns (jobs, sweeps)."""
    cutoff = now() - timedelta(seconds=settings.result_ttl)
    jobs = JobStore(settings)
    sweeps = SweepStore(jobs)
    counts = [0, 0]
    for k, (store, remove) in enumerate(((jobs, jobs.delete), (sweeps, sweeps.purge))):
        while batch := store.expired(cutoff, BATCH):
            counts[k] += sum(remove(item) for item in batch)
            if len(batch) < BATCH:
                break
    return counts[0], counts[1]


def interval(settings: Settings) -> float:
    """Seconds between passes: often enough that nothing outlives its time by more than half of it
    (or a minute)."""
    return min(max(settings.result_ttl / 2, 0.5), 60.0)


def lifespan(settings: Settings):
    """The app's lifespan: the retention thread while the API runs, if a TTL is set."""

    @asynccontextmanager
    async def running(app):
        stop = threading.Event()
        if settings.result_ttl:

            def work():
                while not stop.wait(interval(settings)):
                    try:
                        removed = delete_expired(settings)
                    except (StoreUnavailable, StoreFull) as error:
                        log.warning("retention: %s; trying again later", error)
                        continue
                    if any(removed):
                        log.info("retention: deleted %d job(s) and %d sweep(s)", *removed)

            thread = threading.Thread(target=work, name="percussim-retention", daemon=True)
            thread.start()
        try:
            yield
        finally:
            stop.set()

    return running
