"""`/v1/jobs`: submit a case, follow its job, fetch its summary, result, plots and the plots' data
(series), cancel it.

The routes only validate, publish and read the results store the workers write. No
`from __future__ import annotations` here: FastAPI must see the request examples, a local of
`jobs_router`, in the signature of `submit`.
"""

import base64
import re
from datetime import datetime
from pathlib import Path
from typing import Annotated, Any, Literal
from urllib.parse import urlencode

from fastapi import APIRouter, Body, HTTPException, Query, Request, Response
from fastapi.responses import FileResponse, StreamingResponse
from pydantic import BaseModel, ConfigDict, Field

from percussim.common.settings import Settings
from percussim.common.store import CANCELLED, FAILED, SUCCEEDED, JobStore, UnknownJob
from percussim.solver import series
from percussim.solver.case import Case, CaseError, FieldError
from percussim.solver.limits import check_case
from percussim.solver.plots import FORMATS, PLOTS, NotAvailable, parse_times, problems, render
from percussim.solver.summary import Summary

from .errors import RETRY_AFTER_SECONDS, FieldErrors, Problem
from .queue import JobQueue

Status = Literal["queued", "running", "succeeded", "failed", "cancelled"]


class Links(BaseModel):
    self: str
    summary: str
    result: str
    plots: str


class Job(BaseModel):
    """A job's record in the results store, with the links to follow it."""

    model_config = ConfigDict(extra="allow")  # whatever else the store records is passed on

    id: str
    name: str | None
    status: Status
    progress: float
    created: datetime
    started: datetime | None
    finished: datetime | None
    error: str | None
    links: Links


class JobList(BaseModel):
    total: int
    offset: int
    limit: int
    jobs: list[Job]
    next: str | None  # the next page, by creation time (`cursor`), or null on the last page


def _view(request: Request, record: dict) -> dict:
    """The record with its links (paths relative to the API's root)."""
    job_id = record["id"]
    return record | {
        "links": {
            "self": request.app.url_path_for("get_job", job_id=job_id),
            "summary": request.app.url_path_for("get_summary", job_id=job_id),
            "result": request.app.url_path_for("get_result", job_id=job_id),
            "plots": request.app.url_path_for("list_plots", job_id=job_id),
        }
    }


def succeeded(record: dict, what: str) -> dict:
    """The record of a job that has succeeded; else 409 naming its status (and its error if it
    failed) and that it has no `what` yet."""
    status = record["status"]
    if status == SUCCEEDED:
        return record
    if status == FAILED:
        detail = f"job {record['id']} failed, so it has no {what}: {record['error']}"
    elif status == CANCELLED:
        detail = f"job {record['id']} was cancelled, so it has no {what}"
    else:
        detail = f"job {record['id']} is {status}: its {what} is ready once it has succeeded"
    raise HTTPException(status_code=409, detail=detail)


class PlotLinks(BaseModel):
    png: str
    svg: str


class Plot(BaseModel):
    """A plot of the result: whether this result can make it, and if not, what to change."""

    name: str
    title: str
    available: bool
    reason: str | None
    links: PlotLinks


class PlotList(BaseModel):
    plots: list[Plot]


class SeriesLinks(BaseModel):
    json_: str = Field(alias="json")  # not `json`, which BaseModel has
    csv: str


class Series(BaseModel):
    """The data of an interactive plot: whether this result can give it, and if not, what to change."""

    name: str
    title: str
    available: bool
    reason: str | None
    links: SeriesLinks


class SeriesList(BaseModel):
    series: list[Series]


def _download_name(record: dict, suffix: str = ".h5") -> str:
    """`<name>-<id><suffix>`, the name reduced to characters safe in any file system."""
    name = re.sub(r"[^A-Za-z0-9_.-]+", "_", record.get("name") or "case").strip("._") or "case"
    return f"{name}-{record['id']}{suffix}"


def cancel_or_delete(jobs: JobStore, record: dict, view, what: str = "job") -> dict | Response:
    """DELETE on a job: cancel it if it has not finished (202 and its record: a queued one is
    cancelled at once, a running one by its worker), else remove it and its files (204). A
    variant of a sweep is removed only with its sweep."""
    cancelled = jobs.request_cancel(record["id"])
    if cancelled is not None:
        return view(cancelled)
    if record["sweep"] is not None:
        raise HTTPException(
            status_code=409,
            detail=(
                f"{what} {record['id']} is a variant of sweep {record['sweep']}: it is removed with its "
                f"sweep (DELETE /v1/sweeps/{record['sweep']}?purge=true)"
            ),
        )
    if not jobs.delete(record["id"]):
        raise UnknownJob(record["id"])  # someone else removed it meanwhile
    return Response(status_code=204)


def _cursor(record: dict) -> str:
    return base64.urlsafe_b64encode(f"{record['created']}|{record['id']}".encode()).decode()


def _parse_cursor(cursor: str) -> tuple[datetime, str]:
    try:
        created, job_id = base64.urlsafe_b64decode(cursor.encode()).decode().split("|")
        return datetime.fromisoformat(created), job_id
    except ValueError:
        raise CaseError(
            [
                FieldError(
                    field="query.cursor",
                    message=("is not a cursor of this list: pass the `next` link of the page before"),
                )
            ]
        ) from None


def queue_jobs(jobs: JobStore, queue: JobQueue, job_ids: list[str]) -> None:
    """Publish the jobs; if the broker cannot take them, record why in each and answer 503."""
    error = queue.enqueue_or_fail(jobs, job_ids, "the job could not be queued")
    if error is not None:
        raise HTTPException(
            status_code=503,
            headers={"Retry-After": str(RETRY_AFTER_SECONDS)},
            detail=f"the job queue is unavailable ({queue.describe()}: {error}); "
            "nothing was queued: submit again later",
        )


def jobs_router(settings: Settings, queue: JobQueue, examples: dict[str, Any] | None) -> APIRouter:
    """The job routes for the results store and broker of `settings`."""
    router = APIRouter(prefix="/v1/jobs", tags=["jobs"])
    not_found = {404: {"model": Problem, "description": "no job with this id"}}
    not_ready = {409: {"model": Problem, "description": "the job has not succeeded"}}

    def store(request: Request) -> JobStore:
        return JobStore(settings, owner=request.state.owner)

    @router.post(
        "",
        status_code=202,
        response_model=Job,
        responses={
            422: {"model": FieldErrors, "description": "the case is invalid or exceeds a limit"},
            503: {"model": Problem, "description": "the broker is unreachable; retry later"},
        },
    )
    def submit(request: Request, response: Response, case: Annotated[Case, Body(openapi_examples=examples)]) -> dict:
        """Queue an impact case. A case over the size limits is refused here, naming the limit."""
        check_case(case, settings.limits())
        jobs = store(request)
        record = jobs.create(case.model_dump(mode="json", exclude_none=True))
        queue_jobs(jobs, queue, [record["id"]])
        view = _view(request, record)
        response.headers["Location"] = view["links"]["self"]
        return view

    @router.get("", response_model=JobList, responses={422: {"model": FieldErrors}})
    def list_jobs(
        request: Request,
        offset: Annotated[int, Query(ge=0, le=10**9)] = 0,
        limit: Annotated[int, Query(ge=1, le=500)] = 50,
        status: Annotated[Status | None, Query(description="only jobs of this status")] = None,
        name: Annotated[str | None, Query(description="only jobs of cases of this name")] = None,
        sweep: Annotated[str | None, Query(description="only the variants of this sweep")] = None,
        cursor: Annotated[str | None, Query(description="the page after the one whose `next` link gave it")] = None,
    ) -> dict:
        """Recent jobs, newest first, a page at a time: `next` links the page after (by creation
        time, as fast at the thousandth page as at the first); `total` counts the jobs that match."""
        before = None if cursor is None else _parse_cursor(cursor)
        total, records = store(request).list(offset, limit, status=status, name=name, sweep=sweep, before=before)
        following = None
        if len(records) == limit:
            query = {"limit": limit, "status": status, "name": name, "sweep": sweep, "cursor": _cursor(records[-1])}
            following = (
                request.app.url_path_for("list_jobs")
                + "?"
                + urlencode({k: v for k, v in query.items() if v is not None})
            )
        return {
            "total": total,
            "offset": offset,
            "limit": limit,
            "jobs": [_view(request, r) for r in records],
            "next": following,
        }

    @router.get("/{job_id}", response_model=Job, responses=not_found)
    def get_job(request: Request, job_id: str) -> dict:
        """A job's status, progress (0..1), timestamps and error."""
        return _view(request, store(request).get(job_id))

    @router.get("/{job_id}/case", responses=not_found)
    def get_case(request: Request, job_id: str) -> dict:
        """The case as the job runs it (defaults spelled out), whatever its status: to edit it
        again, or to see how two jobs differ."""
        jobs = store(request)
        jobs.get(job_id)  # 404 for an unknown job, or another owner's
        return jobs.case(job_id)

    @router.get("/{job_id}/summary", response_model=Summary, responses=not_found | not_ready)
    def get_summary(request: Request, job_id: str) -> dict:
        """The pulse summary of a succeeded job."""
        jobs = store(request)
        succeeded(jobs.get(job_id), "summary")
        return jobs.summary(job_id)

    @router.get(
        "/{job_id}/result.h5",
        response_class=FileResponse,
        responses=not_found
        | not_ready
        | {200: {"content": {"application/x-hdf5": {}}, "description": "the HDF5 result"}},
    )
    def get_result(request: Request, job_id: str) -> FileResponse:
        """The HDF5 result of a succeeded job."""
        jobs = store(request)
        record = succeeded(jobs.get(job_id), "result")
        return FileResponse(jobs.result_path(job_id), media_type="application/x-hdf5", filename=_download_name(record))

    @router.get("/{job_id}/plots", response_model=PlotList, responses=not_found | not_ready)
    def list_plots(request: Request, job_id: str) -> dict:
        """The plots of a succeeded job's result: which this result can make, why not the
        others, and where to get each as PNG or SVG."""
        jobs = store(request)
        succeeded(jobs.get(job_id), "plots")
        reasons = problems(jobs.result_path(job_id))
        return {
            "plots": [
                {
                    "name": name,
                    "title": title,
                    "available": reasons[name] is None,
                    "reason": reasons[name],
                    "links": {
                        fmt: request.app.url_path_for("get_plot", job_id=job_id, name=name, fmt=fmt) for fmt in FORMATS
                    },
                }
                for name, title in PLOTS.items()
            ]
        }

    binary = {"schema": {"type": "string", "format": "binary"}}

    @router.get(
        "/{job_id}/plots/{name}.{fmt}",
        response_class=FileResponse,
        responses={
            200: {"content": {media: binary for media in FORMATS.values()}, "description": "the plot"},
            404: {
                "model": Problem,
                "description": "no job with this id, no plot with this name, or a "
                "plot this result cannot make (the reason says why)",
            },
            422: {
                "model": FieldErrors,
                "description": "times that are not numbers, outside the run's fields, "
                "or given for a plot other than stress_along",
            },
        }
        | not_ready,
    )
    def get_plot(
        request: Request,
        job_id: str,
        name: str,
        fmt: Literal["png", "svg"],
        times: Annotated[
            str | None,
            Query(
                description="stress_along only: the times (s) of its curves, e.g. 5e-5,1e-4,1.5e-4 "
                "(default: spread over the first contact)"
            ),
        ] = None,
    ) -> Response:
        """A plot of a succeeded job's result (the names are in `/plots`), drawn once and then kept;
        stress_along at chosen `times` is drawn each time it is asked for."""
        jobs = store(request)
        record = jobs.get(job_id)
        # The name is checked before any path is made from it.
        if name not in PLOTS:
            raise HTTPException(status_code=404, detail=f"no plot named {name!r}; the plots are: {', '.join(PLOTS)}")
        if times is not None and name != "stress_along":
            raise CaseError([FieldError(field="query.times", message="only the stress_along plot takes times")])
        succeeded(record, "plots")
        kept, result = jobs.plot_path(job_id, name, fmt), jobs.result_path(job_id)
        try:
            if times is not None:
                return Response(render(result, name, fmt, parse_times(times)), media_type=FORMATS[fmt])
            # Kept plots older than the result (a job written again) are drawn again.
            if not (kept.is_file() and kept.stat().st_mtime >= result.stat().st_mtime):
                jobs.write_plot(job_id, name, fmt, render(result, name, fmt))
        except NotAvailable as error:
            raise HTTPException(status_code=404, detail=f"job {job_id} has no {name} plot: {error}") from None
        except ValueError as error:
            if times is None:
                raise
            # Times that are not numbers, or outside the run's fields.
            raise CaseError([FieldError(field="query.times", message=str(error))]) from None
        return FileResponse(kept, media_type=FORMATS[fmt])

    @router.get("/{job_id}/series", response_model=SeriesList, responses=not_found | not_ready)
    def list_series(request: Request, job_id: str) -> dict:
        """The data of the job page's interactive plots: which this result can give, why not the
        others, and where to get each as JSON (downsampled for a screen) or CSV (every sample)."""
        jobs = store(request)
        succeeded(jobs.get(job_id), "series")
        reasons = series.problems(jobs.result_path(job_id))
        return {
            "series": [
                {
                    "name": name,
                    "title": title,
                    "available": reasons[name] is None,
                    "reason": reasons[name],
                    "links": {
                        "json": request.app.url_path_for("get_series", job_id=job_id, name=name),
                        "csv": request.app.url_path_for("get_series_csv", job_id=job_id, name=name),
                    },
                }
                for name, title in series.SERIES.items()
            ]
        }

    def series_result(request: Request, job_id: str, name: str) -> tuple[dict, Path]:
        """The job's record and result, once it is known to have series `name`."""
        jobs = store(request)
        record = jobs.get(job_id)
        if name not in series.SERIES:
            raise HTTPException(
                status_code=404, detail=(f"no series named {name!r}; the series are: {', '.join(series.SERIES)}")
            )
        succeeded(record, "series")
        result = jobs.result_path(job_id)
        reason = series.problems(result)[name]
        if reason:
            raise HTTPException(status_code=404, detail=f"job {job_id} has no {name} series: {reason}")
        return record, result

    no_series = {
        404: {
            "model": Problem,
            "description": "no job with this id, no series with this name, or "
            "one this result cannot give (the reason says why)",
        }
    }

    # Before /series/{name}, which would take "force.csv" for a name.
    @router.get(
        "/{job_id}/series/{name}.csv",
        response_class=StreamingResponse,
        responses=no_series
        | {
            200: {"content": {"text/csv": {}}, "description": "every sample, a header of names and units"},
        }
        | not_ready,
    )
    def get_series_csv(request: Request, job_id: str, name: str) -> StreamingResponse:
        """A series of a succeeded job's result as CSV, every sample: a row a sample (a frame, for
        the fields), a column a curve (a station); streamed as it is read."""
        record, result = series_result(request, job_id, name)
        filename = _download_name(record, f"-{name}.csv")
        return StreamingResponse(
            series.csv_chunks(result, name),
            media_type="text/csv; charset=utf-8",
            headers={"Content-Disposition": f'attachment; filename="{filename}"'},
        )

    @router.get(
        "/{job_id}/series/{name}",
        responses=no_series
        | {
            200: {"content": {"application/json": {}}, "description": "the series, SI units"},
            422: {"model": FieldErrors, "description": "a count out of range, or one the series does not take"},
        }
        | not_ready,
    )
    def get_series(
        request: Request,
        job_id: str,
        name: str,
        points: Annotated[
            int | None,
            Query(
                ge=0,
                le=10**7,
                description=(
                    f"a curve's samples, about (default {series.DEFAULT_POINTS}; 0: every one, up "
                    f"to {series.MAX_POINTS}); min–max decimated, so every peak is kept"
                ),
            ),
        ] = None,
        times: Annotated[
            int | None,
            Query(
                ge=0,
                le=10**7,
                description=(
                    f"fields only: frames (default {series.DEFAULT_TIMES}; 0: all, up to {series.MAX_FIELD_SIDE})"
                ),
            ),
        ] = None,
        stations: Annotated[
            int | None,
            Query(
                ge=0,
                le=10**7,
                description=(
                    f"fields only: stations along the tool (default {series.DEFAULT_STATIONS}; "
                    f"0: all, up to {series.MAX_FIELD_SIDE})"
                ),
            ),
        ] = None,
    ) -> Response:
        """A series of a succeeded job's result (the names are in `/series`), downsampled for a
        screen: the curves of a plot, each its own x and y, or the stress field σ(x, t)."""
        _, result = series_result(request, job_id, name)
        counts = {"points": points, "times": times, "stations": stations}
        taken = ("times", "stations") if name == series.FIELDS else ("points",)
        refused = [
            FieldError(field=f"query.{query}", message=f"the {name} series takes {' and '.join(taken)}, not {query}")
            for query, value in counts.items()
            if value is not None and query not in taken
        ]
        if refused:
            raise CaseError(refused)
        data = series.series(result, name, **{query: value for query, value in counts.items() if value is not None})
        return Response(series.dumps(data), media_type="application/json")

    @router.delete(
        "/{job_id}",
        status_code=202,
        response_model=Job,
        responses=not_found
        | {
            204: {"description": "the job had finished: it and its files are removed"},
            409: {"model": Problem, "description": "a finished variant of a sweep: removed with its sweep"},
        },
    )
    def delete_job(request: Request, job_id: str):
        """Cancel a job that has not finished (202): a queued one at once, a running one between
        two chunks of its run. A finished job is removed with its files (204; then 404)."""
        jobs = store(request)
        return cancel_or_delete(jobs, jobs.get(job_id), lambda record: _view(request, record))

    @router.post(
        "/{job_id}/cancel",
        status_code=202,
        response_model=Job,
        responses=not_found | {409: {"model": Problem, "description": "the job has already finished"}},
    )
    def cancel_job(request: Request, job_id: str) -> dict:
        """Cancel a job (or a study) that has not finished, as DELETE does, but never remove one
        that has: 409 then. For a client that must not lose a result finished meanwhile."""
        jobs = store(request)
        cancelled = jobs.request_cancel(job_id)
        if cancelled is None:
            raise HTTPException(
                status_code=409, detail=f"job {job_id} has already finished: it is {jobs.get(job_id)['status']}"
            )
        return _view(request, cancelled)

    return router
