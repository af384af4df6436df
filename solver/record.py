"""A measured record: a time series of one quantity a run also computes, in SI units.

`Record` refuses what no fit can use (times that do not increase, non-finite values, too few
samples) naming the field; `check_against` refuses what does not fit the case (a gauge off the
tool, a medium force with no medium, a record longer than the case); `series` reads the same
quantity from a run at the record's instants.

Its times are given as a column (`time`) or, for an evenly sampled record, as `time_start` and
`sample_rate`. A column whose repeated times come only from rounding an even sampling (a
recorder that prints three significant digits) is read as that even sampling, with a note that
says so (`notes`); any other column that does not increase is refused.

The record's clock and the model's: the model's time is from the impact (the first contact's
start); the record's instant t is the model's t + `time_offset`. A recorder triggered by the
pulse itself starts where the pulse reaches its gauge, about x/c after the impact (x the gauge's
station, c the tool's wave speed): its `time_offset` is that delay. Left out, it is 0 when the
record starts at rest (`starts_at_rest`: time 0 is the impact) and fitted otherwise.

CSV: a header `time,<quantity>`, with the quantity one of `contact_force`, `medium_force`,
`stress@X` (stress at x = X m in the tool, compression negative), `struck_end_velocity`,
`working_end_velocity`; then one sample a line. An evenly sampled record may leave the time
column out (a header `<quantity>` and one value a line) and say `# sample_rate = 12.5e6` (Hz)
and `# time_start = 0` (s) in comment lines before the header, where `# time_offset = …` (s)
may stand too; other comment lines are ignored.
"""

from __future__ import annotations

import csv
import io
import math
import os
from functools import cached_property
from pathlib import Path
from typing import Literal

import numpy as np
from pydantic import BaseModel, Field, model_validator

from .case import INPUT, Case, CaseError, FieldError, field_error, validated
from .grid import wave_speed

MIN_SAMPLES = 20  # fewer say too little about any parameter's effect on the pulse
MAX_SAMPLES = 200_000
REST_NOISE = 4.0  # a first sample within this many noise deviations of 0 is at rest...
REST_SHARE = 0.02  # ...or within this share of the record's peak
RISEN = 0.9  # of the peak: a pulse's front has risen (noise on a plateau moves the peak itself)
CLOCK_FIELDS = ("time_start", "sample_rate", "time_offset")  # a CSV's comment lines may give them

# quantity → (its history's path, its unit)
QUANTITIES = {
    "contact_force": ("contact/force", "N"),
    "medium_force": ("medium/force", "N"),
    "stress": ("probes/stress", "Pa"),
    "struck_end_velocity": ("tool/struck_end_displacement", "m/s"),  # differentiated
    "working_end_velocity": ("tool/working_end_displacement", "m/s"),
}


def printed_step(value: float) -> float:
    """The last printed digit's unit of `value`: the fewest significant digits that give it back
    (1.23e-05 → 1e-7), so that rounding moved it by at most half of this."""
    if value == 0.0:
        return 0.0
    for digits in range(1, 18):
        if float(f"{value:.{digits}g}") == value:
            break
    return 10.0 ** (math.floor(math.log10(abs(value))) - digits + 1)


def even_sampling(time: list[float]) -> np.ndarray | None:
    """The even sampling that `time` rounds, if every instant lies within its rounding (half its
    `printed_step`) of it; else None. The line is fitted through the middles of consecutive
    distinct instants, each at its half-sample: where rounding repeats a time, the middle is the
    rounding's threshold, which the even sampling crossed within that sample, so the fit is good
    to a fraction of a sample interval however coarse the rounding."""
    t = np.asarray(time, dtype=float)
    changes = np.flatnonzero(np.diff(t) > 0.0)
    if len(changes) < 2:
        return None
    step, start = np.polyfit(changes + 0.5, 0.5 * (t[changes] + t[changes + 1]), 1)
    even = start + step * np.arange(len(t))
    rounding = 0.5 * np.array([printed_step(v) for v in time])
    slack = 1.01 * rounding + 1e-3 * float(np.median(rounding)) + 1e-12 * float(np.abs(t).max())
    return even if step > 0.0 and bool(np.all(np.abs(t - even) <= slack)) else None


class Record(BaseModel):
    """Samples `values` of `quantity` at `time` (s on the record's clock), or evenly from
    `time_start` at `sample_rate`; `x` (m from the struck end) is the gauge's station for a
    stress; `time_offset` the model's time (from the impact) at the record's time 0."""

    model_config = INPUT

    quantity: Literal["contact_force", "medium_force", "stress", "struck_end_velocity", "working_end_velocity"]
    x: float | None = Field(default=None, description="the gauge's station for a stress, m")
    time: list[float] | None = Field(
        default=None, min_length=MIN_SAMPLES, max_length=MAX_SAMPLES, description="s, the record's clock"
    )
    time_start: float | None = Field(
        default=None, description="s: the first sample's time, with sample_rate instead of time (default 0)"
    )
    sample_rate: float | None = Field(
        default=None, gt=0.0, le=1e12, description="Hz: samples a second of an evenly sampled record, instead of time"
    )
    time_offset: float | None = Field(
        default=None,
        ge=-1e4,
        le=1e4,
        description=(
            "s: the model's time at the record's time 0 (a record triggered where the pulse reaches "
            "its gauge: about x/c); left out, 0 for a record that starts at rest, else fitted"
        ),
    )
    values: list[float] = Field(
        min_length=MIN_SAMPLES, max_length=MAX_SAMPLES, description="SI: N, Pa (tension positive) or m/s"
    )

    @model_validator(mode="after")
    def _consistent(self) -> Record:
        if self.time is None and self.sample_rate is None:
            if self.time_start is not None:
                raise field_error("Record", ("sample_rate",), "is required with time_start", None)
            raise field_error(
                "Record",
                ("time",),
                "is required: give the samples' times, or time_start and sample_rate for an evenly sampled record",
                None,
            )
        if self.time is not None and (self.sample_rate is not None or self.time_start is not None):
            name = "sample_rate" if self.sample_rate is not None else "time_start"
            raise field_error(
                "Record",
                (name,),
                "cannot be given with time: give the times, or time_start and sample_rate, not both",
                getattr(self, name),
            )
        if self.time is not None:
            if len(self.values) != len(self.time):
                raise field_error(
                    "Record",
                    ("values",),
                    f"must have one value per time: {len(self.values)} values for {len(self.time)} times",
                    None,
                )
            steps = np.diff(self.time)
            # a step back, or repeats that no even sampling explains (`sample_times` kept them)
            if (steps < 0.0).any() or (np.diff(self.sample_times) <= 0.0).any():
                i = int(np.argmax(steps <= 0.0)) + 1
                raise field_error(
                    "Record",
                    ("time", i),
                    f"must increase: time[{i}] = {self.time[i]:.9g} s "
                    f"is not after time[{i - 1}] = {self.time[i - 1]:.9g} s",
                    None,
                )
        if self.instants[-1] + (self.time_offset or 0.0) <= 0.0:
            raise field_error(
                "Record",
                ("time",),
                "must reach past the impact: the last sample is at "
                f"{self.instants[-1] + (self.time_offset or 0.0):.6g} s of the model's time "
                "(the record's time + time_offset)",
                None,
            )
        if self.quantity == "stress" and self.x is None:
            raise field_error(
                "Record", ("x",), "is required for a stress record: the gauge's station, m from the struck end", None
            )
        if self.quantity != "stress" and self.x is not None:
            raise field_error("Record", ("x",), "belongs to a stress record only (quantity 'stress')", self.x)
        if np.ptp(self.values) == 0.0:
            raise field_error("Record", ("values",), "are all equal: a record with no pulse determines nothing", None)
        return self

    @cached_property
    def sample_times(self) -> tuple[float, ...]:
        """The samples' times on the record's clock (s): `time`, the even sampling it rounds, or
        `time_start` + k/`sample_rate` (a tuple, which compares as a field's value would)."""
        if self.time is None:
            return tuple((self.time_start or 0.0) + np.arange(len(self.values)) / self.sample_rate)
        steps = np.diff(self.time)
        rebuilt = even_sampling(self.time) if (steps <= 0.0).any() else None
        return tuple(rebuilt) if rebuilt is not None else tuple(self.time)

    @property
    def instants(self) -> np.ndarray:
        """`sample_times` as an array."""
        return np.asarray(self.sample_times, dtype=float)

    @property
    def notes(self) -> list[str]:
        """What was read differently from how it was given, for the answer's warnings."""
        if self.time is None or not (np.diff(self.time) <= 0.0).any():
            return []
        repeats = int(np.sum(np.diff(self.time) <= 0.0))
        t = self.instants
        return [
            f"record.time repeats {repeats} of its {len(t)} instants, as rounding an even sampling "
            f"does: read as {len(t)} samples evenly from {t[0]:.9g} to {t[-1]:.9g} s "
            f"({(len(t) - 1) / (t[-1] - t[0]):.4g} Hz, fitted through its instants); give "
            "time_start and sample_rate to say so"
        ]

    @property
    def unit(self) -> str:
        return QUANTITIES[self.quantity][1]

    @property
    def label(self) -> str:
        """The quantity as a CSV header names it."""
        return f"stress@{self.x:g}" if self.quantity == "stress" else self.quantity

    def station(self, case: Case) -> float:
        """Where the quantity is measured along the tool (m): the gauge, or the end it is at."""
        if self.quantity == "stress":
            return self.x
        return case.tool.length if self.quantity in ("medium_force", "working_end_velocity") else 0.0

    def starts_at_rest(self) -> bool:
        """Whether the first sample is at rest: within `REST_NOISE` deviations of the record's
        noise of 0, or `REST_SHARE` of its peak. A record triggered by its pulse does not."""
        values = np.asarray(self.values)
        peak = float(np.max(np.abs(values)))
        noise = record_noise(self) * float(np.ptp(values))
        return abs(values[0]) <= max(REST_NOISE * noise, REST_SHARE * peak)

    def offset_bounds(self, case: Case) -> tuple[float, float]:
        """Where a fitted `time_offset` is sought by default: the pulse's arrival at the station,
        x/c (c the tool's wave speed), give or take the record's own rise (its first sample to
        the first that reaches `RISEN` of its peak), within which a trigger fires."""
        values = np.abs(np.asarray(self.values))
        t = self.instants
        rise = float(t[int(np.argmax(values >= RISEN * values.max()))] - t[0])
        arrival = self.station(case) / wave_speed(case.tool)
        rise = max(rise, 1e-3 * arrival, float(t[1] - t[0]))
        return max(0.0, arrival - rise) - t[0], arrival + rise - t[0]

    def check_against(self, case: Case, field: str = "record", end: float | None = None) -> None:
        """Refuse, naming the field, a record this case cannot produce; `end` is the model's time
        the runs must reach (by default the last sample's, at the record's time_offset)."""
        errors = []
        if self.quantity == "stress" and not 0.0 <= self.x <= case.tool.length:
            errors.append(
                FieldError(
                    field=f"{field}.x",
                    message=(
                        f"the gauge at x = {self.x:g} m is off the tool: it must lie within 0 ≤ x ≤ "
                        f"tool.length = {case.tool.length:g} m"
                    ),
                )
            )
        if self.quantity == "medium_force" and case.medium is None:
            errors.append(
                FieldError(field=f"{field}.quantity", message="a medium force needs a medium: the case has none")
            )
        last = float(self.instants[-1])
        end = last + (self.time_offset or 0.0) if end is None else end
        offset = end - last
        if end > case.numerics.duration:
            shifted = f" (its last sample + time_offset {offset:.6g} s)" if offset else ""
            errors.append(
                FieldError(
                    field=f"{field}.time",
                    message=(
                        f"ends at {end:.6g} s of the model's time{shifted}, after the case's "
                        f"numerics.duration of {case.numerics.duration:.6g} s: times are in seconds (SI); "
                        "lengthen numerics.duration if the record is that long"
                    ),
                )
            )
        if errors:
            raise CaseError(errors)

    def outputs(self) -> dict:
        """What a run must keep to give this quantity: every step, and the gauge as a probe."""
        return {"history_stride": 1, "probes": [self.x] if self.quantity == "stress" else []}


def scatter(values) -> float:
    """The noise of a finely sampled series, in its units: the scatter of its second differences
    (robust: a median), which a pulse sampled finely enough hardly has."""
    second = np.diff(np.asarray(values, float), 2)
    return 1.4826 * float(np.median(np.abs(second - np.median(second)))) / math.sqrt(6.0)


def record_noise(record: Record) -> float:
    """The record's noise over its range (`scatter`): the least misfit a fit can reach."""
    return scatter(record.values) / float(np.ptp(record.values))


def parse_record(data: dict, field: str = "record") -> Record:
    """Validate a record given as JSON; `CaseError` names each bad field under `field`."""
    return validated(Record, data, field)


def read_record(source: str | os.PathLike, **clock: float) -> Record:
    """Read a record from a CSV file (see the module's docstring): `CaseError` names the line
    and column of anything that is not a sample. `clock` (time_start, sample_rate, time_offset)
    adds to what the file's comment lines say (the command line's flags)."""
    text = Path(source).read_text()
    return record_from_csv(text, **clock)


def csv_error(message: str, field: str = "record") -> CaseError:
    return CaseError([FieldError(field=field, message=message)])


def csv_rows(text: str) -> tuple[list[tuple[int, str]], list[tuple[int, list[str]]]]:
    """CSV text as `(comments, rows)`, each with its line number (from 1): the comment lines
    (`#`) before the first row, and every row's cells stripped; blank lines and later comments
    left out."""
    comments: list[tuple[int, str]] = []
    rows: list[tuple[int, list[str]]] = []
    for line, row in enumerate(csv.reader(io.StringIO(text)), start=1):
        if not row or not any(cell.strip() for cell in row):
            continue
        if row[0].lstrip().startswith("#"):
            if not rows:
                comments.append((line, ",".join(row)))
            continue
        rows.append((line, [cell.strip() for cell in row]))
    return comments, rows


def csv_numbers(samples: list[tuple[int, list[str]]], width: int, columns: str, numbers: str) -> list[list[float]]:
    """Each sample row (`csv_rows`'s) as `width` numbers; `CaseError` names the line of one that
    has other than `width` cells (`columns` says which) or is not `numbers`."""
    found = []
    for line, row in samples:
        if len(row) != width:
            raise csv_error(f"line {line} has {len(row)} columns, not {width} ({columns})")
        try:
            found.append([float(cell) for cell in row])
        except ValueError:
            raise csv_error(f"line {line}: {','.join(row)!r} is not {numbers}") from None
    return found


def _clock_comment(line: int, text: str, clock: dict[str, float]) -> None:
    """A comment line's `name = value` for a field of `CLOCK_FIELDS` into `clock`."""
    name, equals, value = text.lstrip("#").partition("=")
    name = name.strip()
    if not equals or name not in CLOCK_FIELDS:
        return  # a free comment
    try:
        clock[name] = float(value)
    except ValueError:
        raise csv_error(f"line {line}: {name} = {value.strip()!r} is not a number", f"record.{name}") from None


def record_from_csv(text: str, **given: float) -> Record:
    """A record from CSV text: a header `time,<quantity>` and two columns, or a header
    `<quantity>`, one column and the sampling in comment lines or in `given`."""
    clock: dict[str, float] = {}
    comments, rows = csv_rows(text)
    for line, comment in comments:
        _clock_comment(line, comment, clock)
    for name, value in given.items():
        if name in clock and clock[name] != value:
            raise csv_error(f"is {value:g}, but the file says {name} = {clock[name]:g}: give one", f"record.{name}")
        clock[name] = value
    if not rows:
        raise csv_error("is empty: give a header time,<quantity> and samples")
    (header_line, header), samples = rows[0], rows[1:]
    known = ", ".join(q if q != "stress" else "stress@X" for q in QUANTITIES)
    timed = len(header) == 2 and header[0] == "time"
    if not (timed or len(header) == 1 and header[0] != "time"):
        raise csv_error(
            f"line {header_line} must be the header time,<quantity> (or <quantity> alone, "
            f"with sample_rate given) with the quantity one of {known}; found {','.join(header)!r}"
        )
    label = header[-1]
    quantity, x = label, None
    if quantity.startswith("stress@"):
        try:
            quantity, x = "stress", float(quantity.removeprefix("stress@"))
        except ValueError:
            raise csv_error(
                f"{label!r}: the gauge's station must be a number of metres, as in stress@0.35", "record.x"
            ) from None
    elif quantity not in QUANTITIES or quantity == "stress":
        raise csv_error(f"{quantity!r} is not a recorded quantity: give one of {known}", "record.quantity")
    columns = "time and " + label if timed else label
    numbers = csv_numbers(samples, len(header), columns, "two numbers" if timed else "a number")
    data: dict = {"quantity": quantity, "values": [row[-1] for row in numbers], **clock}
    if timed:
        data["time"] = [row[0] for row in numbers]
    if x is not None:
        data["x"] = x
    return parse_record(data)


def record_to_csv(record: Record) -> str:
    """The record as CSV text, as `record_from_csv` reads it."""
    lines = [f"# {name} = {getattr(record, name)!r}" for name in CLOCK_FIELDS if getattr(record, name) is not None]
    if record.time is None:
        lines += [record.label] + [f"{v!r}" for v in record.values]
    else:
        lines += [f"time,{record.label}"] + [f"{t!r},{v!r}" for t, v in zip(record.time, record.values)]
    return "\n".join(lines) + "\n"


def series(quantity: str, history: dict[str, np.ndarray], probe_stress: np.ndarray, times: np.ndarray) -> np.ndarray:
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
