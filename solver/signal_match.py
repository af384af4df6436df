"""Signal matching: a pile's soil from the force and velocity measured near its head.

The record (`PileRecord`: the gauges' station `x` below the head, and force and velocity at its
instants) drives the pile below the gauges through its measured velocity (`struck_end`), and the
soil's values are fitted so that the force the pile then needs at its head is the measured one, as
the signal-matching programs do. The fit is a calibration's (`calibrate`: a global stage, bounded
least squares, standard errors, correlation, and warnings naming the parameters the record cannot
tell apart); by default its unknowns are each shaft segment's ultimate resistance, one quake and
one damping factor for the whole shaft (`shaft.*.…`), and the toe's three (`default_parameters`).

The answer adds what a pile engineer reads off a match: the static `capacity` (the fitted
resistances' sum, its standard error from their covariance), the `resistance_distribution`, the
`match_quality` (`MATCH_QUALITY`), the Case method's capacity from the record alone
(`pile_record.case_method`), a `static_load_test` of the fitted soil (`rest.static_load_test`),
the waves down and up at the gauges (`waves`), and the fitted case.
"""

from __future__ import annotations

import math
import re
from typing import Annotated

import numpy as np
from pydantic import BaseModel, Field, field_validator, model_validator

from .calibrate import calibrate
from .case import INPUT, Case, CaseError, FieldError, field_error, increasing, validated
from .evaluate import Evaluator
from .grid import make_grid, wave_speed
from .limits import Limits
from .pile_record import case_method, proportionality, waves
from .record import csv_error, csv_numbers, csv_rows, scatter
from .rest import static_load_test
from .result import CancelCheck, ProgressCallback

MATCH_QUALITY = (
    "the root-mean-square difference between the computed and the measured force over the record, "
    "as a fraction of the measured force's peak (0: a perfect match); `window` is the same over the "
    "2L/c after the velocity's peak, where the soil's resistance first shows, `after` over the rest"
)
UNITS_OFF = 300.0  # F/(Z·v) at impact this far from 1, either way: a unit off by a prefix (1000)
PROPORTIONAL = 0.2  # F/(Z·v) at impact further than this from 1: warn of the gauge, area or wave speed
RESISTANCE_SPAN = 10.0  # a resistance's bounds: its starting guess over and times this
QUAKE_BOUNDS = [5e-4, 1e-2]  # m: Smith's quakes, from dense sand to soft clay
DAMPING_BOUNDS = [0.01, 2.0]  # s/m: Smith's damping factors
Sample = Annotated[float, Field(ge=-1e12, le=1e12)]


class PileRecord(BaseModel):
    """Force (N, compression positive) and velocity (m/s, toward the toe positive) at the gauges,
    `x` (m) below the pile's head, at `time` (s, increasing)."""

    model_config = INPUT

    x: float = Field(0.0, ge=0.0, description="the gauges' station below the pile's head, m")
    time: list[Annotated[float, Field(ge=-1e4, le=1e4)]] = Field(min_length=8, max_length=1_000_000)
    force: list[Sample] = Field(min_length=8, max_length=1_000_000)
    velocity: list[Sample] = Field(min_length=8, max_length=1_000_000)

    @field_validator("time")
    @classmethod
    def _increasing(cls, time: list[float]) -> list[float]:
        return increasing(time, "must increase: time[{i}] = {b} s is not after time[{j}] = {a} s")

    @model_validator(mode="after")
    def _one_sample_each(self) -> PileRecord:
        for name in ("force", "velocity"):
            if len(getattr(self, name)) != len(self.time):
                raise field_error(
                    "PileRecord",
                    (name,),
                    f"must have one value per time: {len(getattr(self, name))} values for {len(self.time)} times",
                    None,
                )
        if max(self.velocity) <= 0.0:
            raise field_error(
                "PileRecord", ("velocity",), "never moves toward the toe: a record of no blow determines nothing", None
            )
        return self

    def arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Time from the first sample, force and velocity, as arrays."""
        time = np.asarray(self.time, float)
        return time - time[0], np.asarray(self.force, float), np.asarray(self.velocity, float)


class SignalMatch(BaseModel):
    """A pile (`tool`, `shaft`, a Smith `medium`, `numerics`: its soil's values the starting
    guesses), its head's record, and the parameters to fit with their bounds (default:
    `default_parameters`)."""

    model_config = INPUT

    case: dict
    record: PileRecord
    parameters: dict[str, list[float]] | None = None


def parse_signal_match(data: dict) -> SignalMatch:
    """Validate a signal match given as JSON; `CaseError` names each bad field."""
    return validated(SignalMatch, data)


_HEADER = re.compile(r"^(force|velocity)@([-+0-9.eE]+)$")


def read_pile_record(text: str) -> PileRecord:
    """A record from CSV text: a header `time,force@X,velocity@X` (X the gauges' station, m), then
    a line a sample, SI units; `CaseError` names a bad header or the line of a bad value."""
    _, rows = csv_rows(text)
    header = rows[0][1] if rows else []
    found = [_HEADER.match(cell) for cell in header[1:]]
    if (
        len(header) != 3
        or header[0] != "time"
        or not all(found)
        or {m.group(1) for m in found} != {"force", "velocity"}
    ):
        raise csv_error(f"the header must be time,force@X,velocity@X; it is {','.join(header)}")
    stations = {float(m.group(2)) for m in found}
    if len(stations) != 1:
        raise csv_error(f"force and velocity must be at one station: {sorted(stations)}", "record.x")
    numbers = csv_numbers(rows[1:], 3, ",".join(header), "three numbers")
    columns = {"time": 0} | {m.group(1): k + 1 for k, m in enumerate(found)}
    values = {name: [row[k] for row in numbers] for name, k in columns.items()}
    return validated(PileRecord, {"x": stations.pop(), **values}, "record")


def below_gauges(case: dict, x: float) -> dict:
    """The pile below the gauges, `x` m down, as its own tool: its length, profile and shaft
    segments measured from the gauges (the pile above them carries no record)."""
    if x == 0.0:
        return case
    tool = dict(case["tool"])
    tool["length"] = tool["length"] - x
    if tool.get("profile"):
        stations, areas = tool["profile"]["x"], tool["profile"]["area"]
        kept = [(s - x, a) for s, a in zip(stations, areas) if s > x]
        tool["profile"] = {
            "x": [0.0] + [s for s, _ in kept],
            "area": [float(np.interp(x, stations, areas))] + [a for _, a in kept],
        }
    shaft = [
        segment | {"from": max(segment["from"] - x, 0.0), "to": segment["to"] - x}
        for segment in case.get("shaft") or []
        if segment["to"] > x
    ]
    return case | {"tool": tool} | ({"shaft": shaft} if shaft else {})


def driven_case(request: SignalMatch) -> Case:
    """The pile below the gauges, its head driven by the record's velocity; `CaseError` names what
    a match cannot use: a striker or a contact (the record drives the pile), a gauge off the pile,
    or a toe that is not Smith's."""
    given = request.case
    refused = [
        FieldError(field=f"case.{name}", message="the record drives the pile: leave it out")
        for name in ("striker", "contact", "struck_end")
        if name in given
    ]
    if refused:
        raise CaseError(refused)
    length = (given.get("tool") or {}).get("length")
    if isinstance(length, (int, float)) and request.record.x >= length:
        raise CaseError(
            [
                FieldError(
                    field="record.x",
                    message=f"the gauges at {request.record.x:g} m are off the pile, {length:g} m long",
                )
            ]
        )
    if (given.get("medium") or {}).get("kind") != "smith":
        raise CaseError(
            [FieldError(field="case.medium.kind", message="must be 'smith': a match fits Smith's soil at the toe")]
        )
    time, _, velocity = request.record.arrays()
    case = below_gauges(given, request.record.x) | {
        "struck_end": {"velocity": {"time": time.tolist(), "values": velocity.tolist()}}
    }
    return validated(Case, case, "case")


def round_trip(case: Case) -> float:
    """2L/c (s): a wave's way to the toe and back to the gauges."""
    return 2.0 * case.tool.length / wave_speed(case.tool)


def impedance(case: Case) -> float:
    """Z = E·A/c at the pile's head (the gauges)."""
    area = case.tool.area if case.tool.area is not None else case.tool.profile.area[0]
    return case.tool.youngs_modulus * area / wave_speed(case.tool)


def default_parameters(case: Case) -> dict[str, list[float]]:
    """Each shaft segment's ultimate resistance and the toe's, within `RESISTANCE_SPAN` of their
    starting guesses; one quake and one damping factor for the whole shaft (tied: `shaft.*.…`) and
    one each for the toe, over Smith's ranges."""
    parameters = {
        f"shaft.{k}.ultimate_resistance": [
            s.ultimate_resistance / RESISTANCE_SPAN,
            s.ultimate_resistance * RESISTANCE_SPAN,
        ]
        for k, s in enumerate(case.shaft or [])
    }
    if case.shaft:
        parameters |= {"shaft.*.quake": QUAKE_BOUNDS, "shaft.*.damping_factor": DAMPING_BOUNDS}
    toe = case.medium.ultimate_resistance
    return parameters | {
        "medium.ultimate_resistance": [toe / RESISTANCE_SPAN, toe * RESISTANCE_SPAN],
        "medium.quake": QUAKE_BOUNDS,
        "medium.damping_factor": DAMPING_BOUNDS,
    }


def check_record(request: SignalMatch, case: Case) -> list[str]:
    """Refuse a record no match can use (`CaseError` naming the field): too short to see the toe
    answer (2L/c after the velocity's peak), or with a unit off by a prefix. Returns the warning
    for a record whose force and velocity are not proportional at impact."""
    time, force, velocity = request.record.arrays()
    travel, z = round_trip(case), impedance(case)
    peak = time[int(np.argmax(velocity))]
    if time[-1] < peak + travel:
        raise CaseError(
            [
                FieldError(
                    field="record.time",
                    message=f"ends {time[-1] - peak:.4g} s after the velocity's peak: a match needs at least 2L/c = "
                    f"{travel:.4g} s more, for the toe's answer to reach the gauges",
                )
            ]
        )
    ratio = proportionality(time, force, velocity, z)
    if not 1.0 / UNITS_OFF < abs(ratio) < UNITS_OFF:
        raise CaseError(
            [
                FieldError(
                    field="record.force",
                    message=f"is {ratio:.3g} × Z·v at impact (Z = {z:.4g} N·s/m, the pile's E·A/c): "
                    "force or velocity is off by a unit's prefix (kN for N, mm/s for m/s); give both in SI",
                )
            ]
        )
    if abs(ratio - 1.0) > PROPORTIONAL:
        return [
            f"the force at impact is {ratio:.3g} × Z·v (Z = {z:.4g} N·s/m, before any reflection "
            "they agree): the pile's area or wave speed in the case may be wrong, or a gauge is bad"
        ]
    return []


def signal_match(
    request: SignalMatch | dict,
    evaluator: Evaluator | None = None,
    processes: int | None = None,
    progress: ProgressCallback | None = None,
    cancelled: CancelCheck | None = None,
    limits: Limits = Limits(),
) -> dict:
    """Match the record (see the module's docstring): the calibration's answer (parameters,
    correlation, nrmse, evaluations, warnings, the fitted case) with the pile's `capacity`,
    `resistance_distribution`, `match_quality`, `case_method`, `waves` and `static_load_test`."""
    if not isinstance(request, SignalMatch):
        request = parse_signal_match(request)
    case = driven_case(request)
    warnings = check_record(request, case)
    time, force, velocity = request.record.arrays()
    parameters = request.parameters or default_parameters(case)
    # the measured velocity drives the model: its noise, times Z, is in the computed force
    z, travel = impedance(case), round_trip(case)
    input_noise = z * scatter(velocity) / float(np.ptp(force))
    fit = calibrate(
        {
            "case": case.model_dump(mode="json", exclude_none=True),
            "record": {
                "quantity": "contact_force",
                "time": time.tolist(),
                "values": force.tolist(),
                "time_offset": 0.0,
            },
            "parameters": parameters,
        },
        evaluator=evaluator,
        processes=processes,
        progress=progress,
        cancelled=cancelled,
        limits=limits,
        input_noise=input_noise,
    )
    fitted = validated(Case, fit["case"])
    return fit | {
        "warnings": warnings + fit["warnings"],
        "capacity": capacity(fit),
        "resistance_distribution": distribution(fit, fitted),
        "match_quality": match_quality(fit, float(time[np.argmax(velocity)]), travel),
        "match_quality_definition": MATCH_QUALITY,
        "case_method": case_method(time, force, velocity, z, travel),
        "waves": wave_curves(fit, time, velocity, z),
        "static_load_test": static_load_test(fitted, make_grid(fitted.tool, fit["grid"]["cells"], end_masses=True)),
    }


def _resistances(fit: dict) -> list[str]:
    return [path for path in fit["parameters"] if path.endswith("ultimate_resistance")]


def capacity(fit: dict) -> dict:
    """The fitted resistances' sum (N) and its standard error from their covariance (None when a
    resistance is not determined)."""
    paths = _resistances(fit)
    names = list(fit["parameters"])
    value = sum(fit["parameters"][p]["value"] for p in paths)
    errors = [fit["parameters"][p]["standard_error"] for p in paths]
    if any(e is None for e in errors):
        return {"value": value, "standard_error": None}
    index = [names.index(p) for p in paths]
    correlation = np.asarray(fit["correlation"])[np.ix_(index, index)]
    sigma = np.asarray(errors)
    return {"value": value, "standard_error": float(math.sqrt(max(sigma @ correlation @ sigma, 0.0)))}


def distribution(fit: dict, fitted: Case) -> list[dict]:
    """Each shaft segment's fitted resistance (N) with its span below the gauges and standard
    error, then the toe's."""
    found = fit["parameters"]
    rows = []
    for k, segment in enumerate(fitted.shaft or []):
        entry = found.get(f"shaft.{k}.ultimate_resistance", {})
        rows.append(
            {
                "part": f"shaft.{k}",
                "from": segment.start,
                "to": segment.end,
                "resistance": segment.ultimate_resistance,
                "standard_error": entry.get("standard_error"),
            }
        )
    toe = found.get("medium.ultimate_resistance", {})
    rows.append(
        {
            "part": "toe",
            "from": fitted.tool.length,
            "to": fitted.tool.length,
            "resistance": fitted.medium.ultimate_resistance,
            "standard_error": toe.get("standard_error"),
        }
    )
    return rows


def match_quality(fit: dict, peak: float, travel: float) -> dict:
    """`MATCH_QUALITY`: over the record, over the 2L/c after the velocity's peak (`window_time`, s),
    and after it."""
    time = np.asarray(fit["series"]["time"])
    measured, computed = np.asarray(fit["series"]["record"]), np.asarray(fit["series"]["model"])
    scale = max(float(np.max(np.abs(measured))), 1e-300)

    def rms(mask: np.ndarray) -> float | None:
        return float(np.sqrt(np.mean((computed[mask] - measured[mask]) ** 2)) / scale) if mask.any() else None

    window = (time >= peak) & (time <= peak + travel)
    return {
        "value": rms(np.ones_like(window)),
        "window": rms(window),
        "after": rms(time > peak + travel),
        "window_time": [peak, peak + travel],
    }


def wave_curves(fit: dict, time: np.ndarray, velocity: np.ndarray, impedance: float) -> dict:
    """The waves going down and coming up at the gauges, (F ± Z·v)/2 (N), measured and computed, at
    the fit's instants: the computed ones from the matched pile's force and the measured velocity
    that drives it."""
    at = np.asarray(fit["series"]["time"])
    v = np.interp(at, time, velocity)
    curves = {}
    for name, force in (("measured", fit["series"]["record"]), ("computed", fit["series"]["model"])):
        down, up = waves(np.asarray(force), v, impedance)
        curves[name] = {"down": down.tolist(), "up": up.tolist()}
    return {"time": at.tolist(), "impedance": impedance, **curves}
