"""percussim HTTP service: validate, enqueue, read results."""
