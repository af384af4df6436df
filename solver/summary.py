"""The pulse summary: its response model (`Summary`, every field with its unit), and the one place
it is assembled: `build_summary` from what a run observed, `add_accuracy` from what its error
estimate says. Built as a plain dict (a sweep builds thousands a second); `Summary` validates it
wherever it is served or tested."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field

from . import layout as L
from .case import Case
from .grid import ResolvedNumerics, striker_mass

if TYPE_CHECKING:
    from .accuracy import Accuracy

MAX_CONTACTS = 10_000  # contact intervals kept for the summary; more are counted
FORCE_HISTORY_POINTS = 2000
# The summary's force history: its keys and the history paths they come from
FORCE_HISTORY = {"time": "time", "contact": "contact/force", "medium": "medium/force"}


class _Part(BaseModel):
    model_config = ConfigDict(extra="forbid")


class Contact(_Part):
    start: float = Field(description="s")
    end: float | None = Field(description="s; null while the contact lasts where the run's duration ends")


class PeakForce(_Part):
    value: float = Field(description="N")
    time: float = Field(description="s")


class PeakStress(_Part):
    value: float = Field(description="Pa, as a magnitude")
    x: float = Field(description="m from the struck end")
    time: float = Field(description="s")


class StressEnvelope(_Part):
    """The greatest stresses in each stretch of the tool: where along it the loads are, and what
    the error estimate of the largest stresses reads stretch by stretch."""

    x: list[float] = Field(description="the stretches' bounds, m from the struck end (equal stretches)")
    compression: list[float | None] = Field(
        description="each stretch's greatest compression, Pa, as a magnitude (negative: no compression there); "
        "null where the grid has no node"
    )
    tension: list[float | None] = Field(
        description="each stretch's greatest tension, Pa (negative: no tension there); null where the grid has no node"
    )


class Energy(_Part):
    initial: float = Field(description="the striker's (and an anvil's) kinetic energy at impact (every blow's), J")
    external_work: float = Field(description="work of the external force, J")
    to_medium: float = Field(description="net work on the medium: stored, dissipated and plastic, J")
    to_shaft: float = Field(description="net work on the soil along the tool's side: stored, slipped and damped, J")
    transferred: float = Field(
        description="the largest work done on the tool through its struck end, ∫F·v dt (a pile driving analyser's "
        "EMX), J; with blows, the largest blow's"
    )
    transfer_efficiency: float = Field(description="to_medium and to_shaft over the energy supplied, 1")
    dissipated_contact: float = Field(description="by the contact's damper b1 (and the anvil's contact's), J")
    dissipated_medium: float = Field(description="by the medium's damper b2, J")
    gravity_work: float = Field(description="work of the weights (under gravity) since impact, J")
    stored_at_rest: float = Field(
        description="what the tool, the medium and the anvil's contact stored at rest under gravity before impact, J"
    )
    numerical: float = Field(
        description="lost by the scheme (supplied − stored − dissipated − withdrawn − dissipated between blows), J"
    )
    striker_withdrawn: float = Field(
        description="what the striker still had when each blow ended and the next began, J"
    )
    dissipated_between_blows: float = Field(
        description="a hammer at work's: what the tool's leftover waves (and the medium's and the contacts' "
        "springs) held when each blow ended and the tool came to rest on the medium, J"
    )
    striker_kinetic: float = Field(description="J, at the end of the run")
    striker_strain: float = Field(description="an elastic striker's, J, at the end of the run")
    anvil_kinetic: float = Field(description="J, at the end of the run")
    tool_kinetic: float = Field(description="J, at the end of the run")
    tool_strain: float = Field(description="J, at the end of the run")
    contact_potential: float = Field(description="Φ(δ) (and the anvil's contact's), J, at the end of the run")
    medium_potential: float = Field(description="what the medium would give back unloading, J, at the end of the run")
    medium_plastic: float = Field(description="the medium's work into permanent penetration, J")
    max_excess_fraction: float = Field(
        description="largest energy created over the energy supplied, 1 (0 for a stable scheme)"
    )


class Penetration(_Part):
    max: float = Field(description="the working end's deepest penetration into the medium, m")
    permanent: float = Field(description="what remains when the medium is unloaded, m (0 for a linear medium)")


class Blow(_Part):
    peak_contact_force: float = Field(description="N")
    max_compressive_stress: float = Field(description="Pa, as a magnitude")
    to_medium: float = Field(description="net work on the medium during the blow, J")
    transfer_efficiency: float = Field(description="to_medium over the blow's striker energy and external work, 1")
    permanent_penetration: float = Field(description="the medium's, at the blow's end, m")
    set: float = Field(description="the permanent penetration this blow added, m")
    transferred: float = Field(description="the blow's largest work through the tool's struck end (EMX), J")


class ForceHistory(_Part):
    time: list[float] = Field(description=f"s; at most {FORCE_HISTORY_POINTS} points spread over the run")
    contact: list[float] = Field(description="contact force, N")
    medium: list[float] = Field(description="medium force, N")


class RunGrid(_Part):
    model: str
    scheme: str
    cells: int
    time_step: float = Field(description="s")
    steps: int


class Cycle(_Part):
    """A hammer at work (`cycles`): its blows' impact velocities and strokes, its cycles' times,
    and over the last half of the cycles its means."""

    impact_velocity: list[float] = Field(description="each blow's, m/s")
    stroke: list[float] = Field(description="the stroke before each blow, m")
    cycle_time: list[float] = Field(description="each cycle's (a blow and its flight), s")
    impact_energy: float = Field(description="½·m·v² at impact, J")
    frequency: float | None = Field(description="blows per second, Hz; null with one cycle")
    impact_power: float | None = Field(description="impact energy × frequency, W")
    hydraulic_power: float | None = Field(
        description="the supply's work on the chambers a cycle (or the pump's p·Q) × frequency, W"
    )
    efficiency: float | None = Field(description="the energy to the medium over the hydraulic energy, 1")
    penetration_rate: float | None = Field(description="the set a blow × frequency, m/s")
    periodic: bool = Field(description="whether the last two blows struck at the same velocity, within the tolerance")


class Summary(_Part):
    """The pulse summary of a run (`GET /v1/jobs/{id}/summary`, `Result.summary`)."""

    name: str | None = Field(description="the case's name")
    model: Literal["rod", "lumped"]
    scheme: str
    numerics: ResolvedNumerics
    co_impact_time: float | None = Field(description="end of the first contact, s; null if it never ends")
    contact_fade_time: float | None = Field(
        description="where the first contact ended, how long its overlap took to cross the rounding of the "
        "displacements, s: next to nothing where the faces part, a slow link's relaxation time where the contact "
        "fades out (its end is then set by rounding, and co_impact_time is not estimated); null if it never ends"
    )
    contacts: list[Contact] = Field(description=f"the contact intervals (the first {MAX_CONTACTS})")
    contacts_total: int = Field(description="how many contacts, counting those not listed")
    peak_contact_force: PeakForce
    max_compressive_stress: PeakStress
    max_tensile_stress: PeakStress
    striker_rebound_velocity: float | None = Field(
        description="the striker's velocity when the first contact ends, m/s (negative: away from the tool)"
    )
    stress_envelope: StressEnvelope | None = Field(description="null for the lumped model, which has no stress")
    medium_penetration: Penetration | None = Field(description="null without a medium")
    set: float | None = Field(
        description="the working end's permanent penetration in the last blow, m; null for a medium that does not yield"
    )
    blow_count: float | None = Field(
        description="1/set, blows per metre; null where the medium does not yield, or at refusal (set ≤ 0)"
    )
    energy: Energy
    force_history: ForceHistory
    blows: list[Blow] | None = Field(description="one entry per blow; null when the case has no `blows` or `cycles`")
    cycle: Cycle | None = Field(description="a hammer at work's (`cycles`); null otherwise")
    warnings: list[str] = Field(description="what the answer cannot promise, in words")
    why: str = Field(description="why this model, scheme and grid")
    tolerance: float | None = Field(description="the relative accuracy asked, 1; null for a fixed grid")
    error_estimate: dict[str, float | None] | None = Field(
        description="each estimated quantity's relative error, 1, and 'worst'; null when none could be made"
    )
    not_estimated: dict[str, str] = Field(description="quantity → why its error is not estimated")
    runs: list[RunGrid] = Field(description="the grids solved for this answer, coarse to fine")


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


def to_medium(energy: np.ndarray) -> float:
    """The net work on the medium so far (`energy` in the kernel's slots): stored, plastic and
    dissipated, less what it held at rest under gravity before the first blow."""
    return float(
        energy[L.E_MEDIUM_POTENTIAL]
        + energy[L.E_MEDIUM_PLASTIC]
        + energy[L.E_DISSIPATED_MEDIUM]
        - energy[L.E_MEDIUM_AT_REST]
    )


def launch_energy(case: Case) -> float:
    """What one launch brings (J): the striker's kinetic energy at impact, and an anvil's (none
    when a history drives the struck end: its work is the external work)."""
    if case.striker is None:
        return 0.0
    anvil = case.anvil
    return 0.5 * striker_mass(case.striker) * case.impact_velocity**2 + (
        0.5 * anvil.mass * anvil.velocity**2 if anvil else 0.0
    )


def refusal(last_set: float | None) -> list[str]:
    """The warning a blow that sets the working end no deeper calls for."""
    if last_set is None or last_set > 0.0:
        return []
    return [
        f"refusal: the last blow set the working end {last_set * 1e3:.3g} mm deeper (set ≤ 0), so blow_count "
        "is not defined: the blow does not overcome the medium's resistance"
    ]


def stress_envelope(case: Case, envelope: np.ndarray) -> dict:
    """The greatest compression and tension (Pa, each positive where it is of its kind) in each of
    the tool's `ENVELOPE_BINS` stretches of equal length, from the struck end: `x`, the stretches'
    bounds (m); null for a stretch the grid has no node in."""
    bins = envelope.shape[1]

    def values(row: np.ndarray) -> list[float | None]:
        return [v if math.isfinite(v) else None for v in row.tolist()]

    return {
        "x": [case.tool.length * k / bins for k in range(bins + 1)],
        "compression": values(envelope[0]),
        "tension": values(envelope[1]),
    }


def build_summary(
    case: Case,
    numerics: ResolvedNumerics,
    extremes: np.ndarray,
    contacts: np.ndarray,
    open_contact: float | None,
    energy: np.ndarray,
    history: dict[str, np.ndarray],
    extra_warnings: list[str] | None = None,
    permanent_penetration: float = 0.0,
    blows: list[dict] | None = None,
    set_at_rest: float = 0.0,
    envelope: np.ndarray | None = None,
) -> dict:
    """Assemble the summary; `extremes`, `contacts` and `energy` use the kernel's slot layout,
    `open_contact` is the start of a contact still open at the end (None if there is none),
    `history` needs the paths of FORCE_HISTORY only, `permanent_penetration` is the medium's
    at the end (`set_at_rest` before the first blow, under gravity) and `blows` each blow's row of
    the `blows` table (None: the case has no `blows`); `envelope` the kernel's stress envelope
    (`kernel.Observed`; None: the model keeps none).

    `extra_warnings` are the caller's own (e.g. outputs a model cannot provide); the estimate's
    follow (`add_accuracy`).
    """
    count = int(extremes[L.X_CONTACTS])
    intervals = [{"start": s, "end": e} for s, e in contacts[: min(count, len(contacts))].tolist()]
    if open_contact is not None:
        intervals.append({"start": float(open_contact), "end": None})

    initial = launch_energy(case) + energy[L.E_LAUNCHED]
    at_end = {
        "striker_kinetic": energy[L.E_STRIKER_KINETIC],
        "striker_strain": energy[L.E_STRIKER_STRAIN],
        "anvil_kinetic": energy[L.E_ANVIL_KINETIC],
        "tool_kinetic": energy[L.E_TOOL_KINETIC],
        "tool_strain": energy[L.E_TOOL_STRAIN],
        "contact_potential": energy[L.E_CONTACT_POTENTIAL],
        "medium_potential": energy[L.E_MEDIUM_POTENTIAL],
        "medium_plastic": energy[L.E_MEDIUM_PLASTIC],
    }
    external = energy[L.E_EXTERNAL_WORK]
    dissipated_contact = energy[L.E_DISSIPATED_CONTACT]
    dissipated_medium = energy[L.E_DISSIPATED_MEDIUM]
    withdrawn = energy[L.E_WITHDRAWN]
    between_blows = energy[L.E_BETWEEN_BLOWS]
    shaft = energy[L.E_TO_SHAFT]
    gravity_work, at_rest = energy[L.E_GRAVITY_WORK], energy[L.E_STORED_AT_REST]
    numerical = (
        initial
        + external
        + gravity_work
        + at_rest
        - sum(at_end.values())
        - dissipated_contact
        - dissipated_medium
        - withdrawn
        - between_blows
        - shaft
    )
    budget = initial + max(external, 0.0)
    excess = extremes[L.X_ENERGY_EXCESS] / budget if budget > 0 else 0.0
    medium = to_medium(energy)
    supplied = initial + external
    last_set = (
        (blows[-1]["set"] if blows else float(permanent_penetration - set_at_rest)) if case.medium_yields else None
    )

    return {
        "name": case.name,
        "model": numerics.model,
        "scheme": numerics.scheme,
        "numerics": numerics.as_dict(),
        "co_impact_time": _number(extremes[L.X_CO_IMPACT]),
        "contact_fade_time": _number(extremes[L.X_FADE_TIME]),
        "contacts": intervals,
        "contacts_total": count + (0 if open_contact is None else 1),
        "peak_contact_force": {"value": float(extremes[L.X_PEAK_FORCE]), "time": float(extremes[L.X_PEAK_FORCE_TIME])},
        "max_compressive_stress": {
            "value": float(extremes[L.X_MAX_COMPRESSION]),
            "x": float(extremes[L.X_MAX_COMPRESSION_X]),
            "time": float(extremes[L.X_MAX_COMPRESSION_TIME]),
        },
        "max_tensile_stress": {
            "value": float(extremes[L.X_MAX_TENSION]),
            "x": float(extremes[L.X_MAX_TENSION_X]),
            "time": float(extremes[L.X_MAX_TENSION_TIME]),
        },
        "striker_rebound_velocity": _number(extremes[L.X_REBOUND_VELOCITY]),
        "stress_envelope": None if envelope is None else stress_envelope(case, envelope),
        "medium_penetration": None
        if case.medium is None
        else {"max": float(extremes[L.X_MAX_PENETRATION]), "permanent": float(permanent_penetration)},
        "set": last_set,
        "blow_count": 1.0 / last_set if last_set is not None and last_set > 0.0 else None,
        "energy": {
            "initial": float(initial),
            "external_work": float(external),
            "to_medium": medium,
            "to_shaft": float(shaft),
            "transferred": float(extremes[L.X_MAX_TRANSFERRED]),
            "transfer_efficiency": float((medium + shaft) / supplied) if supplied > 0 else 0.0,
            "dissipated_contact": float(dissipated_contact),
            "dissipated_medium": float(dissipated_medium),
            "gravity_work": float(gravity_work),
            "stored_at_rest": float(at_rest),
            "numerical": float(numerical),
            "striker_withdrawn": float(withdrawn),
            "dissipated_between_blows": float(between_blows),
            **{k: float(v) for k, v in at_end.items()},
            "max_excess_fraction": float(excess),
        },
        "force_history": _downsample(history),
        "blows": blows,
        "cycle": None,  # a hammer at work's, its controller's to fill
        "warnings": list(extra_warnings or []) + refusal(last_set),
    }


def add_accuracy(summary: dict, accuracy: Accuracy) -> None:
    """Print into `summary` what the run says of its accuracy (`accuracy.assess`)."""
    summary.update(
        {
            "tolerance": accuracy.tolerance,
            "error_estimate": accuracy.error_estimate,
            "not_estimated": accuracy.not_estimated,
            "why": accuracy.why,
            "runs": [
                {"model": n.model, "scheme": n.scheme, "cells": n.cells, "time_step": n.time_step, "steps": n.steps}
                for n in accuracy.runs
            ],
        }
    )
    summary["warnings"].extend(accuracy.warnings)
