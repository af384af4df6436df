"""What the workers count for the metrics: histograms of a job's time and of the solver's time
per node-step, kept in the database (`database.counters`) so that the counts of every worker on
every machine add up, and read back by the API's `/metrics`.

A histogram is its buckets' counts (each observation counted once, in the first bucket that
holds it), its sum and its count; the reader makes the buckets cumulative.
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Callable

from sqlalchemy import select
from sqlalchemy.dialects import postgresql, sqlite
from sqlalchemy.engine import Connection

from .database import counters, database
from .settings import Settings
from .store import translated

# name → bucket upper bounds
HISTOGRAMS = {
    "job_seconds": (0.01, 0.03, 0.1, 0.3, 1.0, 3.0, 10.0, 30.0, 100.0, 300.0, 1000.0),
    "solver_seconds_per_node_step": (1e-9, 2e-9, 5e-9, 1e-8, 2e-8, 5e-8, 1e-7, 1e-6),
}


def job_observations(seconds: float, solver_seconds: float, node_steps: float) -> Callable[[Connection], None]:
    """What a succeeded job adds to the counters (its time in the worker and, for a run, the
    solver's time per node-step), to write in the transaction that records its success: counted
    once, with it."""

    def write(connection: Connection) -> None:
        observe(connection, "job_seconds", seconds)
        if node_steps > 0:
            observe(connection, "solver_seconds_per_node_step", solver_seconds / node_steps)

    return write


def observe(connection: Connection, name: str, value: float) -> None:
    bounds = HISTOGRAMS[name]
    index = bisect.bisect_left(bounds, value)
    bucket = str(bounds[index]) if index < len(bounds) else "+Inf"
    insert = (postgresql if connection.dialect.name == "postgresql" else sqlite).insert
    for key, amount in ((bucket, 1.0), ("sum", value), ("count", 1.0)):
        statement = insert(counters).values(name=name, key=key, value=amount)
        connection.execute(
            statement.on_conflict_do_update(index_elements=["name", "key"], set_={"value": counters.c.value + amount})
        )


class Counters:
    """The counters as the API reads them."""

    def __init__(self, settings: Settings):
        self.settings = settings

    def histogram(self, name: str) -> tuple[list[tuple[str, float]], float]:
        """([(upper bound, cumulative count)] ending with +Inf, sum)."""
        with translated(), database(self.settings).connect() as connection:
            values = dict(
                connection.execute(select(counters.c.key, counters.c.value).where(counters.c.name == name)).all()
            )
        total, buckets = 0.0, []
        for bound in (*HISTOGRAMS[name], math.inf):
            key = "+Inf" if bound == math.inf else str(bound)
            total += values.get(key, 0.0)
            buckets.append((key, total))
        return buckets, values.get("sum", 0.0)
