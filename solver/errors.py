"""How a run can end without a result: cancelled, or a value that became non-finite."""

from __future__ import annotations

from .grid import ResolvedNumerics


class Cancelled(Exception):
    """The run was cancelled between two chunks."""


class NumericalFailure(RuntimeError):
    """A non-finite value appeared; carries the time and what to change."""

    def __init__(self, time: float, numerics: ResolvedNumerics):
        self.time = time
        super().__init__(
            f"the solution became non-finite at t = {time:.6g} s (scheme '{numerics.scheme}', time "
            f"step {numerics.time_step:.3g} s, {numerics.cells} cells); likely cause: a contact or "
            "medium far stiffer than the time step resolves. Reduce numerics.time_step."
        )
