"""The entry points of a run: `simulate` (the runs a case takes, `adaptive.solve`, whose summary then
prints what they say of its accuracy) and `run_sweep` (every variant of a sweep)."""

from __future__ import annotations

import contextlib
import functools
import os
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from typing import Any

from pydantic import ValidationError

from .adaptive import solve
from .case import Case, CaseError, as_case, describe_errors
from .errors import NumericalFailure
from .io import ResultWriter
from .limits import Limits
from .result import CancelCheck, ProgressCallback, Recorder, Result
from .summary import add_accuracy
from .sweep import Sweep, table_row, variants


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
    result, accuracy = solve(case, progress, cancelled, limits, recorder)
    add_accuracy(result.summary, accuracy)
    return result


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
    table_only = sweep.case.summary_only()
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
