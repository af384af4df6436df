"""percussim.worker: the queue worker (Celery app, the job task) and what the API and the workers
share: the results store (`store`) and the settings (`settings`)."""

# Installed as percussim.worker: see solver/__init__.py for why no other name is allowed.
if __name__ != "percussim.worker":
    raise ImportError(f"import percussim.worker, not {__name__} (the folder worker/ is that package)")
