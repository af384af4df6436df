"""A measured record: a time series of one quantity a run also computes, in SI units.

`Record` refuses what no fit can use (times that do not increase, non-finite values, too few
samples) naming the field; `check_against` refuses what does not fit the case (a gauge off the
tool, a medium force with no medium, a record longer than the case); `series` reads the same
quantity from a run at the record's instants. Time 0 is the impact: the first contact's start.

CSV: a header `time,<quantity>`, with the quantity one of `contact_force`, `medium_force`,
`stress@X` (stress at x = X m in the tool, compression negative), `struck_end_velocity`,
`working_end_velocity`; then one sample a line.
"""

from __future__ import annotations

import csv
import io
import os
from pathlib import Path
from typing import Literal

import numpy as np
from pydantic import BaseModel, Field, model_validator

from .case import INPUT, Case, CaseError, FieldError, field_error, validated

MIN_SAMPLES = 20  # fewer say too little about any parameter's effect on the pulse
MAX_SAMPLES = 200_000

# quantity → (its history's path, its unit)
QUANTITIES = {
    "contact_force": ("contact/force", "N"),
    "medium_force": ("medium/force", "N"),
    "stress": ("probes/stress", "Pa"),
    "struck_end_velocity": ("tool/struck_end_displacement", "m/s"),  # differentiated
    "working_end_velocity": ("tool/working_end_displacement", "m/s"),
}


class Record(BaseModel):
    """Samples `values` of `quantity` at `time` (s from the impact); `x` (m from the struck end)
    is the gauge's station for a stress."""

    model_config = INPUT

    quantity: Literal["contact_force", "medium_force", "stress", "struck_end_velocity",
                      "working_end_velocity"]
    x: float | None = Field(default=None, description="the gauge's station for a stress, m")
    time: list[float] = Field(min_length=MIN_SAMPLES, max_length=MAX_SAMPLES, description="s")
    values: list[float] = Field(min_length=MIN_SAMPLES, max_length=MAX_SAMPLES,
                                description="SI: N, Pa (tension positive) or m/s")

    @model_validator(mode="after")
    def _consistent(self) -> "Record":
        if len(self.values) != len(self.time):
            raise field_error("Record", ("values",), f"must have one value per time: "
                              f"{len(self.values)} values for {len(self.time)} times", None)
        if self.time[0] < 0.0:
            raise field_error("Record", ("time",),
                              f"must start at or after 0 (the impact), not at {self.time[0]:g} s", None)
        steps = np.diff(self.time)
        if (steps <= 0.0).any():
            i = int(np.argmax(steps <= 0.0)) + 1
            raise field_error("Record", ("time", i), f"must increase: time[{i}] = {self.time[i]:.9g} s "
                              f"is not after time[{i - 1}] = {self.time[i - 1]:.9g} s", None)
        if self.quantity == "stress" and self.x is None:
            raise field_error("Record", ("x",), "is required for a stress record: the gauge's "
                              "station, m from the struck end", None)
        if self.quantity != "stress" and self.x is not None:
            raise field_error("Record", ("x",), "belongs to a stress record only (quantity 'stress')",
                              self.x)
        if np.ptp(self.values) == 0.0:
            raise field_error("Record", ("values",),
                              "are all equal: a record with no pulse determines nothing", None)
        return self

    @property
    def unit(self) -> str:
        return QUANTITIES[self.quantity][1]

    @property
    def label(self) -> str:
        """The quantity as a CSV header names it."""
        return f"stress@{self.x:g}" if self.quantity == "stress" else self.quantity

    def check_against(self, case: Case, field: str = "record") -> None:
        """Refuse, naming the field, a record this case cannot produce."""
        errors = []
        if self.quantity == "stress" and not 0.0 <= self.x <= case.tool.length:
            errors.append(FieldError(field=f"{field}.x", message=(
                f"the gauge at x = {self.x:g} m is off the tool: it must lie within 0 ≤ x ≤ "
                f"tool.length = {case.tool.length:g} m")))
        if self.quantity == "medium_force" and case.medium is None:
            errors.append(FieldError(field=f"{field}.quantity",
                                     message="a medium force needs a medium: the case has none"))
        if self.time[-1] > case.numerics.duration:
            errors.append(FieldError(field=f"{field}.time", message=(
                f"ends at {self.time[-1]:.6g} s, after the case's numerics.duration of "
                f"{case.numerics.duration:.6g} s: times are in seconds from the impact (SI); "
                "lengthen numerics.duration if the record is that long")))
        if errors:
            raise CaseError(errors)

    def outputs(self) -> dict:
        """What a run must keep to give this quantity: every step, and the gauge as a probe."""
        return {"history_stride": 1, "probes": [self.x] if self.quantity == "stress" else []}


def parse_record(data: dict, field: str = "record") -> Record:
    """Validate a record given as JSON; `CaseError` names each bad field under `field`."""
    return validated(Record, data, field)


def read_record(source: str | os.PathLike) -> Record:
    """Read a record from a CSV file (see the module's docstring): `CaseError` names the line
    and column of anything that is not a sample."""
    text = Path(source).read_text()
    return record_from_csv(text)


def record_from_csv(text: str) -> Record:
    """A record from CSV text with a header `time,<quantity>`."""
    rows = [row for row in csv.reader(io.StringIO(text)) if row and any(cell.strip() for cell in row)]
    if not rows:
        raise CaseError([FieldError(field="record", message="is empty: give a header time,<quantity> and samples")])
    header = [cell.strip() for cell in rows[0]]
    known = ", ".join(q if q != "stress" else "stress@X" for q in QUANTITIES)
    if len(header) != 2 or header[0] != "time":
        raise CaseError([FieldError(field="record", message=(
            f"line 1 must be the header time,<quantity> with the quantity one of {known}; "
            f"found {','.join(header)!r}"))])
    quantity, x = header[1], None
    if quantity.startswith("stress@"):
        try:
            quantity, x = "stress", float(quantity.removeprefix("stress@"))
        except ValueError:
            raise CaseError([FieldError(field="record.x", message=(
                f"{header[1]!r}: the gauge's station must be a number of metres, as in stress@0.35"))]) from None
    elif quantity not in QUANTITIES or quantity == "stress":
        raise CaseError([FieldError(field="record.quantity", message=(
            f"{quantity!r} is not a recorded quantity: give one of {known}"))])
    time, values = [], []
    for line, row in enumerate(rows[1:], start=2):
        if len(row) != 2:
            raise CaseError([FieldError(field="record", message=(
                f"line {line} has {len(row)} columns, not 2 (time and {header[1]})"))])
        try:
            t, v = float(row[0]), float(row[1])
        except ValueError:
            raise CaseError([FieldError(field="record", message=(
                f"line {line}: {','.join(row)!r} is not two numbers"))]) from None
        time.append(t)
        values.append(v)
    data = {"quantity": quantity, "time": time, "values": values}
    if x is not None:
        data["x"] = x
    return parse_record(data)


def record_to_csv(record: Record) -> str:
    """The record as CSV text, as `record_from_csv` reads it."""
    lines = [f"time,{record.label}"]
    lines += [f"{t!r},{v!r}" for t, v in zip(record.time, record.values)]
    return "\n".join(lines) + "\n"


def series(quantity: str, history: dict[str, np.ndarray], probe_stress: np.ndarray,
           times: np.ndarray) -> np.ndarray:
    """A run's `quantity` at `times` (linear between its samples): its history, its first probe's
    stress, or an end's velocity from its displacement."""
    t = history["time"]
    if quantity == "stress":
        samples = probe_stress[:, 0]
    elif quantity.endswith("_velocity"):
        samples = np.gradient(history[QUANTITIES[quantity][0]], t)
    else:
        samples = history[QUANTITIES[quantity][0]]
    return np.interp(times, t, samples)
