"""Error answers: every refused case names its fields, in the words `percussim run` uses.

422 `{"detail": [{"field": "contact.exponent", "message": "must be ≤ 0.5"}, ...]}` for a case
that is invalid or too large, 404 `{"detail": "..."}` for an unknown job; 507 while the results
store cannot write (a full disk) and 503 with `Retry-After` while the database is away, never 500.
"""

from __future__ import annotations

from typing import Any

from fastapi import FastAPI, Request
from fastapi.exception_handlers import http_exception_handler
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse
from pydantic import BaseModel
from starlette.exceptions import HTTPException

from percussim.common.store import StoreFull, StoreUnavailable, UnknownJob, UnknownSweep
from percussim.solver.case import CaseError, FieldError, describe, field_path

RETRY_AFTER_SECONDS = 10  # what a client is told to wait when the broker or the database is down


class FieldErrors(BaseModel):
    """The answer to a refused request: each offending field and why."""

    detail: list[FieldError]


class Problem(BaseModel):
    """An error answer in words."""

    detail: str


def _body_errors(body: Any, errors: list[dict]) -> list[FieldError]:
    """The body's errors, in the words of `percussim run`."""
    if not isinstance(body, dict):
        return [FieldError(field="body", message="must be a JSON object, sent as application/json")]
    return describe([e | {"loc": tuple(e["loc"])[1:]} for e in errors])


def request_errors(exc: RequestValidationError) -> list[FieldError]:
    """A request FastAPI refused, as field paths ("body" stripped) and reasons."""
    described, body = [], []
    for e in exc.errors():
        loc = tuple(e["loc"])
        if e["type"] == "json_invalid":
            described.append(
                FieldError(field="body", message=f"is not valid JSON: {e['ctx']['error']} (at character {loc[1]})")
            )
        elif loc[:1] == ("body",):
            body.append(e)
        else:  # a query or path parameter: "query.limit"
            described.append(FieldError(field=field_path(loc), message=e["msg"]))
    if body:
        described += _body_errors(exc.body, body)
    return described


def _field_errors(errors: list[FieldError]) -> JSONResponse:
    return JSONResponse(status_code=422, content={"detail": [e.model_dump() for e in errors]})


async def _invalid_request(request: Request, exc: RequestValidationError) -> JSONResponse:
    return _field_errors(request_errors(exc))


async def _invalid_case(request: Request, exc: CaseError) -> JSONResponse:
    # Raised by the up-front limits check: the limit and the field that sets it.
    return _field_errors(exc.errors)


async def _unknown_job(request: Request, exc: UnknownJob) -> JSONResponse:
    return JSONResponse(status_code=404, content={"detail": f"no job with id {exc.args[0]!r}"})


async def _http_error(request: Request, exc: HTTPException) -> JSONResponse:
    # FastAPI answers 400 "There was an error parsing the body" when decoding a body fails other
    # than as invalid JSON (a body nested deeper than the parser goes): name the body instead.
    if exc.status_code == 400 and exc.__cause__ is not None:
        cause = exc.__cause__
        reason = (
            "is nested too deeply to read"
            if isinstance(cause, RecursionError)
            else f"could not be read: {type(cause).__name__}"
        )
        return _field_errors([FieldError(field="body", message=reason)])
    return await http_exception_handler(request, exc)


async def _unknown_sweep(request: Request, exc: UnknownSweep) -> JSONResponse:
    return JSONResponse(status_code=404, content={"detail": f"no sweep with id {exc.args[0]!r}"})


async def _store_full(request: Request, exc: StoreFull) -> JSONResponse:
    return JSONResponse(
        status_code=507,
        content={"detail": (f"{exc.strerror}: nothing was stored; free space in the results store, then submit again")},
    )


async def _store_unavailable(request: Request, exc: StoreUnavailable) -> JSONResponse:
    return JSONResponse(
        status_code=503,
        headers={"Retry-After": str(RETRY_AFTER_SECONDS)},
        content={"detail": f"{exc.args[0]}; try again later"},
    )


def install(app: FastAPI) -> None:
    """Register the handlers on `app`; FastAPI's own 404 and 405 answers are left as they are."""
    app.add_exception_handler(RequestValidationError, _invalid_request)
    app.add_exception_handler(CaseError, _invalid_case)
    app.add_exception_handler(UnknownJob, _unknown_job)
    app.add_exception_handler(UnknownSweep, _unknown_sweep)
    app.add_exception_handler(HTTPException, _http_error)
    app.add_exception_handler(StoreFull, _store_full)
    app.add_exception_handler(StoreUnavailable, _store_unavailable)
