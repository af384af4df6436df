"""A running job's beat: when the worker running it last said it still does. A job whose beat has
lapsed may be taken by another worker (its message delivered again) or queued again from its
record (its message lost); one whose beat is fresh is not run twice.

Revision ID: 0003
Revises: 0002
"""

import sqlalchemy as sa
from alembic import op

revision = "0003"
down_revision = "0002"
branch_labels = None
depends_on = None


def upgrade() -> None:
    with op.batch_alter_table("jobs") as batch:
        batch.add_column(sa.Column("beat", sa.DateTime(timezone=True)))
    # Jobs running across the upgrade: their beat from their start, renewed by their worker.
    op.execute("UPDATE jobs SET beat = COALESCE(started, created) WHERE status = 'running'")


def downgrade() -> None:
    with op.batch_alter_table("jobs") as batch:
        batch.drop_column("beat")
