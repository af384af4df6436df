"""The database of job and sweep records: SQLite in the results folder by default, PostgreSQL when
`PERCUSSIM_DATABASE_URL` names one; one code path (SQLAlchemy Core), the schema kept by Alembic.

A process opens each database once (`database`), which brings its schema up to date under a lock
(a file lock beside an SQLite file, an advisory lock on PostgreSQL), so that the API and its
workers starting together migrate it once. The first migration from a store that kept its records
in folders imports them (`migrations/versions/0002_*`).
"""

from __future__ import annotations

import fcntl
import os
from collections.abc import Iterator
from contextlib import contextmanager
from functools import lru_cache
from pathlib import Path

from sqlalchemy import (
    JSON,
    BigInteger,
    Boolean,
    Column,
    DateTime,
    Float,
    Index,
    Integer,
    MetaData,
    String,
    Table,
    Text,
    create_engine,
    event,
    text,
)
from sqlalchemy.engine import Connection, Engine

from .settings import Settings

CONNECT_TIMEOUT = 3  # seconds: a database that is down must not hold a request for long
SQLITE_BUSY_SECONDS = 30  # how long a writer waits for another process's write to SQLite
MIGRATION_LOCK = 0x70657263  # PostgreSQL advisory lock key of the schema's migrations

metadata = MetaData()

jobs = Table(
    "jobs",
    metadata,
    Column("id", String(32), primary_key=True),
    Column("owner", String(64)),  # the API key's id; null without keys
    Column("name", Text),
    Column("kind", String(16), nullable=False),  # run, calibration, optimization, bearing_graph, drivability
    Column("status", String(16), nullable=False),
    Column("progress", Float, nullable=False),
    Column("created", DateTime(timezone=True), nullable=False),
    Column("started", DateTime(timezone=True)),
    Column("finished", DateTime(timezone=True)),
    Column("error", Text),
    Column("attempts", Integer, nullable=False),
    Column("worker", Text),
    Column("sweep", String(32)),  # the sweep it is a variant of
    Column("cancel_requested", Boolean, nullable=False),
    Column("result_bytes", BigInteger),  # its files' size once finished
    # A running job's last sign of life from its worker; a queued one's last queueing again.
    Column("beat", DateTime(timezone=True)),
    Index("ix_jobs_created", "created", "id"),
    Index("ix_jobs_owner_created", "owner", "created", "id"),
    Index("ix_jobs_status_created", "status", "created", "id"),
    Index("ix_jobs_name_created", "name", "created", "id"),
    Index("ix_jobs_sweep", "sweep"),
)

sweeps = Table(
    "sweeps",
    metadata,
    Column("id", String(32), primary_key=True),
    Column("owner", String(64)),
    Column("name", Text),
    Column("created", DateTime(timezone=True), nullable=False),
    Column("parameters", JSON, nullable=False),  # the swept paths
    Column("variants", JSON, nullable=False),  # [{"values": {...}, "job": id}]
    Index("ix_sweeps_created", "created"),
)

# Cumulative counters for the metrics (a histogram's buckets, sums and counts), kept here so that
# every worker on every machine adds to the same ones.
counters = Table(
    "counters",
    metadata,
    Column("name", String(64), primary_key=True),
    Column("key", String(32), primary_key=True),
    Column("value", Float, nullable=False),
)


def database(settings: Settings) -> Engine:
    """The engine of the settings' database, opened (and migrated) once per process."""
    # Looked up on every read and write of a record: by the settings as given, nothing resolved.
    return _open(settings.database_url, settings.results_dir)


@lru_cache
def _open(configured: str | None, results_dir: Path) -> Engine:
    """The configured database, else an SQLite file in the results folder."""
    results_dir = results_dir.resolve()
    url = configured or f"sqlite:///{results_dir / 'percussim.db'}"
    if url.startswith("sqlite"):
        results_dir.mkdir(parents=True, exist_ok=True)
        engine = create_engine(url, connect_args={"timeout": SQLITE_BUSY_SECONDS})
        event.listen(engine, "connect", _sqlite_pragmas)
    else:
        engine = create_engine(url, pool_pre_ping=True, connect_args={"connect_timeout": CONNECT_TIMEOUT})
    migrate(engine, results_dir)
    _engines.append(engine)
    return engine


def _sqlite_pragmas(connection, _record) -> None:
    # Readers do not wait for writers (the workers write progress while the API lists). A commit
    # is written, not synced: safe from a crashed process, and as safe from a power cut as the
    # results' own files (a sync a commit cost 1.2 ms of a submission's 1.5 ms in the store).
    cursor = connection.cursor()
    cursor.execute("PRAGMA journal_mode=WAL")
    cursor.execute("PRAGMA synchronous=NORMAL")
    cursor.close()


_engines: list[Engine] = []


def _dispose_after_fork() -> None:
    # A forked worker process must not share its parent's connections (SQLAlchemy's advice).
    for engine in _engines:
        engine.dispose(close=False)


os.register_at_fork(after_in_child=_dispose_after_fork)


def migrate(engine: Engine, results_dir: Path) -> None:
    """Bring the schema up to date (Alembic, to `head`): once, whoever else starts with us."""
    from alembic import command
    from alembic.config import Config

    config = Config()
    config.set_main_option("script_location", "percussim.common:migrations")
    with engine.connect() as connection, _migration_lock(connection):
        config.attributes |= {"connection": connection, "results_dir": results_dir}
        command.upgrade(config, "head")
        connection.commit()


@contextmanager
def _migration_lock(connection: Connection) -> Iterator[None]:
    if connection.dialect.name == "postgresql":
        connection.execute(text("SELECT pg_advisory_lock(:key)"), {"key": MIGRATION_LOCK})
        connection.commit()
        try:
            yield
        finally:
            connection.execute(text("SELECT pg_advisory_unlock(:key)"), {"key": MIGRATION_LOCK})
            connection.commit()
        return
    with open(f"{connection.engine.url.database}.migrate.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        yield
