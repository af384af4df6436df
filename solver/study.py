"""What a calibration and an optimisation ask (`Calibration`, `Optimization`), and the checks
made before any of their runs: the fields, the bounds, the record against the case and its units,
the summary quantities named. Neither SciPy nor the kernel is loaded by importing this module,
so that the service validates a request as cheaply as a case; the units check runs the model,
and loads the kernel then."""

from __future__ import annotations

import types
import typing
from typing import Any

import numpy as np
from pydantic import BaseModel, Field, model_validator

from .case import INPUT, Case, CaseError, FieldError, Numerics, Whole, field_error, validated
from .evaluate import Batch, Space, check_grid, evaluate_batch
from .grid import fewest_cells, first_cells
from .limits import Limits
from .record import Record
from .summary import Summary

OFFSET = "record.time_offset"  # a parameter of the fit that is the record's, not the case's
UNITS_FACTOR = 30.0  # a record this far above or below every model's peak has the wrong units
COARSE_TOLERANCE = 0.1  # of the grid of the units check: a peak within tens of percent is enough
EXAMPLE_QUANTITIES = (
    "energy.transfer_efficiency",
    "max_compressive_stress",
    "peak_contact_force",
    "energy.to_medium",
    "medium_penetration.permanent",
)


class Calibration(BaseModel):
    """A case, a measured record, and the parameters to fit with their bounds."""

    model_config = INPUT

    case: Case
    record: Record
    parameters: dict[str, list[float]] = Field(
        min_length=1, description="dotted field path → [low, high], the bounds of the fit"
    )


STUDY_NUMERICS = ("duration", "tolerance")  # what a study reads of a case's numerics


def study_case(case: Case, tolerance: float | None = None) -> Case:
    """The case as a study runs it: every run on the study's own grid (the explicit scheme at
    Courant number 1, chosen for the tolerance), so of its numerics only the duration and the
    tolerance (`tolerance` when given) are kept; a fixed grid it gives is set aside."""
    kept = Numerics(duration=case.numerics.duration, tolerance=tolerance or case.numerics.tolerance)
    return case.model_copy(update={"numerics": kept})


def set_aside(case: Case) -> list[str]:
    """A warning naming the numerics a study does not use, if the case gives any."""
    given = [
        f"numerics.{name}" for name in case.numerics.model_dump(exclude_defaults=True) if name not in STUDY_NUMERICS
    ]
    if not given:
        return []
    return [
        f"{', '.join(given)} {'is' if len(given) == 1 else 'are'} set aside: a study runs every "
        "case on its own grid, the explicit scheme at Courant number 1, chosen for "
        "numerics.tolerance (0.01 when not given)"
    ]


def parse_calibration(data: dict) -> Calibration:
    """Validate a calibration given as JSON; `CaseError` names each bad field."""
    return validated(Calibration, data)


def fitted_bounds(calibration: Calibration) -> dict[str, list[float]]:
    """The parameters to fit and their bounds: the request's, and the record's time_offset when
    it is fitted by default (neither given nor in the parameters, and the record does not start
    at rest: `Record.offset_bounds`). Refuses a time_offset both given and fitted."""
    bounds = dict(calibration.parameters)
    record = calibration.record
    if OFFSET in bounds and record.time_offset is not None:
        raise CaseError(
            [
                FieldError(
                    field=f"parameters[{OFFSET!r}]",
                    message=(
                        f"the record gives time_offset = {record.time_offset:g} s: leave it out of the record "
                        "to fit it here, or out of the parameters to keep it"
                    ),
                )
            ]
        )
    if OFFSET not in bounds and record.time_offset is None and not record.starts_at_rest():
        bounds[OFFSET] = list(record.offset_bounds(calibration.case))
    return bounds


def run_span(record: Record, space: Space) -> float:
    """How long the study's runs last (s of the model's time): to the record's last sample at the
    latest time_offset the fit may try."""
    offset = space.high[space.paths.index(OFFSET)] if OFFSET in space.paths else record.time_offset or 0.0
    return float(record.instants[-1] + offset)


# What a user can change when a study's grid is over the limits: not the case's grid, which a study
# sets aside (`study_case`).
GRID_REMEDY = (
    "the fit refines its grid until its values settle and the record's length sets the runs': "
    "shorten the record, or raise the limit"
)
DURATION_REMEDY = (
    "the study chooses its grid for numerics.tolerance: shorten numerics.duration, "
    "loosen numerics.tolerance, or raise the limit"
)


def check_calibration(calibration: Calibration, limits: Limits = Limits()) -> Space:
    """Refuse, naming the field, what no fit can use: a record the case cannot produce, a
    parameter that is not a number of the case or bounds it cannot take, and a record whose peak
    is `UNITS_FACTOR` or more from the model's at every corner of the bounds (its units are off),
    from quick runs on a coarse grid the case accepts. Returns the parameters' space (the
    record's time_offset among them when it is fitted)."""
    case, record = study_case(calibration.case), calibration.record
    space = Space.of(fitted_bounds(calibration), "parameters")
    case_space = space.without(OFFSET)
    duration = run_span(record, space)
    record.check_against(case, end=duration)
    if case_space.paths:
        case_space.check(case, "parameters")
    corners = case_space.corners(case)
    coarse = max([first_cells(case, COARSE_TOLERANCE)] + [fewest_cells(corner) for corner in corners])
    check_grid(case, coarse, duration, limits, field="record.time", remedy=GRID_REMEDY)
    answers = evaluate_batch(
        Batch(
            cases=[
                corner.model_dump(mode="json", exclude_none=True) | {"outputs": record.outputs()} for corner in corners
            ],
            cells=coarse,
            duration=duration,
            series={"quantity": record.quantity, "times": None},
            quantities=None,
        )
    )
    peaks = [float(np.max(np.abs(a["series"]))) for a in answers if "series" in a]
    if peaks:
        _check_units(record, peaks)
    return space


def _check_units(record: Record, peaks: list[float]) -> None:
    peak = float(np.max(np.abs(record.values)))
    low, high = min(peaks), max(peaks)
    if peak > UNITS_FACTOR * high or peak < low / UNITS_FACTOR:
        ratio = peak / high if peak > high else peak / low
        raise CaseError(
            [
                FieldError(
                    field="record.values",
                    message=(
                        f"the record's peak |{record.quantity}| is {peak:.4g} {record.unit}, {ratio:.3g}× the "
                        f"model's ({low:.4g} to {high:.4g} {record.unit} at the bounds' corners): give the record in "
                        f"SI units ({record.unit}); a factor near 1000 is a unit off by a prefix (kN, MPa, mm/s)"
                    ),
                )
            ]
        )


class Objective(BaseModel):
    """The summary quantity to maximise or to minimise (one of the two)."""

    model_config = INPUT

    maximize: str | None = None
    minimize: str | None = None

    @model_validator(mode="after")
    def _one(self) -> Objective:
        if (self.maximize is None) == (self.minimize is None):
            raise field_error(
                "Objective",
                ("maximize",),
                "give one of maximize or minimize, with a summary quantity such as energy.transfer_efficiency",
                None,
            )
        return self

    @property
    def quantity(self) -> str:
        return self.maximize or self.minimize

    @property
    def goal(self) -> str:
        """'maximize' or 'minimize'."""
        return "maximize" if self.maximize is not None else "minimize"

    @property
    def sign(self) -> float:
        """+1 to minimise, −1 to maximise: what the optimiser minimises is sign × quantity."""
        return -1.0 if self.maximize is not None else 1.0


class Bound(BaseModel):
    """A limit on a summary quantity: at most `max`, at least `min`, or both."""

    model_config = INPUT

    max: float | None = None
    min: float | None = None

    @model_validator(mode="after")
    def _some(self) -> Bound:
        if self.max is None and self.min is None:
            raise field_error("Bound", ("max",), "give max, min or both", None)
        if self.max is not None and self.min is not None and self.min > self.max:
            raise field_error("Bound", ("min",), f"must be ≤ max = {self.max:g}", self.min)
        return self


class Optimization(BaseModel):
    """A case, the fields to vary with their bounds, the objective and the limits."""

    model_config = INPUT

    case: Case
    variables: dict[str, list[float]] = Field(min_length=1, description="dotted field path → [low, high]")
    objective: Objective
    limits: dict[str, Bound] = Field(default_factory=dict, description="summary quantity → its {max} and/or {min}")
    max_evaluations: Whole = Field(
        default=1000,
        ge=10,
        le=100_000,
        description="the budget of model runs: 80% for the global stage, the rest "
        "for the local stage (a stage stops at the end of the "
        "generation or iteration that reaches it)",
    )
    seed: Whole = Field(default=0, ge=0, description="of the global stage's random choices")


def parse_optimization(data: dict) -> Optimization:
    """Validate an optimisation given as JSON; `CaseError` names each bad field."""
    return validated(Optimization, data)


def _present(annotation: Any) -> Any:
    """`X` of an optional `X | None`; any other annotation as it is."""
    args = [a for a in typing.get_args(annotation) if a is not type(None)]
    optional = typing.get_origin(annotation) in (typing.Union, types.UnionType)
    return args[0] if optional and len(args) == 1 else annotation


def _summary_has(path: str) -> bool:
    """Whether `path` names a number of the pulse summary's schema (a peak by its value; a list's
    item by its index), without a run."""
    model: Any = Summary
    for key in path.split("."):
        model = _present(model)
        if typing.get_origin(model) is list:
            if not key.lstrip("-").isdigit():
                return False
            model = typing.get_args(model)[0]
        elif isinstance(model, type) and issubclass(model, BaseModel) and key in model.model_fields:
            model = model.model_fields[key].annotation
        else:
            return False
    target = _present(model)
    if isinstance(target, type) and issubclass(target, BaseModel):
        return "value" in target.model_fields
    return target in (float, int)


def quantity_fields(request: Optimization) -> dict[str, str]:
    """Each summary quantity a request names → the request's field that names it."""
    return {request.objective.quantity: f"objective.{request.objective.goal}"} | {
        name: f"limits[{name!r}]" for name in request.limits
    }


def check_optimization(request: Optimization, limits: Limits = Limits()) -> Space:
    """Refuse, naming the field, variables the case cannot take and quantities the summary does
    not have, and a study whose least grid (the fewest cells every point within the bounds takes)
    is over the limits, without a run (the service's check before it queues). Returns the
    variables' space."""
    space = Space.of(request.variables, "variables")
    case = study_case(request.case)
    space.check(case, "variables")
    check_grid(
        case,
        space.fewest_cells(case),
        case.numerics.duration,
        limits,
        field="case.numerics.duration",
        remedy=DURATION_REMEDY,
    )
    errors = [
        FieldError(
            field=field,
            message=(
                f"{name!r} is not a number of the pulse summary: give a summary quantity such as "
                + ", ".join(EXAMPLE_QUANTITIES)
            ),
        )
        for name, field in quantity_fields(request).items()
        if not _summary_has(name)
    ]
    if errors:
        raise CaseError(errors)
    return space
