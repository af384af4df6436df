"""Blows until the set settles: a pile driven blow after blow until a blow sets it as deep as the one
before it, within the case's tolerance (`settled_after`), as a wave-equation analysis reads its blow
count off the blow the pile has settled into.

How many blows that takes is counted on one run of every blow `blows.count` allows (`DEFAULT_BLOWS`
when the case gives none) on a coarse grid (`counting_numerics`); the case is then solved with that
many blows to its own accuracy (`simulate`). Every grid of its ladder so runs the same blows, and its
error estimate compares like with like (a ladder whose grids each stopped at their own blow would
compare different blows, and different numbers of contacts).
"""

from __future__ import annotations

from .case import SUMMARY_ONLY, Case
from .grid import DEFAULT_TOLERANCE, ResolvedNumerics, explicit_numerics, first_cells, tolerance_of
from .limits import Limits, check_limits

DEFAULT_BLOWS = 10  # blows at most, for a case that gives no blows.count
COUNTING_CELLS = 64  # the counting run's grid, unless the case's first grid is finer


def settle_tolerance(case: Case) -> float:
    """How close two successive sets must be: the case's tolerance (the default accuracy's for a
    fixed grid)."""
    return tolerance_of(case.numerics) or DEFAULT_TOLERANCE


def settled_after(sets: list[float], tolerance: float) -> int | None:
    """The first blow (counted from 1) whose set is within `tolerance` of the set before it
    (relative to its own), or which, as the one before it, sets the pile no deeper (refusal); None
    if no blow has."""
    for k in range(1, len(sets)):
        now, before = sets[k], sets[k - 1]
        if (now <= 0.0 and before <= 0.0) or abs(now - before) <= tolerance * abs(now):
            return k + 1
    return None


def with_blows(case: Case, count: int) -> Case:
    """The case with `count` blows and a summary's outputs only."""
    return Case.model_validate(
        case.model_dump(mode="json", exclude_none=True)
        | {"blows": {"count": count}, "outputs": SUMMARY_ONLY.model_dump(mode="json")}
    )


def most_blows(case: Case) -> int:
    return case.blows.count if case.blows else DEFAULT_BLOWS


def counting_numerics(case: Case) -> ResolvedNumerics:
    """The grid the blows are counted on: the explicit scheme on `COUNTING_CELLS` cells, or the
    case's first grid under its tolerance if that is finer."""
    return explicit_numerics(case, max(COUNTING_CELLS, first_cells(case, settle_tolerance(case))))


def check_counting(case: Case, limits: Limits) -> None:
    """Refuse (`CaseError`, naming the field) a case whose counting run is over the limits."""
    counting = with_blows(case, most_blows(case))
    check_limits(counting, counting_numerics(counting), limits)


def settled_run(case: Case, limits: Limits = Limits()) -> dict:
    """The summary of `case` driven until its set settles (see the module's docstring), solved to
    its own accuracy; its `warnings` say when the set had not settled."""
    from .controller import simulate_rod  # the kernel, loaded when a run needs it
    from .simulate import simulate

    most, tolerance = most_blows(case), settle_tolerance(case)
    blows = most
    if most > 1:
        counting = with_blows(case, most)
        numerics = counting_numerics(counting)
        check_limits(counting, numerics, limits)
        sets = [blow["set"] for blow in simulate_rod(counting, numerics=numerics).summary["blows"]]
        blows = settled_after(sets, tolerance) or most
    summary = simulate(with_blows(case, blows), limits=limits).summary
    summary["warnings"] += unsettled(summary, tolerance, most)
    return summary


def unsettled(summary: dict, tolerance: float, most: int) -> list[str]:
    """The warning of a run whose last two blows' sets are not within `tolerance`."""
    sets = [blow["set"] for blow in summary["blows"] or []]
    if len(sets) < 2 or settled_after(sets[-2:], tolerance):
        return []
    change = abs(sets[-1] - sets[-2]) / abs(sets[-1]) if sets[-1] else float("inf")
    cause = (
        f"in the {most} blows blows.count allows"
        if len(sets) == most
        else f"on the case's grid, though it had on the grid the blows were counted on ({len(sets)} blows)"
    )
    return [
        f"the set had not settled {cause}: the last blow's set differs by {100 * change:.3g}% from the one "
        f"before it, more than the tolerance of {100 * tolerance:g}%; the blow count is the last blow's"
    ]
