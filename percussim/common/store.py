"""The results store: each job's record in the database (`common.database`), its files in a folder
of its own under the results folder, readable by any process.

    jobs/<id>/case.json     the case as submitted
    jobs/<id>/request.json  a study's request (kind 'calibration', 'optimization',
                            'bearing_graph', 'drivability', 'signal_match'; a run's kind is 'run')
    jobs/<id>/answer.json   their answer, once succeeded
    jobs/<id>/batches/      their batches of runs while they are spread over the workers
    jobs/<id>/summary.json  the pulse summary, once succeeded
    jobs/<id>/result.h5     the HDF5 result, once succeeded
    jobs/<id>/plots/        plots of the result as rendered for the API: <name>.<png|svg>

A record changes only by conditional updates, each one statement: a job goes queued → running →
succeeded, failed or cancelled, and of a cancel and a finish racing only one wins (a finish does
not win once a cancel was asked). A finished job's record never changes again; it can only be
deleted, with its folder. A sweep's record lists its variants' values and jobs.

Every file is written to a temporary name and renamed, so a reader never sees half a file and a
job delivered twice writes the same files again instead of twice. Job ids are random and
checked against their pattern before any path is built from them. A store that cannot write
(a full disk, a file size limit) raises `StoreFull`; a database that cannot be reached,
`StoreUnavailable`.
"""

from __future__ import annotations

import errno
import json
import os
import re
import secrets
import shutil
import tempfile
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from datetime import UTC, datetime, timedelta
from pathlib import Path

from sqlalchemy import and_, delete, func, insert, or_, select, tuple_, update
from sqlalchemy.engine import Connection
from sqlalchemy.exc import DBAPIError, InterfaceError, OperationalError

from .database import database
from .database import jobs as JOBS
from .database import sweeps as SWEEPS
from .settings import Settings

QUEUED, RUNNING, SUCCEEDED, FAILED, CANCELLED = "queued", "running", "succeeded", "failed", "cancelled"
FINISHED = (SUCCEEDED, FAILED, CANCELLED)
STATUSES = (QUEUED, RUNNING, *FINISHED)
RUN, CALIBRATION, OPTIMIZATION = "run", "calibration", "optimization"  # a job's kind
BEARING_GRAPH, DRIVABILITY = "bearing_graph", "drivability"  # the pile studies' kinds
SIGNAL_MATCH = "signal_match"  # a pile's soil from its head's record
# The plot a succeeded study of each kind keeps (a name of `solver.study_plots.STUDY_PLOTS`): the
# worker draws it, the API serves it.
STUDY_PLOT = {
    CALIBRATION: "fit",
    OPTIMIZATION: "convergence",
    BEARING_GRAPH: "bearing_graph",
    DRIVABILITY: "drivability",
    SIGNAL_MATCH: "signal_match",
}
# A worker says it is alive every HEARTBEAT_SECONDS, and so does the process running a job, in the
# job's beat; three missed, and the worker (or the job's run) is taken for gone.
HEARTBEAT_SECONDS = 5.0
ALIVE_WITHIN = 3 * HEARTBEAT_SECONDS
_ID = re.compile(r"[A-Za-z0-9_-]{22}")
_PLOT_NAME = re.compile(r"[a-z_]+")


# What the disk or the database answers when nothing more can be written.
_FULL_ERRNOS = (errno.ENOSPC, errno.EFBIG, errno.EDQUOT)
_FULL_MESSAGES = ("database or disk is full", "disk i/o error", "could not extend file", "no space left")


class UnknownJob(KeyError):
    """No job has this id."""


class StoreFull(OSError):
    """The results store cannot write: its disk is full or a file size limit is reached."""


class StoreUnavailable(Exception):
    """The database of records cannot be reached."""


def now() -> datetime:
    return datetime.now(UTC)


def new_id() -> str:
    return secrets.token_urlsafe(16)  # 22 characters, 128 random bits


def _store_error(error: BaseException) -> BaseException:
    """The store's own error for what the disk or the database raised (else `error` itself)."""
    if isinstance(error, OSError) and error.errno in _FULL_ERRNOS:
        return StoreFull(error.errno, f"the results store cannot write: {error.strerror}")
    if isinstance(error, DBAPIError):
        reason = str(error.orig).strip().splitlines()[0] if error.orig else str(error)
        if any(m in reason.lower() for m in _FULL_MESSAGES) or getattr(error.orig, "sqlstate", "") == "53100":
            return StoreFull(errno.ENOSPC, f"the database cannot write: {reason}")
        if isinstance(error, (OperationalError, InterfaceError)) or error.connection_invalidated:
            return StoreUnavailable(f"the database is unavailable: {reason}")
    return error


@contextmanager
def translated() -> Iterator[None]:
    """Raise what the disk or the database raises in the block as `StoreFull` or `StoreUnavailable`."""
    try:
        yield
    except (OSError, DBAPIError) as error:
        mapped = _store_error(error)
        if mapped is error:
            raise
        raise mapped from error


def write_atomic(path: Path, data: bytes) -> None:
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".part", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


class JobStore:
    """The jobs; with an `owner` (an API key's id), only that owner's: others' are unknown."""

    def __init__(self, settings: Settings, owner: str | None = None):
        self.settings = settings
        self.jobs = settings.results_dir / "jobs"
        self.owner = owner

    @contextmanager
    def _connection(self, write: bool = False) -> Iterator[Connection]:
        """A connection to the records (a transaction committed at the end, to `write`)."""
        with translated():
            engine = database(self.settings)
            with engine.begin() if write else engine.connect() as connection:
                yield connection

    def _mine(self, condition):
        return condition if self.owner is None else and_(condition, JOBS.c.owner == self.owner)

    def folder(self, job_id: str) -> Path:
        if not isinstance(job_id, str) or not _ID.fullmatch(job_id):
            raise UnknownJob(job_id)
        return self.jobs / job_id

    def _new(self, job_id: str, case: dict, kind: str, request: dict | None, sweep: str | None) -> dict:
        """A new queued job's folder, written, and its record (not yet in the database)."""
        folder = self.jobs / job_id
        with translated():
            folder.mkdir(parents=True)
            write_atomic(folder / "case.json", json.dumps(case).encode())
            if request is not None:
                write_atomic(folder / "request.json", json.dumps(request).encode())
        return {
            "id": job_id,
            "owner": self.owner,
            "name": case.get("name"),
            "kind": kind,
            "status": QUEUED,
            "progress": 0.0,
            "created": now(),
            "started": None,
            "finished": None,
            "error": None,
            "attempts": 0,
            "worker": None,
            "sweep": sweep,
            "cancel_requested": False,
            "result_bytes": None,
            "beat": None,
        }

    def _create(
        self,
        new: list[tuple[str, dict, str, dict | None]],
        sweep: str | None = None,
        more: Callable[[Connection], None] | None = None,
    ) -> list[dict]:
        """New queued jobs, each (id, case, kind, request): their folders written, then their
        records (and whatever `more(connection)` adds) in one transaction. If anything fails,
        none of their folders is left."""
        try:
            rows = [self._new(*job, sweep) for job in new]
            with self._connection(write=True) as connection:
                connection.execute(insert(JOBS), rows)
                if more is not None:
                    more(connection)
        except BaseException:
            self._remove_folders(job_id for job_id, *_ in new)
            raise
        return rows

    def _remove_folders(self, job_ids: Iterable[str]) -> None:
        for job_id in job_ids:
            shutil.rmtree(self.jobs / job_id, ignore_errors=True)

    def create(self, case: dict, kind: str = RUN, request: dict | None = None) -> dict:
        """A new queued job for `case` (validated JSON), of `kind` with its `request` (a study's,
        which holds the case too); returns its record."""
        return _record(self._create([(new_id(), case, kind, request)])[0])

    def get(self, job_id: str) -> dict:
        self.folder(job_id)  # the id's pattern
        with self._connection() as connection:
            row = connection.execute(select(JOBS).where(self._mine(JOBS.c.id == job_id))).first()
        if row is None:
            raise UnknownJob(job_id)
        return _record(row._mapping)

    def _change(self, job_id: str, condition, then: Callable[[Connection], None] | None = None, **values) -> bool:
        """Set `values` on the job if `condition` holds for it, in one statement: True if it did;
        then `then(connection)` in the same transaction, if it did."""
        with self._connection(write=True) as connection:
            done = connection.execute(update(JOBS).where(JOBS.c.id == job_id, condition).values(**values)).rowcount == 1
            if done and then is not None:
                then(connection)
            return done

    def start(self, job_id: str, worker: str) -> dict | None:
        """Queued, or running with its beat lapsed (its worker died, or handed it back) → running on
        `worker`, unless cancelled: the record then, or None if it was not started."""
        taken = or_(JOBS.c.status == QUEUED, and_(JOBS.c.status == RUNNING, JOBS.c.beat < _lapsed_before()))
        with self._connection(write=True) as connection:
            row = connection.execute(
                update(JOBS)
                .where(JOBS.c.id == job_id, taken, ~JOBS.c.cancel_requested)
                .values(
                    status=RUNNING, started=now(), attempts=JOBS.c.attempts + 1, worker=worker, progress=0.0, beat=now()
                )
                .returning(*JOBS.c)
            ).first()
        return None if row is None else _record(row._mapping)

    def held(self, job_id: str) -> bool:
        """The job runs on a worker that keeps its beat: another must not run it too."""
        with self._connection() as connection:
            return (
                connection.scalar(
                    select(func.count())
                    .select_from(JOBS)
                    .where(JOBS.c.id == job_id, JOBS.c.status == RUNNING, JOBS.c.beat >= _lapsed_before())
                )
                == 1
            )

    def renew(self, job_id: str, worker: str) -> bool:
        """The job `worker` runs still runs: its beat, now. True if it was `worker`'s to renew."""
        return self._change(job_id, _running_on(worker), beat=now())

    def release(self, job_id: str, worker: str) -> bool:
        """`worker` hands the job back (its message goes back on the queue): its beat lapsed now, so
        that the next worker delivered it takes it at once. True if it was `worker`'s to hand back."""
        return self._change(job_id, _running_on(worker), beat=_lapsed_before())

    def lapsed(self, before: datetime) -> list[tuple[str, str]]:
        """(id, worker) of the running jobs whose last beat was before then, oldest first."""
        with self._connection() as connection:
            return [
                tuple(row)
                for row in connection.execute(
                    select(JOBS.c.id, JOBS.c.worker)
                    .where(JOBS.c.status == RUNNING, JOBS.c.beat < before)
                    .order_by(JOBS.c.created, JOBS.c.id)
                )
            ]

    def set_progress(self, job_id: str, fraction: float) -> bool:
        return self._change(job_id, JOBS.c.status == RUNNING, progress=fraction)

    def finish(
        self,
        job_id: str,
        status: str,
        error: str | None = None,
        then: Callable[[Connection], None] | None = None,
        **values,
    ) -> bool:
        """An unfinished job → `status` (with `error`): True if this call finished it, and then
        `then(connection)` in the same transaction. Success needs a running job with no cancel
        asked; a failure or a cancel, any unfinished job."""
        if status == SUCCEEDED:
            condition = and_(JOBS.c.status == RUNNING, ~JOBS.c.cancel_requested)
        else:
            condition = JOBS.c.status.in_((QUEUED, RUNNING))
        return self._change(job_id, condition, then, status=status, error=error, finished=now(), **values)

    def complete(
        self,
        job_id: str,
        status: str,
        error: str | None = None,
        then: Callable[[Connection], None] | None = None,
        **values,
    ) -> str:
        """A worker's end of a job: `finish` it as `status` (and `then`); a success that lost to a
        cancel asked meanwhile removes what it wrote and ends cancelled. Returns the job's final
        status."""
        if self.finish(job_id, status, error, then, **values):
            return status
        record = self.get(job_id)
        if record["cancel_requested"] and record["status"] not in FINISHED:
            self.remove_results(job_id)
            self.finish(job_id, CANCELLED)
            return CANCELLED
        return record["status"]

    def requeue(self, job_id: str, worker: str, lapsed_before: datetime | None = None) -> bool:
        """Running on `worker`, which died (with no beat since `lapsed_before`, if given) → queued again,
        its beat now: when it was queued again."""
        condition = _running_on(worker)
        if lapsed_before is not None:
            condition = and_(condition, JOBS.c.beat < lapsed_before)
        return self._change(job_id, condition, status=QUEUED, progress=0.0, beat=now())

    def unpublished(self, before: datetime) -> list[str]:
        """The queued jobs last queued (created, or queued again) before then, oldest first."""
        with self._connection() as connection:
            return list(
                connection.scalars(select(JOBS.c.id).where(_queued_before(before)).order_by(JOBS.c.created, JOBS.c.id))
            )

    def queued_again(self, job_id: str, before: datetime) -> bool:
        """A queued job last queued before then is queued again now (its message lost): True if
        this call did (so that of several callers one publishes it)."""
        return self._change(job_id, _queued_before(before), beat=now())

    def request_cancel(self, job_id: str) -> dict | None:
        """Cancel the job if it has not finished: a queued one at once, a running one by its
        worker, which is asked to (`cancel_requested`). Returns the record as it then is, or
        None if the job had already finished."""
        self.get(job_id)  # known, and this owner's
        if self._change(
            job_id, JOBS.c.status == QUEUED, status=CANCELLED, finished=now(), cancel_requested=True
        ) or self._change(job_id, JOBS.c.status == RUNNING, cancel_requested=True):
            return self.get(job_id)
        return None

    def cancel_requested(self, job_id: str) -> bool:
        with self._connection() as connection:
            return bool(connection.scalar(select(JOBS.c.cancel_requested).where(JOBS.c.id == job_id)))

    def delete(self, job_id: str) -> bool:
        """Remove a finished job, its record and its folder: True if this call removed it."""
        self.folder(job_id)
        with self._connection(write=True) as connection:
            gone = (
                connection.execute(
                    delete(JOBS).where(self._mine(and_(JOBS.c.id == job_id, JOBS.c.status.in_(FINISHED))))
                ).rowcount
                == 1
            )
        if gone:
            self._remove_folders([job_id])
        return gone

    def case(self, job_id: str) -> dict:
        return json.loads((self.folder(job_id) / "case.json").read_text())

    def summary(self, job_id: str) -> dict:
        return json.loads((self.folder(job_id) / "summary.json").read_text())

    def write_summary(self, job_id: str, summary_json: str) -> None:
        """Store the summary, given as JSON text (the result file's copy: it is encoded once)."""
        write_atomic(self.folder(job_id) / "summary.json", summary_json.encode())

    def request(self, job_id: str) -> dict:
        return json.loads((self.folder(job_id) / "request.json").read_text())

    def answer(self, job_id: str) -> dict:
        return json.loads((self.folder(job_id) / "answer.json").read_text())

    def write_answer(self, job_id: str, answer: dict) -> None:
        write_atomic(self.folder(job_id) / "answer.json", json.dumps(answer).encode())

    def batches(self, job_id: str) -> Path:
        """Where a study's batches of runs wait for the workers."""
        return self.folder(job_id) / "batches"

    def result_path(self, job_id: str) -> Path:
        return self.folder(job_id) / "result.h5"

    def plot_path(self, job_id: str, name: str, fmt: str) -> Path:
        """Where plot `name` of the job's result is kept as `fmt`; both are checked, never trusted."""
        if not (_PLOT_NAME.fullmatch(name) and fmt in ("png", "svg")):
            raise ValueError(f"not a plot file name: {name!r}.{fmt!r}")
        return self.folder(job_id) / "plots" / f"{name}.{fmt}"

    def write_plot(self, job_id: str, name: str, fmt: str, data: bytes) -> Path:
        path = self.plot_path(job_id, name, fmt)
        path.parent.mkdir(exist_ok=True)
        write_atomic(path, data)
        return path

    def remove_results(self, job_id: str) -> None:
        """Remove what a run or a study wrote (a job whose finish lost to a cancel)."""
        folder = self.folder(job_id)
        for name in ("summary.json", "answer.json", "result.h5"):
            (folder / name).unlink(missing_ok=True)
        shutil.rmtree(folder / "plots", ignore_errors=True)

    def size(self, job_id: str) -> int:
        """Bytes in the job's folder."""
        return sum(f.stat().st_size for f in self.folder(job_id).rglob("*") if f.is_file())

    def list(
        self,
        offset: int = 0,
        limit: int = 50,
        status: str | None = None,
        name: str | None = None,
        sweep: str | None = None,
        before: tuple[datetime, str] | None = None,
    ) -> tuple[int, list[dict]]:
        """(how many match, a page of them newest first): `offset` into them, or those created
        `before` (created, id) — the last of the page before, which does not grow with the
        number of jobs as an offset does."""
        conditions = [
            column == value
            for column, value in (
                (JOBS.c.owner, self.owner),
                (JOBS.c.status, status),
                (JOBS.c.name, name),
                (JOBS.c.sweep, sweep),
            )
            if value is not None
        ]
        page = conditions if before is None else [*conditions, tuple_(JOBS.c.created, JOBS.c.id) < tuple_(*before)]
        with self._connection() as connection:
            # No condition at all when none is asked: SQLite then counts the table at once.
            total = connection.scalar(select(func.count()).select_from(JOBS).where(*conditions))
            rows = connection.execute(
                select(JOBS).where(*page).order_by(JOBS.c.created.desc(), JOBS.c.id.desc()).offset(offset).limit(limit)
            )
            return total, [_record(row._mapping) for row in rows]

    def ids(self, status: str, worker: str | None = None) -> list[str]:
        """The jobs of `status` (on `worker`), oldest first."""
        condition = JOBS.c.status == status
        if worker is not None:
            condition = and_(condition, JOBS.c.worker == worker)
        with self._connection() as connection:
            return list(
                connection.scalars(select(JOBS.c.id).where(self._mine(condition)).order_by(JOBS.c.created, JOBS.c.id))
            )

    def counts(self) -> dict[str, int]:
        """How many jobs of each status."""
        with self._connection() as connection:
            return dict(connection.execute(select(JOBS.c.status, func.count()).group_by(JOBS.c.status)).all())

    def expired(self, finished_before: datetime, limit: int) -> list[str]:
        """Up to `limit` finished jobs, not of a sweep, finished before then, oldest first."""
        with self._connection() as connection:
            return list(
                connection.scalars(
                    select(JOBS.c.id)
                    .where(JOBS.c.status.in_(FINISHED), JOBS.c.sweep.is_(None), JOBS.c.finished < finished_before)
                    .order_by(JOBS.c.finished)
                    .limit(limit)
                )
            )

    def result_bytes(self) -> int:
        with self._connection() as connection:
            return int(connection.scalar(select(func.coalesce(func.sum(JOBS.c.result_bytes), 0))))


def _running_on(worker: str):
    return and_(JOBS.c.status == RUNNING, JOBS.c.worker == worker)


def _queued_before(before: datetime):
    """Queued, and last queued (its beat: when it was queued again, else its creation) before then."""
    return and_(
        JOBS.c.status == QUEUED,
        or_(JOBS.c.beat < before, and_(JOBS.c.beat.is_(None), JOBS.c.created < before)),
    )


def _lapsed_before() -> datetime:
    """A beat before this has lapsed."""
    return now() - timedelta(seconds=ALIVE_WITHIN)


def _utc(value: datetime | None) -> str | None:
    """A time as ISO 8601 in UTC (SQLite gives it back without its zone)."""
    if value is None:
        return None
    return (value if value.tzinfo else value.replace(tzinfo=UTC)).isoformat()


def _record(row) -> dict:
    """A job's record as the API and the workers see it: times in ISO 8601."""
    record = dict(row)
    for key in ("created", "started", "finished"):
        record[key] = _utc(record[key])
    return record


class UnknownSweep(KeyError):
    """No sweep has this id."""


class SweepStore:
    """Sweeps: each variant is an ordinary job; the sweep record says which job has which values.
    With an `owner`, only that owner's sweeps are known."""

    def __init__(self, jobs: JobStore):
        self.jobs = jobs

    def _mine(self, condition):
        owner = self.jobs.owner
        return condition if owner is None else and_(condition, SWEEPS.c.owner == owner)

    def create(self, name: str | None, parameters: list[str], variants: list[tuple[dict, dict]]) -> dict:
        """A new sweep of `variants` (each (values, case JSON)), each a new queued job, all
        recorded in one transaction; returns the sweep's record."""
        sweep_id, job_ids = new_id(), [new_id() for _ in variants]
        record = {
            "id": sweep_id,
            "owner": self.jobs.owner,
            "name": name,
            "created": now(),
            "parameters": parameters,
            "variants": [{"values": values, "job": job_id} for (values, _), job_id in zip(variants, job_ids)],
        }
        self.jobs._create(
            [(job_id, case, RUN, None) for job_id, (_, case) in zip(job_ids, variants)],
            sweep_id,
            lambda connection: connection.execute(insert(SWEEPS), [record]),
        )
        return _sweep_record(record)

    def get(self, sweep_id: str) -> dict:
        if not isinstance(sweep_id, str) or not _ID.fullmatch(sweep_id):
            raise UnknownSweep(sweep_id)
        with self.jobs._connection() as connection:
            row = connection.execute(select(SWEEPS).where(self._mine(SWEEPS.c.id == sweep_id))).first()
        if row is None:
            raise UnknownSweep(sweep_id)
        return _sweep_record(row._mapping)

    def purge(self, sweep_id: str) -> bool:
        """Remove a sweep whose jobs have all finished, with its jobs: True if this call did."""
        self.get(sweep_id)
        with self.jobs._connection(write=True) as connection:
            # One statement per table, each conditional on the sweep having finished.
            unfinished = select(JOBS.c.id).where(JOBS.c.sweep == sweep_id, JOBS.c.status.notin_(FINISHED))
            gone = connection.execute(delete(SWEEPS).where(SWEEPS.c.id == sweep_id, ~unfinished.exists())).rowcount == 1
            if gone:
                ids = list(connection.scalars(delete(JOBS).where(JOBS.c.sweep == sweep_id).returning(JOBS.c.id)))
        if gone:
            self.jobs._remove_folders(ids)
        return gone

    def expired(self, finished_before: datetime, limit: int) -> list[str]:
        """Up to `limit` sweeps whose jobs all finished before then."""
        later = select(JOBS.c.id).where(
            JOBS.c.sweep == SWEEPS.c.id, or_(JOBS.c.status.notin_(FINISHED), JOBS.c.finished >= finished_before)
        )
        with self.jobs._connection() as connection:
            return list(
                connection.scalars(
                    select(SWEEPS.c.id)
                    .where(~later.exists(), SWEEPS.c.created < finished_before)
                    .order_by(SWEEPS.c.created)
                    .limit(limit)
                )
            )


def _sweep_record(row) -> dict:
    record = dict(row)
    record["created"] = _utc(record["created"])
    return record


class WorkerRegistry:
    """Workers announce themselves with a heartbeat file; readiness asks for a recent one."""

    def __init__(self, root: Path):
        self.folder = Path(root) / "workers"
        self.folder.mkdir(parents=True, exist_ok=True)

    def beat(self, name: str) -> None:
        safe = re.sub(r"[^A-Za-z0-9_.@-]", "_", name)
        write_atomic(
            self.folder / f"{safe}.json", json.dumps({"name": name, "time": datetime.now(UTC).timestamp()}).encode()
        )

    def alive(self, within: float) -> list[str]:
        limit = datetime.now(UTC).timestamp() - within
        names = []
        for path in self.folder.glob("*.json"):
            try:
                beat = json.loads(path.read_text())
            except (OSError, ValueError):
                continue
            if beat["time"] >= limit:
                names.append(beat["name"])
        return sorted(names)
