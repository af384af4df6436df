"""The results store: one folder a job under the results folder, readable by any process.

    jobs/<id>/job.json      status, progress, timestamps, error, kind (rewritten atomically)
    jobs/<id>/case.json     the case as submitted
    jobs/<id>/request.json  a calibration's or an optimisation's request (kind 'calibration',
                            'optimization'; a run's kind is 'run')
    jobs/<id>/answer.json   their answer, once succeeded
    jobs/<id>/batches/      their batches of runs while they are spread over the workers
    jobs/<id>/summary.json  the pulse summary, once succeeded
    jobs/<id>/result.h5     the HDF5 result, once succeeded
    jobs/<id>/cancel        present once a cancel was asked for
    jobs/<id>/plots/        plots of the result as rendered for the API: <name>.<png|svg>
    sweeps/<id>.json        a sweep: its parameters and, per variant, the values and the job id

Every write goes to a temporary name and is renamed, so a reader never sees half a file and a
job delivered twice writes the same files again instead of twice. Job ids are random and
checked against their pattern before any path is built from them.
"""

from __future__ import annotations

import json
import os
import re
import secrets
import tempfile
from datetime import datetime, timezone
from pathlib import Path
from typing import Iterator

QUEUED, RUNNING, SUCCEEDED, FAILED, CANCELLED = "queued", "running", "succeeded", "failed", "cancelled"
FINISHED = (SUCCEEDED, FAILED, CANCELLED)
RUN, CALIBRATION, OPTIMIZATION = "run", "calibration", "optimization"  # a job's kind
_ID = re.compile(r"[A-Za-z0-9_-]{22}")
_PLOT_NAME = re.compile(r"[a-z_]+")


class UnknownJob(KeyError):
    """No job has this id."""


def now() -> str:
    return datetime.now(timezone.utc).isoformat()


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

    def __init__(self, root: Path, owner: str | None = None):
        self.jobs = Path(root) / "jobs"
        self.jobs.mkdir(parents=True, exist_ok=True)
        self.owner = owner

    def folder(self, job_id: str) -> Path:
        if not isinstance(job_id, str) or not _ID.fullmatch(job_id):
            raise UnknownJob(job_id)
        folder = self.jobs / job_id
        if not (folder / "job.json").is_file():
            raise UnknownJob(job_id)
        return folder

    def create(self, case: dict, kind: str = RUN, request: dict | None = None) -> dict:
        """A new queued job for `case` (validated JSON), of `kind` with its `request` (a
        calibration's or an optimisation's, which holds the case too); returns its record."""
        job_id = secrets.token_urlsafe(16)  # 22 characters, 128 random bits
        folder = self.jobs / job_id
        folder.mkdir()
        write_atomic(folder / "case.json", json.dumps(case).encode())
        if request is not None:
            write_atomic(folder / "request.json", json.dumps(request).encode())
        record = {"id": job_id, "name": case.get("name"), "kind": kind, "status": QUEUED,
                  "progress": 0.0, "created": now(), "started": None, "finished": None,
                  "error": None, "attempts": 0, "worker": None, "owner": self.owner}
        write_atomic(folder / "job.json", json.dumps(record).encode())
        return record

    def get(self, job_id: str) -> dict:
        record = json.loads((self.folder(job_id) / "job.json").read_text())
        if not self._sees(record):
            raise UnknownJob(job_id)
        return record

    def _sees(self, record: dict) -> bool:
        return self.owner is None or record.get("owner") == self.owner

    def update(self, job_id: str, **changes) -> dict:
        record = self.get(job_id) | changes
        write_atomic(self.folder(job_id) / "job.json", json.dumps(record).encode())
        return record

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

    def request_cancel(self, job_id: str) -> None:
        write_atomic(self.folder(job_id) / "cancel", b"")

    def cancel_requested(self, job_id: str) -> bool:
        return (self.folder(job_id) / "cancel").exists()

    def records(self) -> Iterator[dict]:
        """Every job's record, in no order."""
        for folder in self.jobs.iterdir():
            try:
                record = json.loads((folder / "job.json").read_text())
            except (OSError, ValueError):
                continue  # a folder being created
            if self._sees(record):
                yield record

    def list(self, offset: int = 0, limit: int = 50) -> tuple[int, list[dict]]:
        """(total, records) newest first."""
        records = sorted(self.records(), key=lambda r: r["created"], reverse=True)
        return len(records), records[offset:offset + limit]


class UnknownSweep(KeyError):
    """No sweep has this id."""


class SweepStore:
    """Sweeps: each variant is an ordinary job; the sweep record says which job has which values.
    With an `owner`, only that owner's sweeps are known."""

    def __init__(self, root: Path, owner: str | None = None):
        self.folder = Path(root) / "sweeps"
        self.folder.mkdir(parents=True, exist_ok=True)
        self.owner = owner

    def create(self, name: str | None, parameters: list[str], variants: list[dict]) -> dict:
        """A new sweep of `variants` (each `{"values": {...}, "job": id}`); returns its record."""
        record = {"id": secrets.token_urlsafe(16), "name": name, "created": now(),
                  "parameters": parameters, "variants": variants, "owner": self.owner}
        write_atomic(self.folder / f"{record['id']}.json", json.dumps(record).encode())
        return record

    def get(self, sweep_id: str) -> dict:
        if not isinstance(sweep_id, str) or not _ID.fullmatch(sweep_id):
            raise UnknownSweep(sweep_id)
        try:
            record = json.loads((self.folder / f"{sweep_id}.json").read_text())
        except FileNotFoundError:
            raise UnknownSweep(sweep_id) from None
        if self.owner is not None and record.get("owner") != self.owner:
            raise UnknownSweep(sweep_id)
        return record


class WorkerRegistry:
    """Workers announce themselves with a heartbeat file; readiness asks for a recent one."""

    def __init__(self, root: Path):
        self.folder = Path(root) / "workers"
        self.folder.mkdir(parents=True, exist_ok=True)

    def beat(self, name: str) -> None:
        safe = re.sub(r"[^A-Za-z0-9_.@-]", "_", name)
        write_atomic(self.folder / f"{safe}.json",
                     json.dumps({"name": name, "time": datetime.now(timezone.utc).timestamp()}).encode())

    def alive(self, within: float) -> list[str]:
        limit = datetime.now(timezone.utc).timestamp() - within
        names = []
        for path in self.folder.glob("*.json"):
            try:
                beat = json.loads(path.read_text())
            except (OSError, ValueError):
                continue
            if beat["time"] >= limit:
                names.append(beat["name"])
        return sorted(names)
