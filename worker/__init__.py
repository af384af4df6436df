"""percussim.worker: the queue worker, the Celery app (`app`) and its tasks (`tasks`: a job, a
study's parts). What it shares with the API is `percussim.common`."""

# Installed as percussim.worker: see solver/__init__.py for why no other name is allowed.
if __name__ != "percussim.worker":
    raise ImportError(f"import percussim.worker, not {__name__} (the folder worker/ is that package)")
