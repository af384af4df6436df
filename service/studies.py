"""`/v1/calibrations` and `/v1/optimizations`: studies of many runs, each a job on the workers.

A study is an ordinary job of its kind (its record, progress, cancel and time limit are a run's),
checked up front as far as can be without the workers, then queued; the worker that takes it
spreads its runs over the others. Its answer (the fit, the optimum) and its plot are read back
here. No `from __future__ import annotations`: FastAPI reads the signatures.
"""

from collections.abc import Callable
from typing import Annotated, Literal

from fastapi import APIRouter, Body, Request, Response
from fastapi.responses import FileResponse
from pydantic import BaseModel, ConfigDict

from percussim.common.settings import Settings
from percussim.common.store import CALIBRATION, OPTIMIZATION, SUCCEEDED, JobStore, UnknownJob
from percussim.solver.limits import check_case
from percussim.solver.plots import FORMATS
from percussim.solver.presets import preset_json, preset_names
from percussim.solver.study import Calibration, Optimization, check_calibration, check_optimization, study_case

from .errors import FieldErrors, Problem
from .jobs import cancel_or_delete, queue_jobs, succeeded
from .queue import JobQueue


class StudyLinks(BaseModel):
    self: str
    plot_png: str
    plot_svg: str


class Study(BaseModel):
    """A study's job record, its links, and its answer once it has succeeded."""

    model_config = ConfigDict(extra="allow")

    id: str
    kind: Literal["calibration", "optimization"]
    status: Literal["queued", "running", "succeeded", "failed", "cancelled"]
    progress: float
    error: str | None
    links: StudyLinks


def _optimization_example() -> dict | None:
    if "rock_drill" not in preset_names():
        return None
    return {
        "rock-drill-piston": {
            "summary": "Rock drill: the piston length and speed that put the most energy into the rock "
            "with the rod's stress at most 250 MPa",
            "value": {
                "case": preset_json("rock_drill"),
                "variables": {"striker.length": [0.1, 0.6], "striker.velocity": [5.0, 20.0]},
                "objective": {"maximize": "energy.to_medium"},
                "limits": {"max_compressive_stress": {"max": 2.5e8}},
                "max_evaluations": 300,
            },
        }
    }


# kind → (route prefix, the answer's name in the view, request model, its check, its plot)
KINDS: dict[str, tuple[str, str, type[BaseModel], Callable, str]] = {
    CALIBRATION: ("/v1/calibrations", "fit", Calibration, check_calibration, "fit"),
    OPTIMIZATION: ("/v1/optimizations", "optimum", Optimization, check_optimization, "convergence"),
}


def studies_router(settings: Settings, queue: JobQueue, kind: str) -> APIRouter:
    """The routes of one kind of study for the results store and broker of `settings`."""
    prefix, answer_name, model, check, plot = KINDS[kind]
    router = APIRouter(prefix=prefix, tags=[f"{kind}s"])
    not_found = {404: {"model": Problem, "description": f"no {kind} with this id"}}

    def store(request: Request) -> JobStore:
        return JobStore(settings, owner=request.state.owner)

    def record_of(request: Request, study_id: str) -> dict:
        record = store(request).get(study_id)
        if record.get("kind") != kind:
            raise UnknownJob(study_id)
        return record

    def view(request: Request, record: dict) -> dict:
        jobs = store(request)
        answer = jobs.answer(record["id"]) if record["status"] == SUCCEEDED else None
        links = {"self": request.app.url_path_for(f"get_{kind}", study_id=record["id"])}
        links |= {
            f"plot_{fmt}": request.app.url_path_for(f"get_{kind}_plot", study_id=record["id"], fmt=fmt)
            for fmt in FORMATS
        }
        return record | {"links": links, answer_name: answer}

    examples = _optimization_example() if kind == OPTIMIZATION else None

    @router.post(
        "",
        status_code=202,
        response_model=Study,
        name=f"submit_{kind}",
        responses={
            422: {"model": FieldErrors, "description": "the request is invalid, naming the field"},
            503: {"model": Problem, "description": "the broker is unreachable; retry later"},
        },
    )
    def submit(request: Request, response: Response, study: Annotated[model, Body(openapi_examples=examples)]) -> dict:
        check_case(study_case(study.case), settings.limits())
        check(study, settings.limits())
        jobs = store(request)
        record = jobs.create(
            study.case.model_dump(mode="json", exclude_none=True),
            kind=kind,
            request=study.model_dump(mode="json", exclude_none=True),
        )
        queue_jobs(jobs, queue, [record["id"]])
        response.headers["Location"] = request.app.url_path_for(f"get_{kind}", study_id=record["id"])
        return view(request, record)

    submit.__doc__ = (
        f"Queue a {kind}: checked first (the request's fields, the case's limits"
        + (
            ", the record against the case and its units"
            if kind == CALIBRATION
            else ", the variables and the summary quantities named"
        )
        + "), each refusal naming its field; then a job on the workers."
    )

    @router.get("/{study_id}", response_model=Study, name=f"get_{kind}", responses=not_found)
    def get(request: Request, study_id: str) -> dict:
        return view(request, record_of(request, study_id))

    get.__doc__ = f"The {kind}'s status and progress, then its answer (`{answer_name}`)."

    @router.get(
        "/{study_id}/plot.{fmt}",
        response_class=FileResponse,
        name=f"get_{kind}_plot",
        responses=not_found | {409: {"model": Problem, "description": "not succeeded"}},
    )
    def get_plot(request: Request, study_id: str, fmt: Literal["png", "svg"]) -> FileResponse:
        succeeded(record_of(request, study_id), "plot")
        return FileResponse(store(request).plot_path(study_id, plot, fmt), media_type=FORMATS[fmt])

    get_plot.__doc__ = (
        "The record against the fitted model, and the residual."
        if kind == CALIBRATION
        else "Every evaluation of the objective, and the best so far."
    )

    @router.delete(
        "/{study_id}",
        status_code=202,
        response_model=Study,
        name=f"delete_{kind}",
        responses=not_found | {204: {"description": "it had finished: it and its files are removed"}},
    )
    def delete_study(request: Request, study_id: str):
        return cancel_or_delete(
            store(request), record_of(request, study_id), lambda record: view(request, record), kind
        )

    delete_study.__doc__ = (
        f"Cancel the {kind} if it has not finished (202): a queued one at once, a running "
        "one between two batches. A finished one is removed with its files (204)."
    )
    return router
