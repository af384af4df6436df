"""Alembic's environment: migrations run on the connection `percussim.common.database.migrate`
hands over (no alembic.ini; the database is the service's own configuration)."""

from alembic import context

context.configure(connection=context.config.attributes["connection"], target_metadata=None)
with context.begin_transaction():
    context.run_migrations()
