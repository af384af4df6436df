"""`/v1/calibrations`, `/v1/optimizations`, `/v1/bearing-graphs`, `/v1/drivability` and
`/v1/signal-matches`: studies of many runs, each a job on the workers.

A study is an ordinary job of its kind (its record, progress, cancel and time limit are a run's),
checked up front as far as can be without the workers, then queued; the worker that takes it
spreads its runs over the others. Its answer (the fit, the optimum; a pile study's rows beside its
record) and its plot are read back here. No `from __future__ import annotations`: FastAPI reads
the signatures.
"""

from collections.abc import Callable
from typing import Annotated, Literal, NamedTuple

from fastapi import APIRouter, Body, Request, Response
from fastapi.responses import FileResponse
from pydantic import BaseModel, ConfigDict

from percussim.common.settings import Settings
from percussim.common.store import (
    BEARING_GRAPH,
    CALIBRATION,
    DRIVABILITY,
    OPTIMIZATION,
    SIGNAL_MATCH,
    STUDY_PLOT,
    SUCCEEDED,
    JobStore,
    UnknownJob,
)
from percussim.solver.limits import Limits, check_case
from percussim.solver.pile_requests import BearingGraph, Drivability, bearing_variants, drivability_variants
from percussim.solver.plots import FORMATS
from percussim.solver.presets import preset_json, preset_names
from percussim.solver.signal_match import SignalMatch, check_record, driven_case
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
    kind: Literal["calibration", "optimization", "bearing_graph", "drivability", "signal_match"]
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


# A soil for the pile preset's drivability example: sand over dense sand (Smith's quakes, GRLWEAP's
# damping factors), driven to 14 m.
EXAMPLE_SOIL = {
    "layers": [
        {"from": 0.0, "to": 6.0, "shaft_resistance": 2e4, "toe_resistance": 4e5, "shaft_quake": 2.54e-3,
         "toe_quake": 2.54e-3, "shaft_damping_factor": 0.16, "toe_damping_factor": 0.49},
        {"from": 6.0, "to": 20.0, "shaft_resistance": 5e4, "toe_resistance": 1.2e6, "shaft_quake": 2.54e-3,
         "toe_quake": 2.54e-3, "shaft_damping_factor": 0.16, "toe_damping_factor": 0.49, "setup_factor": 1.3},
    ],
    "depths": [2.0, 4.0, 6.0, 8.0, 10.0, 12.0, 14.0],
    "blow_rate": 0.8,
    "refusal": 250.0,
}  # fmt: skip


def _drivability_example() -> dict | None:
    if "pile" not in preset_names():
        return None
    return {
        "pile-in-sand": {
            "summary": "The pile preset driven into sand over dense sand, 2 to 14 m, with setup in the dense sand",
            "value": {"case": preset_json("pile"), "soil": EXAMPLE_SOIL},
        }
    }


def _bearing_graph_example() -> dict | None:
    if "pile" not in preset_names():
        return None
    return {
        "pile-bearing-graph": {
            "summary": "The pile preset's bearing graph: 0.5 to 2.5 MN, all at the toe",
            "value": {"case": preset_json("pile"), "capacity": [5e5, 1e6, 1.5e6, 2e6, 2.5e6]},
        }
    }


EXAMPLES = {
    OPTIMIZATION: _optimization_example,
    BEARING_GRAPH: _bearing_graph_example,
    DRIVABILITY: _drivability_example,
}


def _on_its_grid(check: Callable[[BaseModel, Limits], object]) -> Callable[[BaseModel, Limits], object]:
    """A fit's or an optimisation's check, after its case's on the study's own grid."""

    def checked(study: BaseModel, limits: Limits) -> object:
        check_case(study_case(study.case), limits)
        return check(study, limits)

    return checked


def _checked_match(match: SignalMatch, limits: Limits) -> object:
    """A signal match's check: its record against the pile it drives, on the match's grid."""
    case = driven_case(match)
    check_case(study_case(case), limits)
    return check_record(match, case)


def _given_case(study: BaseModel) -> dict:
    return study.case.model_dump(mode="json", exclude_none=True)


def _driven_case(match: SignalMatch) -> dict:
    return driven_case(match).model_dump(mode="json", exclude_none=True)


class Kind(NamedTuple):
    """A kind of study as the API serves it."""

    prefix: str
    tag: str
    answer: str | None  # the answer's name in the view; None: its keys join the record's
    model: type[BaseModel]
    check: Callable[[BaseModel, Limits], object]  # refuses the request, naming the field
    checked: str  # what the check looks at, in words
    plotted: str  # what the plot (`STUDY_PLOT`'s) shows, in words
    case: Callable[[BaseModel], dict] = _given_case  # the job's case, as its record lists it


KINDS: dict[str, Kind] = {
    CALIBRATION: Kind(
        "/v1/calibrations",
        "calibrations",
        "fit",
        Calibration,
        _on_its_grid(check_calibration),
        "the request's fields, the case's limits, the record against the case and its units",
        "The record against the fitted model, and the residual.",
    ),
    OPTIMIZATION: Kind(
        "/v1/optimizations",
        "optimizations",
        "optimum",
        Optimization,
        _on_its_grid(check_optimization),
        "the request's fields, the case's limits, the variables and the summary quantities named",
        "Every evaluation of the objective, and the best so far.",
    ),
    BEARING_GRAPH: Kind(
        "/v1/bearing-graphs",
        "bearing graphs",
        None,
        BearingGraph,
        bearing_variants,
        "capacity or stroke, the toe's Smith soil, and every variant case against the limits",
        "The blow count and the largest stresses against the capacity or the ram's stroke.",
    ),
    DRIVABILITY: Kind(
        "/v1/drivability",
        "drivability",
        None,
        Drivability,
        drivability_variants,
        "the soil's layers and depths against the pile, and every depth's case against the limits",
        "The blow count (and the restrike's) and the largest stresses against the depth.",
    ),
    SIGNAL_MATCH: Kind(
        "/v1/signal-matches",
        "signal matches",
        "match",
        SignalMatch,
        _checked_match,
        "the request's fields, the pile and its Smith toe, the gauges' station, the record's length and units",
        "The force and the waves at the gauges, measured and computed; the fitted resistance along the pile; "
        "the static load test.",
        _driven_case,  # the pile as the record drives it
    ),
}


def studies_router(settings: Settings, queue: JobQueue, kind: str) -> APIRouter:
    """The routes of one kind of study for the results store and broker of `settings`."""
    prefix, tag, answer_name, model, check, checked, plotted, case_of = KINDS[kind]
    plot = STUDY_PLOT[kind]
    router = APIRouter(prefix=prefix, tags=[tag])
    not_found = {404: {"model": Problem, "description": f"no {kind.replace('_', ' ')} with this id"}}

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
        if answer_name is None:
            return record | {"links": links} | (answer or {})
        return record | {"links": links, answer_name: answer}

    examples = EXAMPLES[kind]() if kind in EXAMPLES else None

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
        check(study, settings.limits())
        jobs = store(request)
        record = jobs.create(
            case_of(study),
            kind=kind,
            request=study.model_dump(mode="json", exclude_none=True),
        )
        queue_jobs(jobs, queue, [record["id"]])
        response.headers["Location"] = request.app.url_path_for(f"get_{kind}", study_id=record["id"])
        return view(request, record)

    submit.__doc__ = (
        f"Queue a {kind.replace('_', ' ')}: checked first ({checked}), each refusal naming its field; "
        "then a job on the workers."
    )

    @router.get("/{study_id}", response_model=Study, name=f"get_{kind}", responses=not_found)
    def get(request: Request, study_id: str) -> dict:
        return view(request, record_of(request, study_id))

    get.__doc__ = f"The {kind.replace('_', ' ')}'s status and progress, then its answer " + (
        "(`rows` and the rest beside the record)." if answer_name is None else f"(`{answer_name}`)."
    )

    @router.get(
        "/{study_id}/plot.{fmt}",
        response_class=FileResponse,
        name=f"get_{kind}_plot",
        responses=not_found | {409: {"model": Problem, "description": "not succeeded"}},
    )
    def get_plot(request: Request, study_id: str, fmt: Literal["png", "svg"]) -> FileResponse:
        succeeded(record_of(request, study_id), "plot")
        return FileResponse(store(request).plot_path(study_id, plot, fmt), media_type=FORMATS[fmt])

    get_plot.__doc__ = plotted

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
        f"Cancel the {kind.replace('_', ' ')} if it has not finished (202): a queued one at once, a running "
        "one between two batches. A finished one is removed with its files (204)."
    )
    return router
