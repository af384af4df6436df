"""Estimation's one home: what a run says of its own accuracy.

A run calls it once, with the runs it made (`assess`), and gets its `Accuracy`: the error
estimate, the tolerance asked, the grids and why they are those, and the warnings the estimate
calls for. The summary only prints it (`summary.add_accuracy`). `adaptive` chooses which runs to
make, reading the same estimate (`from_runs`) to decide the next grid.

Every summary states the relative error of six headline quantities (`HEADLINE`) and the transfer
efficiency. A quantity that is absent or negligible in a scene has no meaningful relative error
and is left out of the estimate with the reason (`left_out`): a first contact that lasts the whole
run has no co-impact time and no rebound, one that fades out a co-impact time that rounding sets;
a tension or a rebound that is a small fraction of its
natural scale, or the energy to a medium that takes almost nothing, would ask for an accuracy
nobody needs at a cost nobody wants.
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from .case import Case
    from .grid import ResolvedNumerics

HEADLINE = (
    "co_impact_time",
    "peak_contact_force",
    "max_compressive_stress",
    "max_tensile_stress",
    "energy.to_medium",
    "striker_rebound_velocity",
)

# Below these fractions of its scale a quantity is left out of the estimate
TENSION_FRACTION = 0.02  # of the maximum compressive stress
REBOUND_FRACTION = 0.02  # of the impact velocity W1
MEDIUM_FRACTION = 0.01  # of the input energy (initial + external work)
# A first contact whose overlap, where it ends, takes more than this fraction of the contact's
# length to cross the rounding of the displacements (`contact_fade_time`) fades out: the striker
# comes to rest against the tool on a link that relaxes slowly, and where it ends, within about ten
# of those times, is rounding's, not the grid's (seed 4's matrix-68: 53 µs on every grid from 87 to
# 2784 cells, 73 and 118 µs on the characteristics' grids). A first contact that parts takes about
# 1e-12 of its length (the presets'); the rock drill's piston, which comes to rest on the tool,
# 1.6e-4. Near the line: seed 4's matrix-47, a contact that chatters and says 'not met', 7.6e-4
# on its finest grid and 4.7e-3 on the one before (`bench/fade.py`).
FADE_FRACTION = 1e-3


def headline(summary: dict) -> dict[str, float | None]:
    """The headline quantities of a summary under their dotted names (None where it has none)."""
    return {
        "co_impact_time": summary["co_impact_time"],
        "peak_contact_force": summary["peak_contact_force"]["value"],
        "max_compressive_stress": summary["max_compressive_stress"]["value"],
        "max_tensile_stress": summary["max_tensile_stress"]["value"],
        "energy.to_medium": summary["energy"]["to_medium"],
        "striker_rebound_velocity": summary["striker_rebound_velocity"],
    }


def left_out(
    values: dict[str, float | None],
    impact_velocity: float,
    input_energy: float,
    has_medium: bool,
    contact_fade_time: float | None = None,
) -> dict[str, str]:
    """The headline quantities without a meaningful relative error, each with the reason; the first
    contact's `contact_fade_time` (s) tells whether it fades out."""
    reasons = {}
    if values["co_impact_time"] is None:
        reasons["co_impact_time"] = "the first contact lasts the whole run (or a history drives the struck end)"
        reasons["striker_rebound_velocity"] = "the striker never leaves the tool during the run (or there is none)"
    elif contact_fade_time is not None and contact_fade_time > FADE_FRACTION * values["co_impact_time"]:
        reasons["co_impact_time"] = (
            f"the first contact fades out: where it ends, after {values['co_impact_time']:.3g} s, its overlap "
            f"takes {contact_fade_time:.3g} s to cross the rounding of the displacements, so rounding, not the "
            "grid, sets its end"
        )
        reasons["striker_rebound_velocity"] = "the first contact fades out: rounding sets when the striker leaves"
    elif abs(values["striker_rebound_velocity"]) < REBOUND_FRACTION * abs(impact_velocity):
        reasons["striker_rebound_velocity"] = (
            f"the striker leaves at {values['striker_rebound_velocity']:.3g} m/s, under "
            f"{100 * REBOUND_FRACTION:g}% of its impact velocity"
        )
    compression = values["max_compressive_stress"] or 0.0
    tension = values["max_tensile_stress"] or 0.0
    if tension <= TENSION_FRACTION * compression:
        reasons["max_tensile_stress"] = (
            f"the tension, {tension / 1e6:.3g} MPa, is under {100 * TENSION_FRACTION:g}% of the compression"
            if tension > 0
            else "the tool is never in tension"
        )
    if not has_medium:
        reasons["energy.to_medium"] = "no medium"
    elif values["energy.to_medium"] < MEDIUM_FRACTION * input_energy:
        reasons["energy.to_medium"] = f"under {100 * MEDIUM_FRACTION:g}% of the input energy reaches the medium"
    if not values["peak_contact_force"]:
        reasons["peak_contact_force"] = "the striker never presses on the tool"
        reasons["max_compressive_stress"] = "the tool is never in compression"
    return reasons


def relative_change(fine: float | None, coarse: float | None) -> float:
    """`|fine − coarse|/|fine|` (inf when only one of them exists, 0 when neither does)."""
    if fine is None or coarse is None:
        return 0.0 if fine is coarse else float("inf")
    return abs(fine - coarse) / abs(fine) if fine else (0.0 if coarse == fine else float("inf"))


# --- The error of the finest of several grids -------------------------------------------------
#
# Grids refined in h and τ together, coarse to fine. On the last three the differences of a
# quantity give its observed order p (Q = Q* + C·h^p); the finest grid's error is then
# `|Q_3 − Q_2|/((h_2/h_3)^p − 1)` (Richardson), with p no larger than the scheme's own order
# (a faster apparent convergence is not relied on) and taken `SAFETY_FACTOR` larger (Roache's
# factor for three-grid studies). Grids whose differences change sign, or shrink slower than
# order `LOWEST_ORDER`, are not yet in their asymptotic range: the estimate is then the larger of
# the two differences read at that order (each `d/(r^0.5 − 1)`, r the refinement), ×`SAFETY_FACTOR`.
# With a fourth grid the order is trusted only as far as the three coarser grids confirm it (the
# smaller of the two orders), and at most
# `UNCONFIRMED_ORDER` where they are not in their asymptotic range (a tension behind a front can
# show order 2 on 4, 8 and 16 cells by chance, and 0.1 on 8, 16 and 32).

SAFETY_FACTOR = 1.25
LOWEST_ORDER = 0.5
UNCONFIRMED_ORDER = 1.0


ORDERS = (1e-3, 12.0)  # the orders an observed one is sought within


def observed_order(h: tuple[float, float, float], q: tuple[float, float, float]) -> float | None:
    """The order p with `(h2^p − h1^p)/(h3^p − h2^p) = (q2 − q1)/(q3 − q2)` (h1 > h2 > h3) within
    `ORDERS`, or None when the differences change sign or the finer one is not smaller. With equal
    refinements r (a doubling ladder's) the ratio is r^p, so p = ln((q2 − q1)/(q3 − q2))/ln r."""
    d1, d2 = q[1] - q[0], q[2] - q[1]
    if d1 == 0.0 or d2 == 0.0 or (d1 > 0.0) != (d2 > 0.0) or abs(d2) >= abs(d1):
        return None
    target = d1 / d2
    lo, hi = ORDERS
    coarse, fine = h[0] / h[1], h[1] / h[2]
    if abs(coarse - fine) <= 1e-12 * fine:
        return min(hi, max(lo, math.log(target) / math.log(fine)))

    def excess(p: float) -> float:  # grows with p
        return (h[1] ** p - h[0] ** p) / (h[2] ** p - h[1] ** p) - target

    if excess(hi) < 0.0:
        return hi
    if excess(lo) > 0.0:
        return lo
    from scipy.optimize import brentq  # loaded when grids refine unevenly, not with the summary's reader

    return brentq(excess, lo, hi, xtol=1e-14)


@dataclass(frozen=True)
class QuantityError:
    """The estimated relative error of one quantity on the finest grid, and how it was found."""

    error: float
    order: float | None  # observed; None with fewer than three grids or out of the asymptotic range
    asymptotic: bool


def quantity_error(h: list[float], values: list[float | None], formal_order: float) -> QuantityError:
    """The finest grid's relative error of one quantity from its values on grids `h` (coarse to
    fine, at least two)."""
    fine = values[-1]
    if fine is None or any(v is None for v in values[-3:]):
        return QuantityError(math.inf, None, False)
    scale = abs(fine) or math.inf
    if len(values) == 2:
        change = abs(values[1] - values[0])
        bare = change / ((h[0] / h[1]) ** formal_order - 1.0)
        return QuantityError(SAFETY_FACTOR * bare / scale, None, False)
    h3, q3 = tuple(h[-3:]), tuple(values[-3:])
    d1, d2 = q3[1] - q3[0], q3[2] - q3[1]
    if d2 == 0.0:
        return QuantityError(0.0 if d1 == 0.0 else SAFETY_FACTOR * abs(d1) / scale, None, d1 == 0.0)
    order = observed_order(h3, q3)
    if order is None or order < LOWEST_ORDER:
        # Each difference read at the lowest order relied on (refinement r: error d/(r^p − 1)),
        # the finer grid's error not taken to be smaller than the coarser's.
        rough = max(
            abs(d1) / ((h3[0] / h3[1]) ** LOWEST_ORDER - 1.0), abs(d2) / ((h3[1] / h3[2]) ** LOWEST_ORDER - 1.0)
        )
        return QuantityError(SAFETY_FACTOR * rough / scale, order, False)
    used, confirmed, finest = min(order, formal_order), True, abs(d2)
    off_trend = 0.0
    if len(values) >= 4 and values[-4] is not None:
        # Three coarse grids can show order 2 by chance; the three before must confirm it.
        before = observed_order(tuple(h[-4:-1]), tuple(values[-4:-1]))
        confirmed = before is not None and before >= LOWEST_ORDER
        used = min(used, before if confirmed else UNCONFIRMED_ORDER)
        if confirmed and order > formal_order:
            # Faster than the scheme converges: the finest grid is off the trend of the grids
            # before it, and its own three cannot say how far. An oscillating error passes near
            # zero on it (it swings back on the next): the difference before, carried at the order
            # the grids confirm, bounds it.
            finest = max(finest, abs(d1) / (h3[0] / h3[1]) ** used)
            refinement = h3[1] / h3[2]
            if abs(refinement - round(refinement)) > 1e-9 * refinement:
                # A grid not nested in the one before samples a feature apart (a peak near a kink
                # of the profile) and may lag the trend instead: the limit the three before
                # extrapolate to shows how far.
                off_trend = abs(q3[2] - (q3[1] + d1 / ((h3[0] / h3[1]) ** used - 1.0)))
    bare = max(finest / ((h3[1] / h3[2]) ** used - 1.0), off_trend)
    return QuantityError(SAFETY_FACTOR * bare / scale, order, confirmed)


@dataclass(frozen=True)
class Estimate:
    """The finest grid's error estimate: per quantity, the quantities left out (with why), and
    whether the two finest grids it rests on agree on the number of contacts."""

    errors: dict[str, QuantityError]
    left_out: dict[str, str]
    same_contacts: bool
    contacts: tuple[int, ...] = ()  # each grid's, coarse to fine
    formal_order: float = 2.0

    @property
    def worst(self) -> float:
        return max((e.error for e in self.errors.values()), default=0.0)

    @property
    def asymptotic(self) -> bool:
        return all(e.asymptotic for e in self.errors.values())

    def relative(self) -> dict[str, float]:
        """The summary's `error_estimate`: each quantity's estimate and the worst."""
        return {**{name: e.error for name, e in self.errors.items()}, "worst": self.worst}


ESTIMATED = HEADLINE + ("energy.transfer_efficiency", "set", "blow_count")
# a hammer at work's (`cycles`): its last impact velocity, and its cycle's frequency, impact energy
# and efficiency
CYCLE_ESTIMATED = ("cycle.impact_velocity", "cycle.frequency", "cycle.impact_energy", "cycle.efficiency")


def estimated_names(summary: dict) -> tuple[str, ...]:
    """The quantities a run's error is estimated for: `ESTIMATED`, and a work cycle's."""
    return ESTIMATED + (CYCLE_ESTIMATED if summary.get("cycle") is not None else ())


SET_FRACTION = 0.01  # of the deepest penetration: below it a set is refusal, its relative error moot


def estimated_values(summary: dict) -> dict[str, float | None]:
    """The quantities an error is estimated for: the headline ones, the transfer efficiency,
    where the medium yields the set and the blow count, and a work cycle's."""
    values = {
        **headline(summary),
        "energy.transfer_efficiency": summary["energy"]["transfer_efficiency"],
        "set": summary["set"],
        "blow_count": summary["blow_count"],
    }
    cycle = summary.get("cycle")
    if cycle is not None:
        values |= {
            "cycle.impact_velocity": cycle["impact_velocity"][-1],
            "cycle.frequency": cycle["frequency"],
            "cycle.impact_energy": cycle["impact_energy"],
            "cycle.efficiency": cycle["efficiency"],
        }
    return values


def set_left_out(summary: dict) -> str | None:
    """Why a run's set (and blow count) has no meaningful relative error, if it has none."""
    found = summary["set"]
    if found is None:
        return "the medium does not yield" if summary["medium_penetration"] else "no medium"
    deepest = summary["medium_penetration"]["max"]
    if found <= SET_FRACTION * deepest:
        return (
            f"the set, {found * 1e3:.3g} mm, is under {100 * SET_FRACTION:g}% of the deepest penetration "
            f"({deepest * 1e3:.3g} mm): refusal"
        )
    return None


def not_estimated(summary: dict, impact_velocity: float, has_medium: bool) -> dict[str, str]:
    """The estimated quantities a run leaves out (`left_out`), the efficiency with the energy."""
    energy = summary["energy"]
    skip = left_out(
        headline(summary),
        impact_velocity,
        energy["initial"] + max(energy["external_work"], 0.0),
        has_medium,
        summary["contact_fade_time"],
    )
    if "energy.to_medium" in skip:
        skip["energy.transfer_efficiency"] = skip["energy.to_medium"]
    reason = set_left_out(summary)
    if reason:
        skip["set"] = skip["blow_count"] = reason
    cycle = summary.get("cycle")
    if cycle is not None:
        for name in ("frequency", "efficiency"):
            if cycle[name] is None:
                skip[f"cycle.{name}"] = "one cycle: no flight to time" if name == "frequency" else "no hydraulic energy"
    return skip


# The largest stresses and the rows of the stress envelope (`summary.stress_envelope`) they are the
# largest of
ENVELOPED = {"max_compressive_stress": "compression", "max_tensile_stress": "tension"}


def with_the_whole_tool(
    error: QuantityError, h: list[float], summaries: list[dict], name: str, kind: str, formal_order: float
) -> QuantityError:
    """The error of the largest stress `name`, allowing for the rest of the tool: a stretch's own
    greatest stress (`kind` of its envelope) that rises from grid to grid at an order its grids
    show, taken as far as its own estimate reaches, may pass the largest, which it would then be
    on a finer grid. A peak just behind a front, which coarse grids smear, can rise at first order
    in one part of the tool while the grids agree on the largest elsewhere (`docs/numerics.md`).
    The stretches next to the largest's hold the largest's own peak, which their bounds cut as the
    nodes move from grid to grid: its own estimate answers for it. A stretch whose grids show no
    order yet is left to the grids after: read at the lowest order, a peak that rises toward the
    largest from below (the rock drill's reflected front, 271 to 294 MPa under 299 on 976 to 9760
    cells) would take the ladder twice as far for nothing."""
    largest = summaries[-1][name]
    rows = [s["stress_envelope"][kind] if s.get("stress_envelope") else None for s in summaries]
    if len(rows) < 3 or rows[-1] is None or not largest["value"] > 0.0:  # an order needs three grids
        return error
    bounds = summaries[-1]["stress_envelope"]["x"]
    at = min(max(bisect.bisect_right(bounds, largest["x"]) - 1, 0), len(rows[-1]) - 1)
    worst = error
    for b in range(len(rows[-1])):
        values = [row[b] if row is not None else None for row in rows]
        if abs(b - at) <= 1 or any(v is None for v in values[-3:]) or not values[-3] < values[-2] < values[-1]:
            continue
        # the most `quantity_error` makes of the last two differences at an order of at least
        # LOWEST_ORDER: a stretch it cannot take past the largest is not read (an estimate on a
        # grid not nested in the one before seeks each stretch's order by root finding)
        d1, d2 = values[-2] - values[-3], values[-1] - values[-2]
        r1, r2 = h[-3] / h[-2], h[-2] / h[-1]
        most = SAFETY_FACTOR * (max(d1, d2) / (r2**LOWEST_ORDER - 1.0) + d2 + d1 / (r1**LOWEST_ORDER - 1.0))
        if values[-1] + most <= largest["value"]:
            continue
        found = quantity_error(h, values, formal_order)
        if found.order is None or found.order < LOWEST_ORDER:
            continue
        excess = (values[-1] + abs(values[-1]) * found.error) / largest["value"] - 1.0
        if excess > worst.error:
            worst = QuantityError(excess, found.order, found.asymptotic)
    return worst


# A largest stress within a cell of a bend of the tool's profile (`kinks`) is read at the node
# nearest the bend, which moves from grid to grid: its error is of this order at best, however
# smooth the rest (seed 1's matrix-57: a tension at a taper's start, 276.0, 296.8, 304.1, 306.9,
# 308.8 MPa on 164 to 2424 cells toward 311, read at order 2 on 328, 656 and 1212 cells)
KINK_ORDER = 1.0


def estimate(
    h: list[float],
    summaries: list[dict],
    formal_order: float,
    impact_velocity: float,
    has_medium: bool,
    kinks: tuple[float, ...] = (),
) -> Estimate:
    """The error of the finest of the runs `summaries` on grids of cell size `h` (coarse to
    fine), on a tool whose profile bends at `kinks` (m). What is left out is decided on the finest
    run."""
    values = [estimated_values(s) for s in summaries]
    skip = not_estimated(summaries[-1], impact_velocity, has_medium)

    def order_of(name: str) -> float:
        """The scheme's order, or `KINK_ORDER` for a largest stress at a bend of the profile."""
        at_a_kink = name in ENVELOPED and any(abs(summaries[-1][name]["x"] - k) <= h[-1] for k in kinks)
        return min(formal_order, KINK_ORDER) if at_a_kink else formal_order

    errors = {
        name: quantity_error(h, [v[name] for v in values], order_of(name))
        for name in estimated_names(summaries[-1])
        if name not in skip
    }
    for name, kind in ENVELOPED.items():
        if name in errors:
            errors[name] = with_the_whole_tool(errors[name], h, summaries, name, kind, formal_order)
    # the two finest grids must agree: a grazing contact that a coarse grid still sees or misses
    # changes none of the quantities estimated by more than their differences show
    contacts = tuple(s["contacts_total"] for s in summaries[-3:])
    return Estimate(errors, skip, contacts[-1] == contacts[-2], contacts, formal_order)


def from_runs(case: Case, runs: list[tuple[ResolvedNumerics, dict]], formal_order: float) -> Estimate:
    """The error of the finest of `case`'s `runs` (numerics and summary, coarse to fine)."""
    return estimate(
        [case.tool.length / n.cells for n, _ in runs],
        [s for _, s in runs],
        formal_order,
        case.impact_velocity,
        case.medium is not None,
        tuple(case.tool.profile.x[1:-1]) if case.tool.profile is not None else (),
    )


def modelled(case: Case, summary: dict, error: float) -> Estimate:
    """A model's own error, `error` on every quantity the run does not leave out (the lumped
    model's ε², which no grid reduces)."""
    skip = not_estimated(summary, case.impact_velocity, case.medium is not None)
    return Estimate(
        {name: QuantityError(error, None, False) for name in estimated_names(summary) if name not in skip}, skip, True
    )


@dataclass(frozen=True)
class Accuracy:
    """What a run says of its accuracy (`assess`), as the summary prints it: the tolerance asked
    (None on a fixed grid), the estimate (None when none could be made), why the grids are those
    they are, the grids (coarse to fine), and the warnings."""

    tolerance: float | None
    estimate: Estimate | None
    why: str
    runs: list[ResolvedNumerics]
    warnings: list[str] = field(default_factory=list)

    @property
    def error_estimate(self) -> dict[str, float] | None:
        return self.estimate.relative() if self.estimate else None

    @property
    def not_estimated(self) -> dict[str, str]:
        return dict(self.estimate.left_out) if self.estimate else {}


def assess(
    found: Estimate | None,
    summary: dict,
    *,
    tolerance: float | None,
    runs: list[ResolvedNumerics],
    why: str,
    unmet: str = "",
    notes: list[str] = (),
) -> Accuracy:
    """The accuracy of the run whose summary is `summary`: the estimate `found`, and as warnings
    `notes` (the caller's, e.g. why no estimate) then what the estimate calls for
    (`accuracy_warnings`; `unmet` says why a tolerance could not be met)."""
    warnings = list(notes)
    if found is not None:
        warnings += accuracy_warnings(found, summary, tolerance, unmet)
    return Accuracy(tolerance, found, why, list(runs), warnings)


# --- What a summary says of its accuracy -------------------------------------------------------

ERROR_WARNING = 0.01  # an estimated error above this is worth a warning
ENERGY_WARNING = 0.01  # so is energy lost or created by the scheme, as a fraction of the input


def _percent(fraction: float) -> str:
    return f"{100 * fraction:.2g}%" if fraction < math.inf else "unknown (the grids do not agree)"


def _listed(errors: dict[str, QuantityError], limit: float) -> str:
    over = sorted(((e.error, name) for name, e in errors.items() if e.error > limit), reverse=True)
    return ", ".join(f"{name} {_percent(error)}" for error, name in over)


def accuracy_warnings(found: Estimate, summary: dict, tolerance: float | None, unmet: str = "") -> list[str]:
    """The warnings an estimate calls for: a tolerance not met, an estimated error over 1% on a
    fixed grid (with the grid that would meet 1%), grids that disagree on the contacts, and energy
    the scheme lost or created beyond 1% of the input; each with the numbers and what to change."""
    out = []
    if tolerance is not None:
        if unmet or found.worst > tolerance or not found.same_contacts:
            reason = unmet or (
                "the grids disagree on the contacts" if found.worst <= tolerance else "the estimate stays above it"
            )
            out.append(
                f"the tolerance of {tolerance:g} is not met ({reason}): estimated errors "
                f"{_listed(found.errors, tolerance) or 'within it'}; the values are the finest "
                "grid's"
            )
    elif found.worst > ERROR_WARNING:
        cells = summary["numerics"]["cells"]
        order = min(
            (e.order or found.formal_order) if e.asymptotic else 1.0
            for e in found.errors.values()
            if e.error > ERROR_WARNING
        )
        needed = (
            math.ceil(cells * (found.worst / (0.5 * ERROR_WARNING)) ** (1.0 / max(order, 0.5)))
            if found.worst < math.inf
            else None
        )
        grid = f" or about {needed} cells with the time step scaled alike" if needed else ""
        out.append(
            f"estimated errors over {_percent(ERROR_WARNING)}: {_listed(found.errors, ERROR_WARNING)}; "
            f"leave out numerics.cells, time_step and scheme for the default accuracy (1%), give "
            f"numerics.tolerance{grid}"
        )
    if not found.same_contacts:
        out.append(
            f"the grids this estimate rests on saw different numbers of contacts "
            f"({', '.join(map(str, found.contacts))}, coarse to fine): the later impacts, and "
            "the stresses they make, may be off by more than the estimate"
        )
    energy = summary["energy"]
    budget = energy["initial"] + max(energy["external_work"], 0.0)
    if budget > 0:
        lost = energy["numerical"] / budget
        created = energy["max_excess_fraction"]
        fix = (
            "give numerics.tolerance or a finer grid"
            if tolerance is None
            else "a tighter numerics.tolerance reduces it"
        )
        if lost > ENERGY_WARNING:
            out.append(
                f"the scheme dissipated {_percent(lost)} of the input energy "
                f"(energy.numerical = {energy['numerical']:.4g} J): {fix}"
            )
        if max(-lost, created) > ENERGY_WARNING:
            out.append(f"the scheme created {_percent(max(-lost, created))} of the input energy at some instant: {fix}")
    return out
