"""The work beside the API, each a thread doing one pass every so often so that requests never wait
for it: retention (`retention`, when `PERCUSSIM_RESULT_TTL` is set) and the recovery of jobs whose
worker died (`recovery`)."""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable, Iterator
from contextlib import ExitStack, asynccontextmanager, contextmanager

from percussim.common.settings import Settings
from percussim.common.store import StoreFull, StoreUnavailable

from . import recovery, retention

log = logging.getLogger("percussim.background")


@contextmanager
def periodically(name: str, seconds: float, work: Callable[[], object]) -> Iterator[None]:
    """`work()` every `seconds` in a thread while the block runs; a pass that fails (the records
    unavailable, anything else) is logged, and the next one runs as planned."""
    stop = threading.Event()

    def loop():
        while not stop.wait(seconds):
            try:
                work()
            except (StoreUnavailable, StoreFull) as error:
                log.warning("%s: %s; trying again later", name, error)
            except Exception:  # a pass that fails must not end the passes to come
                log.exception("%s: the pass failed; trying again later", name)

    thread = threading.Thread(target=loop, name=f"percussim-{name}", daemon=True)
    thread.start()
    try:
        yield
    finally:
        stop.set()


def lifespan(settings: Settings):
    """The app's lifespan: the threads while the API runs."""

    @asynccontextmanager
    async def running(app):
        with ExitStack() as threads:
            if settings.result_ttl:
                threads.enter_context(
                    periodically("retention", retention.interval(settings), lambda: retention.delete_expired(settings))
                )
            threads.enter_context(
                periodically("recovery", recovery.interval(settings), lambda: recovery.recover(settings))
            )
            yield

    return running
