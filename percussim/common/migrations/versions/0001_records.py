"""Job and sweep records, and the metrics' counters.

Revision ID: 0001
Revises:
"""

import sqlalchemy as sa
from alembic import op

revision = "0001"
down_revision = None
branch_labels = None
depends_on = None

WHEN = sa.DateTime(timezone=True)


def upgrade() -> None:
    op.create_table(
        "jobs",
        sa.Column("id", sa.String(32), primary_key=True),
        sa.Column("owner", sa.String(64)),
        sa.Column("name", sa.Text),
        sa.Column("kind", sa.String(16), nullable=False),
        sa.Column("status", sa.String(16), nullable=False),
        sa.Column("progress", sa.Float, nullable=False),
        sa.Column("created", WHEN, nullable=False),
        sa.Column("started", WHEN),
        sa.Column("finished", WHEN),
        sa.Column("error", sa.Text),
        sa.Column("attempts", sa.Integer, nullable=False),
        sa.Column("worker", sa.Text),
        sa.Column("sweep", sa.String(32)),
        sa.Column("cancel_requested", sa.Boolean, nullable=False),
        sa.Column("result_bytes", sa.BigInteger),
    )
    op.create_index("ix_jobs_created", "jobs", ["created", "id"])
    op.create_index("ix_jobs_owner_created", "jobs", ["owner", "created", "id"])
    op.create_index("ix_jobs_status_created", "jobs", ["status", "created", "id"])
    op.create_index("ix_jobs_name_created", "jobs", ["name", "created", "id"])
    op.create_index("ix_jobs_sweep", "jobs", ["sweep"])
    op.create_table(
        "sweeps",
        sa.Column("id", sa.String(32), primary_key=True),
        sa.Column("owner", sa.String(64)),
        sa.Column("name", sa.Text),
        sa.Column("created", WHEN, nullable=False),
        sa.Column("parameters", sa.JSON, nullable=False),
        sa.Column("variants", sa.JSON, nullable=False),
    )
    op.create_index("ix_sweeps_created", "sweeps", ["created"])
    op.create_table(
        "counters",
        sa.Column("name", sa.String(64), primary_key=True),
        sa.Column("key", sa.String(32), primary_key=True),
        sa.Column("value", sa.Float, nullable=False),
    )


def downgrade() -> None:
    for table in ("counters", "sweeps", "jobs"):
        op.drop_table(table)
