"""One entry point for a run: limits first, then the rod or the lumped model."""

from __future__ import annotations

from .case import Case
from .controller import CancelCheck, ProgressCallback, Result, simulate_rod
from .grid import resolve_numerics
from .limits import Limits, check_limits
from .lumped import simulate_lumped


def simulate(case: Case, model: str | None = None, progress: ProgressCallback | None = None,
             cancelled: CancelCheck | None = None, limits: Limits = Limits()) -> Result:
    """Solve `case` with `model` ('rod' or 'lumped'; default `case.numerics.model`)."""
    numerics = resolve_numerics(case, model=model)
    check_limits(case, numerics, limits)
    if numerics.model == "lumped":
        return simulate_lumped(case, progress=progress, cancelled=cancelled)
    return simulate_rod(case, numerics=numerics, progress=progress, cancelled=cancelled)
