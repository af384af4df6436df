"""Retention (`PERCUSSIM_RESULT_TTL`): finished jobs and sweeps older than that are deleted with
their files, by a thread beside the API (`background`), a batch at a time. Every deletion is
conditional, so API replicas doing the same at once delete each job once."""

from __future__ import annotations

import logging
from datetime import timedelta

from percussim.common.settings import Settings
from percussim.common.store import JobStore, SweepStore, now

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
    if any(counts):
        log.info("retention: deleted %d job(s) and %d sweep(s)", *counts)
    return counts[0], counts[1]


def interval(settings: Settings) -> float:
    """Seconds between passes: often enough that nothing outlives its time by more than half of it
    (or a minute)."""
    return min(max(settings.result_ttl / 2, 0.5), 60.0)
