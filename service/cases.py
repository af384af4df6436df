"""`/v1/cases/check`: a case checked as `POST /v1/jobs` checks it, and no job made, for a form that
validates as it is typed.

The problems are `POST /v1/jobs`'s 422 `detail` for the same body: the case validated by the same
model, its errors described by the same `errors.request_errors`, then the service's limits by the
same `check_case`. A body that is JSON but not an object is a problem like any other (`body: must
be a JSON object`); one that is not JSON at all is refused with 422 before any check, as
`POST /v1/jobs` refuses it.
"""

from typing import Annotated, Any

from fastapi import APIRouter, Body
from fastapi.exceptions import RequestValidationError
from pydantic import BaseModel, ValidationError

from percussim.common.settings import Settings
from percussim.solver.case import Case, CaseError, FieldError
from percussim.solver.limits import check_case

from .errors import FieldErrors, request_errors


class CaseCheck(BaseModel):
    """Whether `POST /v1/jobs` would take the case, and if not, every field it would name."""

    valid: bool
    problems: list[FieldError]


def case_problems(body: Any, settings: Settings) -> list[FieldError]:
    """What `POST /v1/jobs` would refuse in `body`, JSON as Python: its 422 `detail`."""
    try:
        case = Case.model_validate(body)
    except ValidationError as error:
        # Under "body", as FastAPI reports a body it refuses to the same handler.
        refused = [e | {"loc": ("body", *e["loc"])} for e in error.errors(include_url=False)]
        return request_errors(RequestValidationError(refused, body=body))
    try:
        check_case(case, settings.limits())
    except CaseError as error:
        return error.errors
    return []


def cases_router(settings: Settings) -> APIRouter:
    router = APIRouter(prefix="/v1/cases", tags=["cases"])

    @router.post(
        "/check",
        response_model=CaseCheck,
        responses={422: {"model": FieldErrors, "description": "the body is not JSON"}},
    )
    def check_a_case(body: Annotated[Any, Body(description="a case, valid or not")] = None) -> dict:
        """Check a case as `POST /v1/jobs` would, its fields and the service's limits, and queue
        nothing: `problems` is what that 422 would name, empty when the case would be taken."""
        problems = case_problems(body, settings)
        return {"valid": not problems, "problems": problems}

    return router
