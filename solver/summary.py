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


def build_summary(case: Case, numerics: ResolvedNumerics, extremes: np.ndarray,
                  contacts: np.ndarray, open_contact: float | None, energy: np.ndarray,
                  history: dict[str, np.ndarray], extra_warnings: list[str] | None = None) -> dict:
    """Assemble the summary; `extremes`, `contacts` and `energy` use the kernel's slot layout,
    `open_contact` is the start of a contact still open at the end (None if there is none), and
    `history` needs the paths of FORCE_HISTORY only.

    `extra_warnings` are the caller's own (e.g. outputs a model cannot provide); the estimate's
    follow (`solver.adaptive.annotate`).
    """
    count = int(extremes[K.X_CONTACTS])
    intervals = [{"start": float(s), "end": float(e)} for s, e in contacts[:min(count, len(contacts))]]
    if open_contact is not None:
        intervals.append({"start": float(open_contact), "end": None})

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
    excess = extremes[K.X_ENERGY_EXCESS] / budget if budget > 0 else 0.0
    to_medium = float(stored["medium_potential"] + dissipated_medium)
    supplied = initial + external

    return {
        "name": case.name,
        "model": numerics.model,
        "scheme": numerics.scheme,
        "numerics": numerics.as_dict(),
        "co_impact_time": _number(extremes[K.X_CO_IMPACT]),
        "contacts": intervals,
        "contacts_total": count + (0 if open_contact is None else 1),
        "peak_contact_force": {"value": float(extremes[K.X_PEAK_FORCE]),
                               "time": float(extremes[K.X_PEAK_FORCE_TIME])},
        "max_compressive_stress": {"value": float(extremes[K.X_MAX_COMPRESSION]),
                                   "x": float(extremes[K.X_MAX_COMPRESSION_X]),
                                   "time": float(extremes[K.X_MAX_COMPRESSION_TIME])},
        "max_tensile_stress": {"value": float(extremes[K.X_MAX_TENSION]),
                               "x": float(extremes[K.X_MAX_TENSION_X]),
                               "time": float(extremes[K.X_MAX_TENSION_TIME])},
        "striker_rebound_velocity": _number(extremes[K.X_REBOUND_VELOCITY]),
        "energy": {
            "initial": initial,
            "external_work": float(external),
            "to_medium": to_medium,
            "transfer_efficiency": to_medium / supplied if supplied > 0 else 0.0,
            "dissipated_contact": float(dissipated_contact),
            "dissipated_medium": float(dissipated_medium),
            "numerical": float(numerical),
            **{k: float(v) for k, v in stored.items()},
            "max_excess_fraction": float(excess),
        },
        "force_history": _downsample(history),
        "warnings": list(extra_warnings or []),
    }
