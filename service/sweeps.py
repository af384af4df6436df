"""`/v1/sweeps`: a parameter study fanned out over the workers, read back as one table.

Each variant is an ordinary job (its own record, summary and HDF5 result); the sweep's record says
which job has which parameter values, and the table is read from the jobs' summaries.
"""

from collections import Counter
from typing import Annotated, Any

from fastapi import APIRouter, Body, HTTPException, Query, Request, Response
from pydantic import BaseModel

from percussim.common.settings import Settings
from percussim.common.store import FAILED, FINISHED, SUCCEEDED, JobStore, SweepStore
from percussim.solver.presets import preset_json, preset_names
from percussim.solver.sweep import COLUMNS, Sweep, table_row, variants

from .errors import FieldErrors, Problem
from .jobs import queue_jobs
from .queue import JobQueue


class SweepView(BaseModel):
    """A sweep: how far it is, and a row per variant (parameter values, status, results)."""

    id: str
    name: str | None
    created: str
    parameters: list[str]
    total: int
    counts: dict[str, int]
    progress: float
    finished: bool
    columns: list[str]
    rows: list[dict[str, Any]]


# The request examples: (name, preset, summary, parameters), each offered when its preset is there.
EXAMPLES = (
    (
        "fig5-velocity-stiffness",
        "fig5",
        "Fig. 5: striker velocity × contact stiffness (6 variants)",
        {"striker.velocity": [3.0, 5.0, 7.0], "contact.stiffness": [4e11, 8e11]},
    ),
    (
        "rock_drill-piston-length",
        "rock_drill",
        "Rock drill: piston length (its efficiency rises to Lundberg's optimum, then falls) × the rock's "
        "unloading stiffness (6 variants)",
        {"striker.length": [0.15, 0.3, 0.6], "medium.unloading_stiffness": [2e9, 5e9]},
    ),
    (
        "pile-quake-blows",
        "pile",
        "Pile: the toe's quake × blows (6 variants)",
        {"medium.quake": [1.5e-3, 2.54e-3, 5e-3], "blows.count": [1, 3]},
    ),
)


def _example() -> dict | None:
    known = preset_names()
    examples = {
        name: {"summary": summary, "value": {"case": preset_json(preset), "parameters": parameters}}
        for name, preset, summary, parameters in EXAMPLES
        if preset in known
    }
    return examples or None


def sweeps_router(settings: Settings, queue: JobQueue) -> APIRouter:
    """The sweep routes for the results store and broker of `settings`."""
    router = APIRouter(prefix="/v1/sweeps", tags=["sweeps"])
    not_found = {404: {"model": Problem, "description": "no sweep with this id"}}

    def stores(request: Request) -> tuple[JobStore, SweepStore]:
        jobs = JobStore(settings, owner=request.state.owner)
        return jobs, SweepStore(jobs)

    def view(request: Request, record: dict) -> dict:
        jobs, _ = stores(request)
        _, records = jobs.list(limit=len(record["variants"]), sweep=record["id"])
        of = {job["id"]: job for job in records}
        rows, counts, progress = [], Counter(), 0.0
        for variant in record["variants"]:
            job = of[variant["job"]]
            counts[job["status"]] += 1
            progress += 1.0 if job["status"] in FINISHED else job["progress"]
            row = {"job": job["id"], "values": variant["values"], "status": job["status"]}
            if job["status"] == SUCCEEDED:
                row |= table_row(jobs.summary(job["id"]))
            elif job["status"] == FAILED:
                row["error"] = job["error"]
            rows.append(row)
        total = len(rows)
        return {
            **{k: record[k] for k in ("id", "name", "created", "parameters")},
            "total": total,
            "counts": dict(counts),
            "progress": progress / total,
            "finished": sum(counts[s] for s in FINISHED) == total,
            "columns": [name for name, _ in COLUMNS] + ["warnings"],
            "rows": rows,
        }

    @router.post(
        "",
        status_code=202,
        response_model=SweepView,
        responses={
            422: {"model": FieldErrors, "description": "a variant is invalid or exceeds a limit"},
            503: {"model": Problem, "description": "the broker is unreachable; retry later"},
        },
    )
    def submit_sweep(
        request: Request, response: Response, sweep: Annotated[Sweep, Body(openapi_examples=_example())]
    ) -> dict:
        """Queue every combination of the parameters' values as a job of its own, at once over
        all workers. Every variant is validated and checked against the limits first: one bad
        variant refuses the sweep, naming the parameter value it came from."""
        found = variants(sweep, max_variants=settings.max_sweep_variants, limits=settings.limits())
        jobs, sweeps = stores(request)
        record = sweeps.create(
            sweep.case.name,
            list(sweep.parameters),
            [(values, case.model_dump(mode="json", exclude_none=True)) for values, case in found],
        )
        queue_jobs(jobs, queue, [variant["job"] for variant in record["variants"]])
        response.headers["Location"] = request.app.url_path_for("get_sweep", sweep_id=record["id"])
        return view(request, record)

    @router.get("/{sweep_id}", response_model=SweepView, responses=not_found)
    def get_sweep(request: Request, sweep_id: str) -> dict:
        """The sweep's progress and its table: a row per variant, filled in as its job succeeds."""
        return view(request, stores(request)[1].get(sweep_id))

    @router.delete(
        "/{sweep_id}",
        status_code=202,
        response_model=SweepView,
        responses=not_found
        | {
            204: {"description": "purged: the sweep and its jobs are removed"},
            409: {"model": Problem, "description": "purge asked while some variants have not finished"},
        },
    )
    def delete_sweep(
        request: Request,
        sweep_id: str,
        purge: Annotated[bool, Query(description="remove the finished sweep and its jobs")] = False,
    ):
        """Cancel every variant that has not finished (202); with `purge=true`, remove a sweep
        whose variants have all finished, with their jobs and files (204; then 404)."""
        jobs, sweeps = stores(request)
        record = sweeps.get(sweep_id)
        if purge:
            if not sweeps.purge(sweep_id):
                unfinished = sum(
                    1
                    for job in jobs.list(limit=len(record["variants"]), sweep=sweep_id)[1]
                    if job["status"] not in FINISHED
                )
                raise HTTPException(
                    status_code=409,
                    detail=(
                        f"sweep {sweep_id} has {unfinished} variant(s) not finished: cancel them "
                        "(DELETE without purge) or wait, then purge"
                    ),
                )
            return Response(status_code=204)
        for variant in record["variants"]:
            jobs.request_cancel(variant["job"])
        return view(request, record)

    return router
