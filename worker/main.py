"""`percussim worker`: a queue worker process (prefork, one job at a time per child)."""

from __future__ import annotations

import socket

from percussim.common.settings import settings


def run_worker(concurrency: int = 1, loglevel: str = "info", name: str | None = None) -> None:
    from .app import app

    argv = [
        "worker",
        "--concurrency",
        str(concurrency),
        "--loglevel",
        loglevel,
        "--pool",
        "prefork",
        "--hostname",
        name or f"percussim@{socket.gethostname()}",
    ]
    if settings().embedded:
        argv += ["--without-gossip", "--without-mingle", "--without-heartbeat"]
    app.worker_main(argv)
