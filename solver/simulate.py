"""One entry point for a run: limits first, then the rod or the lumped model, or a tolerance."""

from __future__ import annotations

from pathlib import Path

from .adaptive import solve_to_tolerance
from .case import Case
from .controller import CancelCheck, ProgressCallback, Recorder, Result, simulate_rod
from .grid import ResolvedNumerics, resolve_numerics
from .io import ResultWriter
from .limits import Limits, check_limits
from .lumped import simulate_lumped


def simulate(case: Case, model: str | None = None, progress: ProgressCallback | None = None,
             cancelled: CancelCheck | None = None, limits: Limits = Limits(),
             result_path: str | Path | None = None) -> Result:
    """Solve `case` with `model` ('rod' or 'lumped'; default `case.numerics.model`), or, when the
    case gives `numerics.tolerance`, with the model, scheme and grid chosen to meet it.

    With `result_path` the result is written there (HDF5, atomically; nothing is left there if
    the run fails or is cancelled), the rod's outputs streamed to it as the run goes so that
    memory stays O(cells) whatever they are: the result returned is then `streamed`, without its
    arrays.
    """
    if model is not None:
        case = case.model_copy(update={"numerics": case.numerics.model_copy(update={"model": model})})
    if result_path is None:
        return _solve(case, progress, cancelled, limits, recorder=None)
    with ResultWriter(result_path) as writer:
        result = _solve(case, progress, cancelled, limits, recorder=writer)
        writer.commit(result)
    return result


def _solve(case: Case, progress: ProgressCallback | None, cancelled: CancelCheck | None,
           limits: Limits, recorder: Recorder | None) -> Result:
    if case.numerics.tolerance is not None:
        return solve_to_tolerance(case, progress=progress, cancelled=cancelled, limits=limits,
                                  recorder=recorder)
    numerics = resolve_numerics(case)
    check_limits(case, numerics, limits)
    if numerics.model == "lumped":
        result = simulate_lumped(case, progress=progress, cancelled=cancelled)
    else:
        result = simulate_rod(case, numerics=numerics, progress=progress, cancelled=cancelled,
                              recorder=recorder)
    result.summary["why"] = fixed_choice(case, numerics)
    return result


def fixed_choice(case: Case, numerics: ResolvedNumerics) -> str:
    """Why a run without a tolerance used its model and scheme: the case said so, or the default."""
    num = case.numerics
    if numerics.model == "lumped":
        return "numerics.model = 'lumped' as asked: the two-mass model problem (21)–(25), DOP853"
    if num.scheme is not None:
        return f"numerics.scheme = '{num.scheme}' as asked, on the grid given or its defaults"
    return ("the default: the paper's weighted scheme (8) with γ = "
            f"{num.gamma:g} on the grid given or its defaults; give numerics.tolerance to let the "
            "solver choose model, scheme and grid")
