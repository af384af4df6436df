"""The entry points of a run: `simulate` (limits first, then a tolerance, the lumped model or a fixed
grid, each with its error estimate, `adaptive`) and `run_sweep` (every variant of a sweep)."""

from __future__ import annotations

import contextlib
import functools
import math
import os
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from typing import Any

from pydantic import ValidationError

from .adaptive import fixed_estimate, lumped_estimate, solve_to_tolerance
from .case import Case, CaseError, FieldError, as_case, describe_errors
from .controller import simulate_rod
from .errors import NumericalFailure
from .grid import ResolvedNumerics, resolve_numerics, tolerance_of
from .io import ResultWriter
from .limits import Limits, check_limits
from .lumped import simulate_lumped
from .result import CancelCheck, ProgressCallback, Recorder, Result
from .sweep import TABLE_OUTPUTS, Sweep, table_row, variants

FIXED_SHARE = 0.75  # of a fixed grid's progress: the run asked for; its companions the rest


def simulate(
    case: Case | dict | str | os.PathLike,
    model: str | None = None,
    progress: ProgressCallback | None = None,
    cancelled: CancelCheck | None = None,
    limits: Limits = Limits(),
    result_path: str | os.PathLike | None = None,
) -> Result:
    """Solve `case` (a `Case`, case JSON as a dict, or a case file's path; `CaseError` names each
    bad field) with `model` ('rod' or 'lumped'; default `case.numerics.model`) to the accuracy
    it asks: `numerics.tolerance`; the default accuracy (a tolerance of 0.01) when it gives neither
    a grid nor a scheme; or the fixed grid it gives, whose error is estimated from two coarser
    companion runs. Every summary carries `error_estimate` (or says in `warnings` why not).

    With `result_path` the result is written there (HDF5, atomically; nothing is left there if
    the run fails or is cancelled), the rod's outputs streamed to it as the run goes so that
    memory stays O(cells) whatever they are: the result returned is then `streamed`, without its
    arrays.
    """
    case = as_case(case)
    if model is not None:
        case = case.model_copy(update={"numerics": case.numerics.model_copy(update={"model": model})})
    if result_path is None:
        return _solve(case, progress, cancelled, limits, recorder=None)
    with ResultWriter(result_path) as writer:
        result = _solve(case, progress, cancelled, limits, recorder=writer)
        writer.commit(result)
    return result


def _solve(
    case: Case,
    progress: ProgressCallback | None,
    cancelled: CancelCheck | None,
    limits: Limits,
    recorder: Recorder | None,
) -> Result:
    tol = tolerance_of(case.numerics)
    if case.numerics.model == "lumped":
        numerics = resolve_numerics(case)
        check_limits(case, numerics, limits)
        result = simulate_lumped(case, progress=progress, cancelled=cancelled)
        return lumped_estimate(case, result)
    if tol is not None:
        return solve_to_tolerance(case, tol, progress=progress, cancelled=cancelled, limits=limits, recorder=recorder)
    numerics = resolve_numerics(case)
    check_limits(case, numerics, limits)
    share = None if progress is None else (lambda fraction: progress(FIXED_SHARE * fraction))
    result = simulate_rod(case, numerics=numerics, progress=share, cancelled=cancelled, recorder=recorder)
    refuse_chatter(result.summary, numerics)

    def companion(coarse_case: Case, coarse: ResolvedNumerics) -> Result:
        result = simulate_rod(coarse_case, numerics=coarse, cancelled=cancelled)
        refuse_chatter(result.summary, coarse)
        return result

    result = fixed_estimate(case, numerics, result, companion, why=fixed_choice(case, numerics))
    if progress is not None:
        progress(1.0)
    return result


CHATTER_STEPS = 5.0  # a contact resolved by fewer steps than this says nothing of the case


def refuse_chatter(summary: dict, numerics: ResolvedNumerics) -> None:
    """Refuse the run of a fixed grid whose ends carry a mass, or none, when of several contacts one
    lasted less than `CHATTER_STEPS` steps: the contact chattered against an end that rings, and
    the answer is the grid's, not the case's (the ends that integrate their own equations resolve
    any contact with their own substeps)."""
    if numerics.ends == "impedance" or summary["contacts_total"] < 2:
        return  # one contact, however short, is no chatter: the estimate says how far off it is
    finished = [c for c in summary["contacts"] if c["end"] is not None]
    shortest = min(((c["end"] - c["start"]) / numerics.time_step for c in finished), default=math.inf)
    if shortest < CHATTER_STEPS:
        raise CaseError(
            [
                FieldError(
                    field="contact",
                    message=f"the contact chattered on this grid ({summary['contacts_total']} contacts, the "
                    f"shortest over {shortest:.2g} time steps of {numerics.time_step:.3g} s): its "
                    f"stiffness or its damper is more than the scheme '{numerics.scheme}' with these "
                    "ends can take on this grid. Leave numerics.cells, time_step and scheme out (the "
                    "default accuracy takes any contact), or give numerics.scheme = 'explicit' with "
                    "numerics.cells only",
                )
            ]
        )


def fixed_choice(case: Case, numerics: ResolvedNumerics) -> str:
    """Why a run on a fixed grid used its scheme: the case said so."""
    num = case.numerics
    if num.scheme is not None:
        return (
            f"numerics.scheme = '{num.scheme}' as asked, on the grid given or its defaults; its "
            "error estimated from two companion runs on grids 2× and 4× coarser"
        )
    return (
        f"a grid was given, so the paper's weighted scheme (8) with γ = {num.gamma:g} on it; "
        "its error estimated from two companion runs on grids 2× and 4× coarser"
    )


def _sweep_row(case: Case, limits: Limits) -> dict[str, Any]:
    try:
        return table_row(simulate(case, limits=limits).summary)
    except (NumericalFailure, CaseError) as error:  # this variant fails, the sweep goes on
        return {"error": str(error)}


def run_sweep(
    sweep: Sweep | dict,
    processes: int | None = None,
    progress: Callable[[int, int], None] | None = None,
    limits: Limits = Limits(),
) -> list[dict[str, Any]]:
    """Solve every variant, `processes` at once (default: one a core); one row each, in the order
    of `variants`: the parameter values, then the summary's columns (or `error`). `sweep` is a
    `Sweep` or its JSON as a dict (`{"case": …, "parameters": {"striker.velocity": [3, 5]}}`)."""
    if not isinstance(sweep, Sweep):
        try:
            sweep = Sweep.model_validate(sweep)
        except ValidationError as error:
            raise CaseError(describe_errors(error)) from None
    table_only = sweep.case.model_copy(update={"outputs": TABLE_OUTPUTS})
    found = variants(sweep.model_copy(update={"case": table_only}), limits=limits)
    processes = processes or os.cpu_count() or 1
    cases = [case for _, case in found]
    solve = functools.partial(_sweep_row, limits=limits)
    rows = []
    with ProcessPoolExecutor(processes) if processes > 1 else contextlib.nullcontext() as pool:
        # Batches large enough to hide the pipe, small enough to keep every process busy.
        solved = pool.map(solve, cases, chunksize=max(1, len(cases) // (64 * processes))) if pool else map(solve, cases)
        for (values, _), row in zip(found, solved):
            rows.append(values | row)
            if progress is not None:
                progress(len(rows), len(found))
    return rows
