"""The pulse summary (the contract's JSON) from what a run observed."""

from __future__ import annotations

import math

import numpy as np

from . import kernel as K
from .case import Case
from .grid import ResolvedNumerics

FORCE_HISTORY_POINTS = 2000
# The summary's force history: its keys and the history paths they come from
FORCE_HISTORY = {"time": "time", "contact": "contact/force", "medium": "medium/force"}
MIN_STEPS_PER_CONTACT = 20  # below this the contact force's time error exceeds about 1%
ENERGY_EXCESS_LIMIT = 0.005  # energy created by the scheme, as a fraction of the input


def _number(value: float) -> float | None:
    value = float(value)
    return value if math.isfinite(value) else None


def force_history_rows(rows: int) -> np.ndarray:
    """The rows of a history of `rows` the summary's force history keeps: all of a short one, else
    FORCE_HISTORY_POINTS evenly spread (spacing ≥ 1, so the truncated indices are distinct and
    increasing)."""
    if rows <= FORCE_HISTORY_POINTS:
        return np.arange(rows)
    return np.linspace(0, rows - 1, FORCE_HISTORY_POINTS).astype(int)


def _downsample(history: dict[str, np.ndarray]) -> dict[str, list]:
    pick = force_history_rows(len(history["time"]))
    return {key: history[path][pick].tolist() for key, path in FORCE_HISTORY.items()}


def _warnings(case: Case, numerics: ResolvedNumerics, trackers, excess: float) -> list[str]:
    found = []
    steps = trackers[K.T_MIN_CONTACT_STEPS]
    # Under a tolerance the ladder's error estimate speaks for the resolution, not this rule.
    if case.numerics.tolerance is None and math.isfinite(steps) and steps < MIN_STEPS_PER_CONTACT:
        shorter = numerics.time_step * steps / MIN_STEPS_PER_CONTACT
        found.append(
            f"a contact interval was resolved by only {steps:.1f} time steps; about 1% accuracy on "
            f"the contact needs at least {MIN_STEPS_PER_CONTACT}: set numerics.time_step ≤ {shorter:.3g} s "
            "or give numerics.tolerance"
        )
    if excess > ENERGY_EXCESS_LIMIT:
        found.append(
            f"the scheme created {100 * excess:.2f}% of the input energy at some instant; "
            "reduce numerics.time_step"
        )
    return found


def build_summary(case: Case, numerics: ResolvedNumerics, trackers: np.ndarray,
                  contacts: np.ndarray, energy: np.ndarray, history: dict[str, np.ndarray],
                  extra_warnings: list[str] | None = None) -> dict:
    """Assemble the summary; `trackers`, `contacts` and `energy` use the kernel's slot layout, and
    `history` needs the paths of FORCE_HISTORY only.

    `extra_warnings` (the caller's own, e.g. outputs a model cannot provide) follow the checks'.
    """
    count = int(trackers[K.T_CONTACTS])
    intervals = [{"start": float(s), "end": float(e)} for s, e in contacts[:min(count, len(contacts))]]
    if trackers[K.T_IN_CONTACT]:
        intervals.append({"start": float(trackers[K.T_CONTACT_START]), "end": None})

    initial = 0.5 * case.striker.mass * case.striker.velocity**2
    stored = {
        "striker_kinetic": energy[K.E_STRIKER_KINETIC],
        "tool_kinetic": energy[K.E_TOOL_KINETIC],
        "tool_strain": energy[K.E_TOOL_STRAIN],
        "contact_potential": energy[K.E_CONTACT_POTENTIAL],
        "medium_potential": energy[K.E_MEDIUM_POTENTIAL],
    }
    external = energy[K.E_EXTERNAL_WORK]
    dissipated_contact = energy[K.E_DISSIPATED_CONTACT]
    dissipated_medium = energy[K.E_DISSIPATED_MEDIUM]
    numerical = initial + external - sum(stored.values()) - dissipated_contact - dissipated_medium
    budget = initial + max(external, 0.0)
    excess = trackers[K.T_ENERGY_EXCESS] / budget if budget > 0 else 0.0

    return {
        "name": case.name,
        "model": numerics.model,
        "scheme": numerics.scheme,
        "numerics": numerics.as_dict(),
        "co_impact_time": _number(trackers[K.T_CO_IMPACT]),
        "contacts": intervals,
        "contacts_total": count + (1 if trackers[K.T_IN_CONTACT] else 0),
        "peak_contact_force": {"value": float(trackers[K.T_PEAK_FORCE]),
                               "time": float(trackers[K.T_PEAK_FORCE_TIME])},
        "max_compressive_stress": {"value": float(trackers[K.T_MAX_COMPRESSION]),
                                   "x": float(trackers[K.T_MAX_COMPRESSION_X]),
                                   "time": float(trackers[K.T_MAX_COMPRESSION_TIME])},
        "max_tensile_stress": {"value": float(trackers[K.T_MAX_TENSION]),
                               "x": float(trackers[K.T_MAX_TENSION_X]),
                               "time": float(trackers[K.T_MAX_TENSION_TIME])},
        "striker_rebound_velocity": _number(trackers[K.T_REBOUND_VELOCITY]),
        "energy": {
            "initial": initial,
            "external_work": float(external),
            "to_medium": float(stored["medium_potential"] + dissipated_medium),
            "dissipated_contact": float(dissipated_contact),
            "dissipated_medium": float(dissipated_medium),
            "numerical": float(numerical),
            **{k: float(v) for k, v in stored.items()},
            "max_excess_fraction": float(excess),
        },
        "force_history": _downsample(history),
        "warnings": (_warnings(case, numerics, trackers, excess)
                     + list(extra_warnings or [])),
    }
