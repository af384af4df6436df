"""percussim's queue worker: the Celery app, the job task and the results store."""
