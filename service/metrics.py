"""`GET /metrics` in Prometheus' text format (prometheus-client): jobs by status, the broker's queue
depth, histograms of a job's time and of the solver's time per node-step (counted by the workers
in the database, `common.metrics`), and the results' disk use. Read at each scrape, so every API
replica answers the same."""

from __future__ import annotations

import math
import shutil

from fastapi import APIRouter
from fastapi.responses import Response
from prometheus_client import CONTENT_TYPE_LATEST, CollectorRegistry, generate_latest
from prometheus_client.core import GaugeMetricFamily, HistogramMetricFamily
from prometheus_client.registry import Collector

from percussim.common.metrics import Counters
from percussim.common.settings import Settings
from percussim.common.store import STATUSES, JobStore

from .queue import BROKER_ERRORS, JobQueue

HISTOGRAMS = {
    "job_seconds": ("percussim_job_duration_seconds", "time a succeeded job ran in its worker"),
    "solver_seconds_per_node_step": (
        "percussim_solver_seconds_per_node_step",
        "the solver's time per node-step of a succeeded run",
    ),
}


class _Service(Collector):
    def __init__(self, settings: Settings, queue: JobQueue):
        self.settings, self.queue = settings, queue

    def collect(self):
        jobs = JobStore(self.settings)
        counts = jobs.counts()
        by_status = GaugeMetricFamily("percussim_jobs", "jobs in the database, by status", labels=["status"])
        for status in STATUSES:
            by_status.add_metric([status], counts.get(status, 0))
        yield by_status
        try:
            depth = self.queue.depth()
        except BROKER_ERRORS:
            depth = math.nan  # the broker is away: /readyz says so; the other metrics still count
        yield GaugeMetricFamily("percussim_queue_depth", "messages waiting in the broker for a worker", value=depth)
        counters = Counters(self.settings)
        for key, (name, documentation) in HISTOGRAMS.items():
            buckets, total = counters.histogram(key)
            yield HistogramMetricFamily(name, documentation, buckets=buckets, sum_value=total)
        yield GaugeMetricFamily(
            "percussim_results_bytes",
            "bytes of the finished jobs' files in the results store",
            value=jobs.result_bytes(),
        )
        yield GaugeMetricFamily(
            "percussim_results_disk_free_bytes",
            "free bytes on the results store's disk",
            value=shutil.disk_usage(self.settings.results_dir).free,
        )


def metrics_router(settings: Settings, queue: JobQueue) -> APIRouter:
    registry = CollectorRegistry(auto_describe=False)
    registry.register(_Service(settings, queue))
    router = APIRouter(tags=["health"])

    @router.get(
        "/metrics",
        response_class=Response,
        responses={200: {"content": {CONTENT_TYPE_LATEST: {}}, "description": "the metrics"}},
    )
    def metrics() -> Response:
        """The service's metrics, in Prometheus' text format."""
        return Response(generate_latest(registry), media_type=CONTENT_TYPE_LATEST)

    return router
