"""Which runs a case takes to answer with its error (`solve`): a ladder of grids to a tolerance,
a fixed grid with its companions, or the lumped model. Each returns its result and, from one call
to `accuracy.assess`, what the result says of its accuracy.

**Under a tolerance** (`numerics.tolerance`, or the default 0.01 when the case gives no grid and
no scheme) the solver chooses the grid: the explicit scheme at Courant number 1, whose ends
integrate their own equations (`kernel.struck_end_step`), on grids refined in h and τ together.
It climbs from a coarse grid placed a priori (`first_cells`), each grid twice as fine as the last,
so that every three in a row show the order they converge at (`accuracy.estimate`: the order
observed, not an assumed one, and confirmed by the three before). Once the last four are in
their asymptotic range the next grid is as fine as the estimate says is needed (at the order observed, aiming at `AIM`× the
tolerance, 1.2–4× finer). The ladder stops when every quantity's estimate on the finest grid is
within the tolerance, the two finest grids saw the same number of contacts and the energy audit
closes within half the tolerance (`energy_closed`). One that cannot (the grids
keep disagreeing, the limits stop it, or `MAX_RUNS` grids were not enough) returns its finest run
with the estimate it has and says so in `warnings`.

**On a fixed grid** (the case gives cells, a time step or a scheme) the run is the one asked
for, and two companion runs on grids 2× and 4× coarser in h and τ (about 31% more work) give
its estimate the same way (`fixed_grid`).

`numerics.model = 'lumped'` is the two-mass model (21)–(25), whose modelling error grows as ε²,
ε the two-mass system's highest frequency over the tool's lowest elastic one (`rigidity`).

A case over the limits is refused before any run (`limits.check_limits`), naming what to change.
"""

from __future__ import annotations

import math

from .accuracy import SAFETY_FACTOR, Accuracy, Estimate, assess, from_runs, modelled
from .case import Case, CaseError, FieldError
from .controller import simulate_rod
from .grid import (
    MIN_CELLS,
    ResolvedNumerics,
    explicit_numerics,
    first_cells,
    ladder_unit,
    resolve_numerics,
    rigidity,
    tolerance_of,
)
from .limits import Limits, check_limits, output_values
from .lumped import simulate_lumped
from .result import CancelCheck, ProgressCallback, Recorder, Result

CLIMB = 2.0  # refinement from one grid to the next until four in a row are asymptotic
MIN_RUNS = 4  # an estimate from three grids, its order confirmed by the three before
MIN_STEP, MAX_STEP = 1.2, 4.0  # refinement to a predicted grid
AIM = 0.75  # a predicted grid aims its bare estimate at this fraction of the tolerance
SURE_ORDER = 1.5  # below this observed order a predicted grid is at most `CLIMB` finer
MAX_RUNS = 14
ENERGY_CLOSURE = 0.5  # of the tolerance: how closely a ladder's energy audit must close
UNSETTLED_GRIDS = 3  # contacts that change from grid to grid over this many, with no gain, stop a ladder
# A run from the fourth grid on may be the result and records its outputs; one whose outputs are
# this many numbers or more (24 MB: a hammer's many cycles, fields) only when it is expected to be
# (`records_long_outputs`)
LONG_OUTPUTS = 3e6
RECORD_MARGIN = 2.0  # of the tolerance: the most a run that may be the result is expected to miss it by
COMPANIONS = (4, 2)  # a fixed grid's companions, this many times coarser
LUMPED_ERROR = 1.0  # the lumped model's relative error is at most this × ε² (measured ≤ 0.58)
FIXED_SHARE = 0.75  # of a fixed grid's progress: the run asked for; its companions the rest
CHATTER_STEPS = 5.0  # a contact resolved by fewer steps than this says nothing of the case


def solve(
    case: Case,
    progress: ProgressCallback | None = None,
    cancelled: CancelCheck | None = None,
    limits: Limits = Limits(),
    recorder: Recorder | None = None,
) -> tuple[Result, Accuracy]:
    """Answer `case` as its numerics ask: the lumped model, a tolerance (given, or the default
    when the case gives neither a grid nor a scheme), or the fixed grid it gives; with what the
    answer says of its accuracy. With a `recorder`, the result's outputs are recorded there."""
    if case.numerics.model == "lumped":
        return lumped(case, progress, cancelled, limits)
    tol = tolerance_of(case.numerics)
    if tol is not None:
        return solve_to_tolerance(case, tol, progress=progress, cancelled=cancelled, limits=limits, recorder=recorder)
    return fixed_grid(case, progress, cancelled, limits, recorder)


def _staged(progress: ProgressCallback | None, stage: int) -> ProgressCallback | None:
    """Progress of the stage-th run mapped into [1 − 2^−stage, 1 − 2^−(stage+1)]: monotone
    although the number of runs is not known in advance."""
    if progress is None:
        return None
    low, width = 1.0 - 0.5**stage, 0.5 ** (stage + 1)
    return lambda fraction: progress(low + width * fraction)


def _limit_refusal(tol: float, numerics: ResolvedNumerics, error: CaseError) -> CaseError:
    return CaseError(
        [
            FieldError(
                field="numerics.tolerance",
                message=f"a tolerance of {tol:g} needs at least {numerics.cells} cells and {numerics.steps} "
                f"steps, beyond the limits ({error}): loosen it, shorten numerics.duration, or "
                "raise the limit",
            )
        ]
    )


def solve_to_tolerance(
    case: Case,
    tol: float,
    progress: ProgressCallback | None = None,
    cancelled: CancelCheck | None = None,
    limits: Limits = Limits(),
    recorder: Recorder | None = None,
) -> tuple[Result, Accuracy]:
    """Meet `tol` on every estimated quantity (see the module's docstring); the summary reports the
    estimate, the grids and why.

    With a `recorder`, every run that may be the result records its outputs there, each starting
    it again, so that it holds the result's when this returns (then `streamed`).
    """
    order = 2.0
    runs: list[tuple[ResolvedNumerics, dict]] = []
    cells = first_cells(case, tol)
    unit = ladder_unit(case, cells)  # an elastic striker kept a whole number of cells
    result = None
    found: Estimate | None = None
    worst: list[float] = []  # each estimate's, from the `MIN_RUNS`-th grid on
    stopped = ""
    for stage in range(MAX_RUNS):
        numerics = explicit_numerics(case, cells)
        may_be_result = stage >= MIN_RUNS - 1  # from the fourth grid on, a run has an estimate
        try:
            check_limits(case if may_be_result else case.summary_only(), numerics, limits)
        except CaseError as error:
            if result is None:
                raise _limit_refusal(tol, numerics, error) from None
            stopped = (
                f"the next grid, {numerics.cells} cells and {numerics.steps} steps, is beyond the limits ({error})"
            )
            break
        recording = may_be_result and records_long_outputs(case, numerics, runs, found, order, tol)
        candidate = simulate_rod(
            case if recording else case.summary_only(),
            numerics=numerics,
            progress=_staged(progress, stage),
            cancelled=cancelled,
            recorder=recorder if recording else None,
        )
        runs.append((numerics, candidate.summary))
        if len(runs) < MIN_RUNS:
            cells = math.ceil(cells * CLIMB)
            continue
        result, found = candidate, from_runs(case, runs, order)
        worst.append(found.worst)
        closed = energy_closed(candidate.summary, tol)
        if found.worst <= tol and found.same_contacts and closed:
            if not recording:  # the result after all: its outputs, from the same run again
                result = simulate_rod(
                    case,
                    numerics=numerics,
                    progress=_staged(progress, stage + 1),
                    cancelled=cancelled,
                    recorder=recorder,
                )
            break
        if unsettled([s["contacts_total"] for _, s in runs], worst):
            stopped = (
                f"the number of contacts keeps changing with the grid ("
                f"{', '.join(str(s['contacts_total']) for _, s in runs[-UNSETTLED_GRIDS:])} on "
                f"{', '.join(str(n.cells) for n, _ in runs[-UNSETTLED_GRIDS:])} cells) while the "
                "estimate does not shrink: the sequence of impacts is sensitive to the smallest "
                "change, and finer grids do not settle it"
            )
            break
        cells = math.ceil(cells * (next_refinement(found, tol) if closed else CLIMB) / unit) * unit
    else:
        stopped = f"{MAX_RUNS} grids did not reach it"
    why = (
        f"the default accuracy (numerics gives neither a grid nor a scheme), as if numerics.tolerance were {tol:g}: "
        if case.numerics.tolerance is None
        else ""
    )
    why += (
        "the explicit scheme at Courant number 1, its ends integrating their own equations, on "
        "grids refined until the error estimated from the last three is within the tolerance"
    )
    return result, assess(found, result.summary, tolerance=tol, runs=[n for n, _ in runs], why=why, unmet=stopped)


def records_long_outputs(
    case: Case,
    numerics: ResolvedNumerics,
    runs: list[tuple[ResolvedNumerics, dict]],
    found: Estimate | None,
    order: float,
    tol: float,
) -> bool:
    """Whether a run that may be the ladder's result records its outputs: always, but one with long
    outputs (`LONG_OUTPUTS`: writing them can cost more than the run) only when the ladder's
    estimate before it (`found`; on the fourth grid, that of the three before it), carried to its
    grid at the scheme's `order`, misses `tol` by at most `RECORD_MARGIN`. Should one that was not
    recorded meet the tolerance, it is run again to record: the same results, at the cost of a run.
    (A hammer's 100 cycles wrote 1.24 million rows for three runs where one was the result.)"""
    if output_values(case, numerics) < LONG_OUTPUTS:
        return True
    before = found if found is not None else from_runs(case, runs, order)
    return before.worst * (runs[-1][0].cells / numerics.cells) ** order <= RECORD_MARGIN * tol


def energy_closed(summary: dict, tol: float) -> bool:
    """Whether the energy audit closes within `ENERGY_CLOSURE`·tol of the energy supplied: what
    the scheme lost or made (`energy.numerical`) is an error of its own, which the headline
    quantities' differences need not show (a front a stiff contact delays by less than a step
    loses energy on every grid, at an order of its own)."""
    energy = summary["energy"]
    supplied = energy["initial"] + max(energy["external_work"], 0.0)
    return abs(energy["numerical"]) <= ENERGY_CLOSURE * tol * supplied


def unsettled(contacts: list[int], worst: list[float]) -> bool:
    """Whether refining has stopped helping: each of the last `UNSETTLED_GRIDS` grids saw a
    different number of contacts from the grid before it (`contacts`, each grid's) and the estimate
    (`worst`, each estimate's) is no smaller than `UNSETTLED_GRIDS − 1` grids before. Repeated
    impacts whose sequence turns on the smallest change (a chaotic rattle) settle on no grid; a
    count that changes and then holds is a rebound the coarser grids did not resolve yet (a pile's
    helmet on 16–64 cells), which finer ones do."""
    recent = contacts[-UNSETTLED_GRIDS:]
    return (
        len(worst) >= UNSETTLED_GRIDS
        and all(coarse != fine for coarse, fine in zip(recent, recent[1:]))
        and worst[-1] >= worst[-UNSETTLED_GRIDS]
    )


def next_refinement(found: Estimate, tol: float) -> float:
    """How much finer the next grid is: `CLIMB` while the two finest grids disagree on the
    contacts, or a quantity still to be refined is not in its asymptotic range; otherwise as the
    worst quantity's estimate asks at the order its grids showed (1–2), aiming its bare estimate
    (without the safety factor, which the stopping test applies) at `AIM` of the tolerance:
    1.2–4× finer, at most `CLIMB` where that order is below `SURE_ORDER` (a low order seen on
    coarse grids is often not yet the one they converge at)."""
    wanting = [e for e in found.errors.values() if e.error > AIM * tol]
    if not found.same_contacts or not all(e.asymptotic for e in wanting):
        return CLIMB
    needed, cap = MIN_STEP, MAX_STEP
    for e in wanting:
        order = max(1.0, min(e.order, 2.0))
        needed = max(needed, (e.error / SAFETY_FACTOR / (AIM * tol)) ** (1.0 / order))
        if e.order < SURE_ORDER:
            cap = CLIMB
    return min(needed, cap)


def fixed_grid(
    case: Case,
    progress: ProgressCallback | None,
    cancelled: CancelCheck | None,
    limits: Limits,
    recorder: Recorder | None,
) -> tuple[Result, Accuracy]:
    """The run on the grid the case gives, its error estimated from companion runs `COMPANIONS`
    times coarser in h and τ (as many of them as the grid allows) at the scheme's order."""
    numerics = resolve_numerics(case)
    check_limits(case, numerics, limits)
    share = None if progress is None else (lambda fraction: progress(FIXED_SHARE * fraction))
    result = simulate_rod(case, numerics=numerics, progress=share, cancelled=cancelled, recorder=recorder)
    refuse_chatter(result.summary, numerics)
    why = fixed_choice(case, numerics)
    companions, missing = [], []
    for factor in COMPANIONS:
        cells = round(numerics.cells / factor)
        if cells < MIN_CELLS:
            missing.append(f"{factor}× coarser: fewer than {MIN_CELLS} cells")
            continue
        try:
            coarse = resolve_numerics(
                case,
                model="rod",
                scheme=numerics.scheme,
                cells=cells,
                time_step=numerics.time_step * numerics.cells / cells,
            )
            companion = simulate_rod(case.summary_only(), numerics=coarse, cancelled=cancelled)
            refuse_chatter(companion.summary, coarse)
            companions.append((coarse, companion.summary))
        except CaseError as error:  # a grid too coarse for a stiff contact or medium
            missing.append(f"{factor}× coarser: {error.errors[0].message.split(':')[0]}")
    if progress is not None:
        progress(1.0)
    if not companions:
        return result, assess(
            None,
            result.summary,
            tolerance=None,
            runs=[numerics],
            why=why,
            notes=[
                f"no error estimate: no coarser grid to compare {numerics.cells} cells with "
                f"({'; '.join(missing)}); leave numerics.cells, time_step and scheme out for the "
                "default accuracy, which estimates its error, or give numerics.tolerance"
            ],
        )
    notes = (
        [f"the error estimate rests on one coarser grid, at the scheme's order ({'; '.join(missing)})"]
        if missing
        else []
    )
    runs = companions + [(numerics, result.summary)]
    found = from_runs(case, runs, numerics.weights().order)
    return result, assess(found, result.summary, tolerance=None, runs=[n for n, _ in runs], why=why, notes=notes)


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


def lumped(
    case: Case, progress: ProgressCallback | None, cancelled: CancelCheck | None, limits: Limits
) -> tuple[Result, Accuracy]:
    """The two-mass model (21)–(25), its error its modelling error, `LUMPED_ERROR·ε²` on every
    quantity."""
    check_limits(case, resolve_numerics(case), limits)
    result = simulate_lumped(case, progress=progress, cancelled=cancelled)
    eps = rigidity(case)
    error = LUMPED_ERROR * eps**2
    return result, assess(
        modelled(case, result.summary, error),
        result.summary,
        tolerance=case.numerics.tolerance,
        runs=[result.numerics],
        why=f"numerics.model = 'lumped' as asked: the two-mass model problem (21)–(25); "
        f"its modelling error estimated as ε² = {error:.2g} (ε = {eps:.3g}, the "
        "two-mass system's highest frequency over the tool's lowest elastic one)",
    )
