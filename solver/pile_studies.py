"""The pile engineer's daily analyses, each a list of variant cases read back as rows: the bearing
graph (blow count against the pile's capacity), the inspector's chart (against the ram's stroke) and
the drivability (against the toe's depth, with the total blows and the driving time).

Every variant is one case driven until its set settles, solved to its own accuracy (so each row
carries its own `error_estimate`), in one batch an evaluator spreads over the processes or the
workers a variant at a time, saying as each is answered (`evaluate.settled_batch`, `parts_of`).
A row's stresses are the largest of the blows run, its set and blow count the last blow's, its
transferred energy the largest work through the pile's head over a blow (EMX).

The drivability's total blows integrate the blow count over the depths driven, by the trapezoidal
rule, from the first depth to the last before refusal (the first depth whose blow count exceeds
`refusal`, or whose blow sets the pile no deeper); the driving time is the total blows over the
blow rate.
"""

from __future__ import annotations

import time

from .case import Case
from .errors import Cancelled
from .evaluate import Evaluator, evaluator_for, settled_batch
from .limits import Limits
from .pile_requests import (
    BearingGraph,
    Drivability,
    bearing_variants,
    drivability_variants,
    parse_bearing_graph,
    parse_drivability,
    set_aside,
    toe_share_of,
)
from .result import CancelCheck, ProgressCallback

# A row's columns: (name, the summary quantity it is).
COLUMNS = (
    ("set", "set"),
    ("blow_count", "blow_count"),
    ("max_compressive_stress", "max_compressive_stress"),
    ("max_tensile_stress", "max_tensile_stress"),
    ("transferred_energy", "energy.transferred"),
    ("error_estimate", "error_estimate.worst"),
)


def run_variants(
    cases: list[Case],
    evaluator: Evaluator,
    limits: Limits,
    progress: ProgressCallback | None = None,
    cancelled: CancelCheck | None = None,
) -> list[dict]:
    """A row per case, in order: the `COLUMNS`, the `blows` it took and its `warnings`, or the
    `error` it failed with."""
    trees = [case.model_dump(mode="json", exclude_none=True) for case in cases]

    def answered(done: int) -> None:
        if progress is not None:
            progress(done / len(trees))
        if cancelled is not None and cancelled():
            raise Cancelled(f"cancelled after {done} of {len(trees)} variants")

    answered(0)
    rows: list[dict] = []
    for answer in evaluator(settled_batch(trees, [path for _, path in COLUMNS], limits), answered=answered):
        if "error" in answer:
            rows.append({"error": answer["error"]})
            continue
        found = answer["quantities"]
        rows.append(
            {name: found[path] for name, path in COLUMNS} | {"blows": answer["blows"], "warnings": answer["warnings"]}
        )
    return rows


def bearing_graph(
    request: BearingGraph | dict,
    evaluator: Evaluator | None = None,
    processes: int | None = None,
    progress: ProgressCallback | None = None,
    cancelled: CancelCheck | None = None,
    limits: Limits = Limits(),
) -> dict:
    """The bearing graph (`capacity` given) or the inspector's chart (`stroke`) of `request` (a
    `BearingGraph` or its JSON): a row per capacity or stroke, in order. `evaluator` runs the
    variants (default: a pool over `processes`, one a core)."""
    if not isinstance(request, BearingGraph):
        request = parse_bearing_graph(request)
    started = time.monotonic()
    cases = bearing_variants(request, limits)
    with evaluator_for(evaluator, processes) as run:
        rows = run_variants(cases, run, limits, progress, cancelled)
    variable = "ultimate_resistance" if request.variable == "capacity" else "stroke"
    return {
        "variable": variable,
        "toe_share": request.toe_share or toe_share_of(request.case),
        "rows": [{variable: value} | row for value, row in zip(request.values, rows)],
        "warnings": failures(rows, [f"{request.variable}[{k}]" for k in range(len(rows))]),
        "seconds": time.monotonic() - started,
    }


def drivability(
    request: Drivability | dict,
    evaluator: Evaluator | None = None,
    processes: int | None = None,
    progress: ProgressCallback | None = None,
    cancelled: CancelCheck | None = None,
    limits: Limits = Limits(),
) -> dict:
    """The drivability of `request` (a `Drivability` or its JSON): a row per depth, the total
    blows, the driving time and the refusal depth (see the module's docstring); with a layer's
    setup factor, each row's `restrike` too, and the depth from which driving, once paused, would
    not start again (`restrike_refusal_depth`). `evaluator` runs the variants (default: a pool
    over `processes`, one a core)."""
    if not isinstance(request, Drivability):
        request = parse_drivability(request)
    started = time.monotonic()
    soil = request.soil
    variants = drivability_variants(request, limits)
    with evaluator_for(evaluator, processes) as run:
        found = run_variants([case for _, _, case in variants], run, limits, progress, cancelled)
    driving = [row for (_, restrike, _), row in zip(variants, found) if not restrike]
    restrikes = [row for (_, restrike, _), row in zip(variants, found) if restrike]
    rows = [
        {"depth": depth} | row | {"restrike": restrikes[k] if restrikes else None}
        for k, (depth, row) in enumerate(zip(soil.depths, driving))
    ]
    fields = [f"soil.depths[{k}]" for k in range(len(rows))]
    driven = drive(soil.depths, driving, soil.refusal)
    return {
        "rows": rows,
        "total_blows": driven["total_blows"],
        "driving_time": None if driven["total_blows"] is None else driven["total_blows"] / soil.blow_rate,
        "refusal_depth": driven["refusal_depth"],
        "driven_to": driven["driven_to"],
        "restrike_refusal_depth": drive(soil.depths, restrikes, soil.refusal)["refusal_depth"] if restrikes else None,
        "blow_rate": soil.blow_rate,
        "refusal": soil.refusal,
        "warnings": set_aside(request.case)
        + failures(driving, fields)
        + failures(restrikes, [f"{field} (restrike)" for field in fields]),
        "seconds": time.monotonic() - started,
    }


def refused(blow_count: float | None, refusal: float) -> bool:
    """Whether a blow count is refusal: above `refusal`, or none (the blow set the pile no deeper)."""
    return blow_count is None or blow_count > refusal


def drive(depths: list[float], rows: list[dict], refusal: float) -> dict:
    """The pile driven from the first depth on (`rows`, a row per depth): the first depth whose
    blow count is refusal (`refusal_depth`, None if none is), the last depth before it
    (`driven_to`, None if refusal is at the first), and the blows to get there (`total_blows`: the
    trapezoidal rule over the depths driven; None if a variant among them failed)."""
    stop = next((k for k, row in enumerate(rows) if "error" not in row and refused(row["blow_count"], refusal)), None)
    driven = len(depths) if stop is None else stop
    total = None
    if not any("error" in row for row in rows[:driven]):
        counts = [row["blow_count"] for row in rows[:driven]]
        total = sum(0.5 * (counts[k] + counts[k + 1]) * (depths[k + 1] - depths[k]) for k in range(driven - 1))
    return {
        "refusal_depth": None if stop is None else depths[stop],
        "driven_to": depths[driven - 1] if driven else None,
        "total_blows": total,
    }


def failures(rows: list[dict], fields: list[str]) -> list[str]:
    """A warning naming each variant that failed, and why."""
    return [f"{field} failed: {row['error']}" for field, row in zip(fields, rows) if "error" in row]
