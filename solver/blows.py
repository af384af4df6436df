"""Blow after blow: what each blow saw, and the whole run's extremes made from them.

The kernel observes one blow at a time (`kernel.Observed`); between two blows the controller
launches the striker again (`kernel.start_blow`). `BlowLog` keeps each blow's extremes, its contact
intervals and its energy at its start and end: the summary's `blows` table, and the run's own
extremes (the largest of the blows', the first blow's co-impact time and rebound).
"""

from __future__ import annotations

import numpy as np

from . import layout as L
from .summary import to_medium

# Each extreme with the slots that go with it (where, when)
_LARGEST = (
    L.X_PEAK_FORCE,
    L.X_MAX_COMPRESSION,
    L.X_MAX_TENSION,
    L.X_MAX_PENETRATION,
    L.X_ENERGY_EXCESS,
    L.X_MAX_TRANSFERRED,
)
_WITH = {
    L.X_PEAK_FORCE: (L.X_PEAK_FORCE_TIME,),
    L.X_MAX_COMPRESSION: (L.X_MAX_COMPRESSION_X, L.X_MAX_COMPRESSION_TIME),
    L.X_MAX_TENSION: (L.X_MAX_TENSION_X, L.X_MAX_TENSION_TIME),
}
# The peaks a summary reports with their time (the last of their `_WITH` slots), by name
_PEAKS = {
    "peak_contact_force": L.X_PEAK_FORCE,
    "max_compressive_stress": L.X_MAX_COMPRESSION,
    "max_tensile_stress": L.X_MAX_TENSION,
}


class BlowLog:
    """Each blow's observations, in order (`start` one, `finish` it)."""

    def __init__(self, launch_energy: float, set_at_rest: float = 0.0):
        self.blows: list[dict] = []
        self._start: np.ndarray | None = None
        self._launched = launch_energy  # the blow under way's striker (and anvil) energy
        self._set = set_at_rest  # the medium's permanent penetration before the first blow

    def start(self, energy: np.ndarray) -> None:
        """A blow starts with the energy terms `energy` (after its striker's launch): its striker's
        energy is the first launch's, or what `E_LAUNCHED` gained since the blow before (a hammer
        at work's drive strikes at a velocity of its own each blow)."""
        if self._start is not None:
            self._launched = energy[L.E_LAUNCHED] - self._start[L.E_LAUNCHED]
        self._start = energy.copy()

    def finish(self, energy: np.ndarray, observed) -> None:
        """The blow ends with `energy`, having observed `observed` (its extremes and contacts,
        and the medium's permanent penetration where its duration ends)."""
        x = observed.extremes
        permanent_penetration = float(x[L.X_SET])
        medium = to_medium(energy) - to_medium(self._start)
        supplied = self._launched + energy[L.E_EXTERNAL_WORK] - self._start[L.E_EXTERNAL_WORK]
        count = int(x[L.X_CONTACTS])
        self.blows.append(
            {
                "row": {
                    "peak_contact_force": float(x[L.X_PEAK_FORCE]),
                    "max_compressive_stress": float(x[L.X_MAX_COMPRESSION]),
                    "to_medium": medium,
                    "transfer_efficiency": float(medium / supplied) if supplied > 0 else 0.0,
                    "permanent_penetration": permanent_penetration,
                    "set": self.set_of(permanent_penetration),
                    "transferred": float(x[L.X_MAX_TRANSFERRED]),
                },
                "extremes": x.copy(),
                "envelope": observed.envelope.copy(),
                "contacts": observed.contacts[: min(count, len(observed.contacts))].copy(),
            }
        )
        self._set = permanent_penetration

    def set_of(self, permanent_penetration: float) -> float:
        """The set of the blow under way, the medium's permanent penetration now `permanent_penetration`."""
        return float(permanent_penetration - self._set)

    def table(self) -> list[dict]:
        return [blow["row"] for blow in self.blows]

    def extremes(self) -> np.ndarray:
        """The whole run's extremes: the largest of the blows' (with where and when), the first
        blow's co-impact time and rebound, every contact counted."""
        run = L.new_extremes()
        for blow in self.blows:
            x = blow["extremes"]
            for slot in _LARGEST:
                if x[slot] > run[slot]:
                    run[slot] = x[slot]
                    for other in _WITH.get(slot, ()):
                        run[other] = x[other]
            run[L.X_CONTACTS] += x[L.X_CONTACTS]
            run[L.X_MIN_CONTACT_STEPS] = min(run[L.X_MIN_CONTACT_STEPS], x[L.X_MIN_CONTACT_STEPS])
        first = self.blows[0]["extremes"]
        for slot in (L.X_CO_IMPACT, L.X_REBOUND_VELOCITY, L.X_FADE_TIME):
            run[slot] = first[slot]
        return run

    def envelope(self) -> np.ndarray:
        """The whole run's stress envelope (`kernel.Observed`): each stretch's greatest of the blows'."""
        return np.max([blow["envelope"] for blow in self.blows], axis=0)

    def still_rising(self, run: np.ndarray, blow_ends: np.ndarray, time_step: float) -> list[str]:
        """Warnings for the run's peaks (`run`, its `extremes`) reached where their blow's duration
        ends (blow k's at `blow_ends[k]`, s, the kernel's time): still rising then, each is the
        value there, not a peak. A last layer can fall a rounding short of the duration's end
        (a duration of whole steps), so the end is taken to a millionth of a `time_step`."""
        found = []
        for name, slot in _PEAKS.items():
            if not run[slot] > 0.0:
                continue
            time_slot = _WITH[slot][-1]
            k, blow = next((k, b["extremes"]) for k, b in enumerate(self.blows) if b["extremes"][slot] == run[slot])
            if blow[time_slot] >= blow_ends[k] - 1e-6 * time_step:
                which = f"blow {k + 1}'s" if len(self.blows) > 1 else "the run's"
                found.append(
                    f"{name} is reached at the end of {which} duration (t = {blow[time_slot]:.4g} s): still "
                    "rising then, it is the value there, not a peak; lengthen numerics.duration to see its peak"
                )
        return found

    def contacts(self) -> np.ndarray:
        return np.concatenate([blow["contacts"] for blow in self.blows]).reshape(-1, 2)
