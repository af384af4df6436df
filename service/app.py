"""The percussim HTTP API (the contract's table): `create_app(settings)` and `app` for uvicorn.

Creating the app writes nothing: the results store is opened per request, so importing this module
(uvicorn does, for `app`) creates no folder wherever it happens to run.
"""

from __future__ import annotations

from fastapi import Depends, FastAPI
from fastapi.middleware.cors import CORSMiddleware
from fastapi.responses import JSONResponse

from percussim.common.settings import Settings
from percussim.common.settings import settings as env_settings
from percussim.common.store import ALIVE_WITHIN, WorkerRegistry

from . import background, errors, page, presets
from .auth import authenticate
from .cases import cases_router
from .jobs import jobs_router
from .limits import BodySizeLimit
from .metrics import metrics_router
from .queue import JobQueue
from .studies import KINDS, studies_router
from .sweeps import sweeps_router


def create_app(settings: Settings | None = None) -> FastAPI:
    """The API on the results folder and broker of `settings` (default: the environment's)."""
    settings = settings or env_settings()
    queue = JobQueue(settings)
    app = FastAPI(
        title="percussim",
        summary="Simulation of percussive impact devices: striker, tool, contact and medium.",
        description="Submit an impact case (SI units) as a job, follow it, then fetch its pulse "
        "summary and its HDF5 result. The presets are the paper's cases, a rock drill and a pile. "
        "In a browser, [the job page](/) does all of this.",
        version="1",
        lifespan=background.lifespan(settings),
    )
    errors.install(app)
    app.add_middleware(BodySizeLimit, max_bytes=settings.max_body_bytes)
    if settings.cors_origin_list():
        app.add_middleware(
            CORSMiddleware,
            allow_origins=settings.cors_origin_list(),
            allow_methods=["GET", "POST", "DELETE"],
            allow_headers=["Content-Type", "X-API-Key"],
            expose_headers=["Location", "Retry-After"],
        )
    keyed = [Depends(authenticate(settings))]
    app.include_router(jobs_router(settings, queue, presets.openapi_examples()), dependencies=keyed)
    app.include_router(cases_router(settings), dependencies=keyed)
    app.include_router(sweeps_router(settings, queue), dependencies=keyed)
    for kind in KINDS:
        app.include_router(studies_router(settings, queue, kind), dependencies=keyed)
    app.include_router(presets.router, dependencies=keyed)
    app.include_router(page.router)
    app.include_router(metrics_router(settings, queue))

    @app.get("/healthz", tags=["health"])
    def healthz() -> dict:
        """Liveness: the API answers."""
        return {"status": "ok"}

    @app.get("/readyz", tags=["health"], responses={503: {"description": "not ready, with the reason"}})
    def readyz():
        """Readiness: the broker is reachable and a worker has reported recently."""
        workers = WorkerRegistry(settings.results_dir).alive(within=ALIVE_WITHIN)
        reason = queue.problem()
        if reason is None and not workers:
            reason = f"no worker has reported in the last {ALIVE_WITHIN:g} s (start one with `percussim worker`)"
        if reason:
            return JSONResponse(
                status_code=503,
                content={"status": "unavailable", "reason": reason, "broker": queue.describe(), "workers": workers},
            )
        return {"status": "ready", "broker": queue.describe(), "workers": workers}

    return app


app = create_app()
