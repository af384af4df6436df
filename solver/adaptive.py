"""Tolerance-driven runs: the solver chooses model, scheme and grid, and estimates its own error.

Given `numerics.tolerance` (relative, on the co-impact time, the peak contact force and the
maximum stress), a run goes:

1. **Lumped model when the tool is stiff against the impact.** The two-mass model (21)–(25) is the
   rod's rigid limit; what it misses grows as ε², ε the ratio of the two-mass system's highest
   frequency to the tool's lowest elastic one, `πa/(2L)`. Over 66 cases with ε ≤ 0.5 (tools
   5–40 cm, tapered or not, strikers 1–100 kg, c1 1e9–1e11, two media; `bench/lumped_error.py`)
   the relative error stayed below 0.58·ε² (median 0.22·ε²); the estimate here is
   `LUMPED_ERROR·ε²` with LUMPED_ERROR = 1, and the lumped model is taken when that is below the
   tolerance.
2. **Otherwise the rod with the explicit scheme at Courant number 1** (second order and
   energy-conserving; at Courant 1 a wave crosses a uniform tool without dispersion, so the stress
   maxima converge at second order too, where the σ-scheme's dispersion overshoot converges at
   about 1.4), on a ladder of grids refined in h and τ together. The first pair of grids is placed
   from an a-priori error model, `error_constant·n^−p` (`Ladder`) with n the time steps per estimated
   contact, so that the finer one would just meet the tolerance: half as fine, then that grid.
   Each later grid is as fine as the last estimate says is needed, at least 1.15× and at most 3×
   finer than the last. A grid's error is estimated against each of its partners, the earlier
   grids at least 1.5× and at most 3× coarser, and the largest estimate counts (Richardson: the
   finer grid's error is `|Q_f − Q_c|/(r^p − 1)`, which holds only when both grids are near the
   asymptotic range, so it is taken 1.5× larger; closer grids would amplify what is not yet
   asymptotic, and where repeated impacts make the convergence irregular a second partner
   catches what one pair's agreement hides). So a step can be small where the estimate says the
   tolerance is nearly met; only once, and only between grids that agree on the contacts: a
   small step that did not end the ladder says the estimate was not to be trusted that closely.
   The grid it stepped from is no Richardson partner (too close), but the change the step made
   counts as an estimate too: the finer grid's error is at least that where `r^p − 1 < 1`.
   A grid whose partners see a different number of contacts ends the ladder only if the
   estimate before was within the tolerance too (a coarse one may have the sequence of impacts
   wrong, so the difference alone says little of the error; grazing re-contacts that come and go
   from grid to grid need the second estimate).
   It stops when every quantity's estimate is within the tolerance; the finer run is the result.
   Only the first run keeps nothing but what its summary needs: any later one may be the result.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .case import Case, CaseError, FieldError, Outputs
from .controller import CancelCheck, ProgressCallback, Recorder, Result, simulate_rod
from .grid import ResolvedNumerics, contact_time_estimate, resolve_numerics, tool_mass, wave_speed
from .limits import Limits, check_limits
from .lumped import simulate_lumped
from .schemes import make_scheme

QUANTITIES = ("co_impact_time", "peak_contact_force", "max_stress")
LUMPED_ERROR = 1.0  # the lumped model's relative error is at most this × ε² (measured ≤ 0.58)
MIN_START_POINTS = 6  # the coarsest first grid, in time steps per estimated contact
MIN_REFINEMENT = 1.5  # between a grid and the partner its error is estimated against
MAX_REFINEMENT = 3.0  # largest: a coarser partner is too far from the asymptotic range to judge by
MIN_STEP = 1.15  # smallest refinement from one grid of the ladder to the next
MAX_RUNS = 8
MIN_CELLS = 2  # the coarsest grid's cells on a tool short against the contact
DEFAULT_SCHEME = "explicit"
COURANT = 1.0 - 1e-9  # the explicit scheme's limit, kept with a margin for rounding


@dataclass(frozen=True)
class Ladder:
    """The ladder's three margins, which trade cost against the risk of an error beyond the
    tolerance (`bench/ladder_settings.py` measures that trade for other values)."""

    # A second-order run's relative error is about this × n^−2, n its time steps per estimated
    # contact (fitted on the ladders of bench/accuracy_vs_cost.py: 3.4 closed form, 5–10 Fig. 3,
    # 5.5 Fig. 5 once converging, 1–6 Fig. 9).
    error_constant: float = 6.0
    safety: float = 0.7  # a predicted grid aims its error estimate at this fraction of the tolerance
    # The Richardson estimate assumes both grids in the asymptotic range; on the presets the true
    # error was up to 1.3× the bare estimate, so the estimate reported and tested is this much larger.
    estimate_factor: float = 1.5


LADDER = Ladder()


def quantities(summary: dict) -> dict[str, float | None]:
    """The quantities a tolerance applies to, from a summary (None when the run has none)."""
    stress = max(summary["max_compressive_stress"]["value"], summary["max_tensile_stress"]["value"])
    return {
        "co_impact_time": summary["co_impact_time"],
        "peak_contact_force": summary["peak_contact_force"]["value"] or None,
        "max_stress": stress or None,
    }


def rigidity(case: Case) -> float:
    """ε: the two-mass system's highest frequency over the tool's lowest elastic one, `πa/(2L)`.

    The contact is linearised at the depth of a rigid-wall impact (the estimate the time step
    starts from too): tangent stiffness `(1+α)·c1·depth^α`.
    """
    alpha, m1 = case.contact.exponent, case.striker.mass
    m2 = tool_mass(case.tool)
    period = contact_time_estimate(case)
    k_contact = (1.0 + alpha) * m1 * (math.pi / period) ** 2  # = (1+α)·G at the rigid-wall depth
    k_medium = case.medium.stiffness if case.medium else 0.0
    # The larger root of det(K − ω²M) = 0 for K = [[k, −k], [−k, k + k_medium]], M = diag(m1, m2):
    # a quadratic whose roots are real and whose larger one suffers no cancellation.
    half_trace = 0.5 * (k_contact / m1 + (k_contact + k_medium) / m2)
    omega2 = half_trace + math.sqrt(max(half_trace**2 - k_contact * k_medium / (m1 * m2), 0.0))
    return math.sqrt(omega2) / (math.pi * wave_speed(case.tool) / (2.0 * case.tool.length))


def _relative_changes(fine: dict, coarse: dict) -> dict[str, float]:
    """`|Q_f − Q_c|/|Q_f|` per quantity that both runs have."""
    return {name: abs(fine[name] - coarse[name]) / abs(fine[name]) for name in QUANTITIES
            if fine[name] is not None and coarse[name] is not None}


def _estimate(runs: list, order: float, estimate_factor: float) -> tuple[dict[str, float], list[int]]:
    """The last run's error per quantity, the largest over its partners, and the numbers of
    contacts the partners saw.

    Against each earlier run `MIN_REFINEMENT` to `MAX_REFINEMENT` times coarser (else the one
    before it), Richardson: `|Q_f − Q_c|/(r^p − 1)`, taken `estimate_factor` larger. A closer run
    (before the ladder's one small step) would amplify what is not yet asymptotic, but it still
    says the finer grid's error is at least the change the step made (`r^p − 1 < 1` there): a
    change beyond the tolerance refutes the coarser partners' agreement.
    """
    last, fine, _ = runs[-1]
    refinements = [math.sqrt((numerics.time_step / last.time_step) * (last.cells / numerics.cells))
                   for numerics, _, _ in runs[:-1]]
    richardson = [k for k, r in enumerate(refinements)
                  if MIN_REFINEMENT <= r <= MAX_REFINEMENT] or [len(runs) - 2]
    close = [k for k, r in enumerate(refinements)
             if MIN_STEP <= r < MIN_REFINEMENT and k not in richardson]
    estimate: dict[str, float] = {}
    for k in richardson + close:
        r = refinements[k]
        scale = estimate_factor / (r**order - 1.0) if k in richardson else 1.0
        for name, change in _relative_changes(fine, runs[k][1]).items():
            estimate[name] = max(scale * change, estimate.get(name, 0.0))
    return estimate, [runs[k][2] for k in sorted(richardson + close)]


def _staged(progress: ProgressCallback | None, stage: int) -> ProgressCallback | None:
    """Progress of the stage-th run mapped into [1 − 2^−stage, 1 − 2^−(stage+1)]: monotone
    although the number of runs is not known in advance."""
    if progress is None:
        return None
    low, width = 1.0 - 0.5**stage, 0.5 ** (stage + 1)
    return lambda fraction: progress(low + width * fraction)


def _summary_only(case: Case, numerics: ResolvedNumerics) -> Case:
    """The case with only what a summary needs kept: no probes, no fields, a sparse history."""
    stride = max(1, numerics.steps // 2000)
    return case.model_copy(update={"outputs": Outputs(history_stride=stride)})


def solve_to_tolerance(case: Case, progress: ProgressCallback | None = None,
                       cancelled: CancelCheck | None = None, limits: Limits = Limits(),
                       recorder: Recorder | None = None, ladder: Ladder = LADDER) -> Result:
    """Meet `case.numerics.tolerance`; the summary reports the estimate, the runs and the choice.

    With a `recorder`, every rod run that may be the result records its outputs there, each
    starting it again, so that it holds the result's when this returns (then `streamed`); a
    lumped result is returned held in memory, as it is small.
    """
    tol = case.numerics.tolerance
    model = case.numerics.model
    eps = rigidity(case)
    lumped_error = LUMPED_ERROR * eps**2
    if model == "lumped" or (model is None and case.numerics.scheme is None and lumped_error <= tol):
        result = simulate_lumped(case, progress=progress, cancelled=cancelled)
        why = (f"the tool is stiff against the impact (ε = {eps:.3g}: its lowest elastic frequency "
               f"is {1 / eps:.3g}× the impact's), so the two-mass model (21)–(25) meets the "
               f"tolerance; its modelling error is estimated as {LUMPED_ERROR:g}·ε² = {lumped_error:.2g}")
        if model == "lumped":
            why = f"numerics.model = 'lumped' as asked; modelling error estimated as ε² = {lumped_error:.2g}"
        estimate = {name: lumped_error for name, v in quantities(result.summary).items() if v is not None}
        return _annotated(result, tol, estimate, runs=[result.numerics], why=why)

    scheme = case.numerics.scheme or DEFAULT_SCHEME
    order = make_scheme(scheme, case.numerics.gamma, case.numerics.sigma, case.numerics.end_masses).order
    period = contact_time_estimate(case)
    a, length = wave_speed(case.tool), case.tool.length

    runs: list[tuple[ResolvedNumerics, dict, int]] = []
    factor = 1.0
    worst = math.inf
    agree = True  # the last grid's partners saw as many contacts as it did
    stepped_small = False
    start = max(MIN_START_POINTS, 0.5 * (ladder.error_constant / tol) ** (1.0 / order))
    for stage in range(MAX_RUNS):
        tau = period / (start * factor)
        cells = max(math.ceil(MIN_CELLS * factor), math.ceil(length / (a * tau)))
        numerics = resolve_numerics(case, model="rod", scheme=scheme, cells=cells,
                                    time_step=min(COURANT * length / cells / a, tau))
        final_candidate = stage > 0
        run_case = case if final_candidate else _summary_only(case, numerics)
        try:
            check_limits(run_case, numerics, limits)
        except CaseError as error:
            raise CaseError([FieldError(
                field="numerics.tolerance",
                message=f"a tolerance of {tol:g} needs about {numerics.cells} cells and "
                        f"{numerics.steps} steps, beyond this service's limits ({error}): loosen it")]) from None
        result = simulate_rod(run_case, numerics=numerics, progress=_staged(progress, stage),
                              cancelled=cancelled, recorder=recorder if final_candidate else None)
        runs.append((numerics, quantities(result.summary), result.summary["contacts_total"]))
        if stage == 0:
            factor *= 2.0
            continue
        seen_fine = runs[-1][2]
        estimate, partner_contacts = _estimate(runs, order, ladder.estimate_factor)
        agree = all(seen == seen_fine for seen in partner_contacts)
        settled = agree or worst <= tol  # `worst`: the previous estimate, so far
        worst = max(estimate.values(), default=0.0)
        if worst <= tol and settled:
            if not agree:
                result.summary["warnings"].append(
                    f"the grids this error estimate rests on saw different numbers of contacts "
                    f"({seen_fine} on the last, {', '.join(map(str, partner_contacts))} on "
                    "the coarser ones it was compared with): the later impacts, and the stresses they "
                    "make, may be off by more than the estimate; shorten numerics.duration to the "
                    "impacts that matter or check them on a finer fixed grid")
            why = (f"the explicit scheme at Courant number 1 (second order, energy-conserving, and "
                   f"free of dispersion along a uniform tool there) on grids refined until the "
                   f"estimated error is within the tolerance; the lumped model was not enough "
                   f"(estimated modelling error {lumped_error:.2g})"
                   if case.numerics.scheme is None else
                   f"numerics.scheme = '{scheme}' as asked, on grids refined until the estimated error "
                   "is within the tolerance")
            return _annotated(result, tol, estimate, runs=[n for n, _, _ in runs], why=why)
        needed = (worst / (ladder.safety * tol)) ** (1.0 / order)
        # A small step only on an estimate to trust, and once: grids that disagree on the
        # contacts, or a small step that did not end the ladder, need a clear refinement.
        small = agree and not stepped_small
        stepped_small = stepped_small or (small and needed < MIN_REFINEMENT)
        factor *= min(max(needed, MIN_STEP if small else MIN_REFINEMENT), MAX_REFINEMENT)
    counts = ", ".join(str(c) for _, _, c in runs)
    why_not = (f"last estimate {worst:.2g}" if worst > tol else
               f"the last estimate, {worst:.2g}, is within it, but compares grids that saw different "
               "numbers of contacts")
    raise CaseError([FieldError(
        field="numerics.tolerance",
        message=f"{MAX_RUNS} grids did not reach a tolerance of {tol:g} ({why_not}; contacts seen by "
                f"each grid: {counts}"
                + ("; when that number keeps changing, the later impacts depend on the grid itself: "
                   "shorten numerics.duration to the impacts that matter" if not agree else "")
                + "): loosen it or give numerics.cells and numerics.time_step")])


def _annotated(result: Result, tol: float, estimate: dict[str, float],
               runs: list[ResolvedNumerics], why: str) -> Result:
    result.summary.update({
        "tolerance": tol,
        "error_estimate": {**estimate, "worst": max(estimate.values(), default=0.0)},
        "why": why,
        "runs": [{"model": n.model, "scheme": n.scheme, "cells": n.cells,
                  "time_step": n.time_step, "steps": n.steps} for n in runs],
    })
    return result

