"""Import the records of a store that kept them in folders: `jobs/<id>/job.json` (with a `cancel`
file once a cancel was asked) and `sweeps/<id>.json` under the results folder. Runs once, as
every migration; the files are left where they are (nothing reads them any more).

Revision ID: 0002
Revises: 0001
"""

import json
from datetime import datetime
from pathlib import Path

import sqlalchemy as sa
from alembic import context, op

revision = "0002"
down_revision = "0001"
branch_labels = None
depends_on = None

WHEN = sa.DateTime(timezone=True)
JOBS = sa.table(
    "jobs",
    *(
        sa.column(name)
        for name in (
            "id",
            "owner",
            "name",
            "kind",
            "status",
            "progress",
            "error",
            "attempts",
            "worker",
            "sweep",
            "cancel_requested",
        )
    ),
    sa.column("created", WHEN),
    sa.column("started", WHEN),
    sa.column("finished", WHEN),
)
SWEEPS = sa.table(
    "sweeps",
    sa.column("id"),
    sa.column("owner"),
    sa.column("name"),
    sa.column("created", WHEN),
    sa.column("parameters", sa.JSON),
    sa.column("variants", sa.JSON),
)


def _when(text):
    return None if text is None else datetime.fromisoformat(text)


def _read(path: Path):
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError):
        return None  # a record being written when the old store stopped


def upgrade() -> None:
    root = Path(context.config.attributes["results_dir"])
    sweep_of, sweep_rows = {}, []
    for path in sorted((root / "sweeps").glob("*.json")):
        record = _read(path)
        if record is None:
            continue
        sweep_rows.append(
            {
                "id": record["id"],
                "owner": record.get("owner"),
                "name": record.get("name"),
                "created": _when(record["created"]),
                "parameters": record["parameters"],
                "variants": record["variants"],
            }
        )
        sweep_of |= {variant["job"]: record["id"] for variant in record["variants"]}
    job_rows = []
    for path in sorted((root / "jobs").glob("*/job.json")):
        record = _read(path)
        if record is None:
            continue
        job_rows.append(
            {
                "id": record["id"],
                "owner": record.get("owner"),
                "name": record.get("name"),
                "kind": record.get("kind", "run"),
                "status": record["status"],
                "progress": record.get("progress", 0.0),
                "error": record.get("error"),
                "attempts": record.get("attempts", 0),
                "worker": record.get("worker"),
                "sweep": sweep_of.get(record["id"]),
                "cancel_requested": (path.parent / "cancel").exists(),
                "created": _when(record["created"]),
                "started": _when(record.get("started")),
                "finished": _when(record.get("finished")),
            }
        )
    for table, rows in ((SWEEPS, sweep_rows), (JOBS, job_rows)):
        if rows:
            op.bulk_insert(table, rows)


def downgrade() -> None:
    pass
