"""percussim.service: the HTTP API (FastAPI): validate, enqueue, read results; the job page."""

# Installed as percussim.service: see solver/__init__.py for why no other name is allowed.
if __name__ != "percussim.service":
    raise ImportError(f"import percussim.service, not {__name__} (the folder service/ is that package)")
