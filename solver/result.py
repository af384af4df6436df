"""What a run gives (`Result`: histories, probes, fields, summary) and where its outputs go as it
runs (a `Recorder`: held in memory by `MemoryRecorder`, or streamed to HDF5 by
`io.ResultWriter`). Imports no Numba: reading a result needs no kernel."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from .case import Case
from .grid import ResolvedNumerics

ProgressCallback = Callable[[float], None]
CancelCheck = Callable[[], bool]
FIELD_NAMES = ("x", "time", "displacement", "stress")  # stored as fields/<name>
STRIKER_FIELD_NAMES = ("striker_x", "striker_displacement", "striker_stress")  # an elastic one's
SHAFT_FIELD_NAMES = ("shaft_resistance",)  # a shaft's


@dataclass
class Fields:
    """Displacement and stress along the tool at the sampled times, along an elastic striker (its x
    from its impact face; None for a lumped one), and the shaft's resistance along the tool (None
    without a shaft)."""

    x: np.ndarray
    time: np.ndarray
    displacement: np.ndarray  # (samples, N + 1)
    stress: np.ndarray  # (samples, N + 1)
    striker_x: np.ndarray | None = None
    striker_displacement: np.ndarray | None = None  # (samples, N_s + 1)
    striker_stress: np.ndarray | None = None  # (samples, N_s + 1)
    shaft_resistance: np.ndarray | None = None  # (samples, N + 1), N/m: the shaft's force per metre


@dataclass
class Result:
    """A finished run: the case, the numerics used, histories, probes, fields, summary.

    A run streamed to a file (`streamed`) carries its case, numerics, probe stations and summary
    only: `history` is empty, `probe_stress` has no rows and `fields` is None; the arrays are in
    the file (`solver.io.read_result`).
    """

    case: Case
    numerics: ResolvedNumerics
    history: dict[str, np.ndarray]
    probe_x: np.ndarray
    probe_stress: np.ndarray  # (samples, probes)
    fields: Fields | None
    summary: dict
    streamed: bool = False
    summary_json: str | None = field(default=None, repr=False)  # as written to a result file

    @classmethod
    def from_arrays(
        cls, case: Case, numerics: ResolvedNumerics, arrays: dict[str, np.ndarray], summary: dict
    ) -> Result:
        """The result from its arrays under their HDF5 names; all but probes and fields are history."""
        history = dict(arrays)
        fields = (
            Fields(
                *(history.pop(f"fields/{k}") for k in FIELD_NAMES),
                *(history.pop(f"fields/{k}", None) for k in STRIKER_FIELD_NAMES + SHAFT_FIELD_NAMES),
            )
            if "fields/x" in history
            else None
        )
        probe_x, probe_stress = history.pop("probes/x"), history.pop("probes/stress")
        return cls(
            case=case,
            numerics=numerics,
            history=history,
            probe_x=probe_x,
            probe_stress=probe_stress,
            fields=fields,
            summary=summary,
        )

    def arrays(self) -> dict[str, np.ndarray]:
        """The arrays under their HDF5 names (the inverse of `from_arrays`)."""
        arrays = {**self.history, "probes/x": self.probe_x, "probes/stress": self.probe_stress}
        if self.fields is not None:
            arrays.update(
                {
                    f"fields/{k}": getattr(self.fields, k)
                    for k in FIELD_NAMES + STRIKER_FIELD_NAMES + SHAFT_FIELD_NAMES
                    if getattr(self.fields, k) is not None
                }
            )
        return arrays


class Recorder(Protocol):
    """Where a run's outputs go, under their HDF5 names.

    `start` begins a run (anything recorded before is dropped), `create` makes a dataset at its
    final shape, and `append` fills it with its next rows.
    """

    def start(self) -> None: ...

    def create(self, name: str, shape: tuple[int, ...], dtype: np.dtype = np.dtype(float)) -> None: ...

    def append(self, name: str, rows: np.ndarray) -> None: ...

    def held(self) -> dict[str, np.ndarray] | None:
        """The datasets when held in memory; None when they went elsewhere."""


class MemoryRecorder:
    """Holds every dataset in memory, allocated at its final shape."""

    def __init__(self) -> None:
        self.start()

    def start(self) -> None:
        self.arrays: dict[str, np.ndarray] = {}
        self.filled: dict[str, int] = {}

    def create(self, name: str, shape: tuple[int, ...], dtype: np.dtype = np.dtype(float)) -> None:
        self.arrays[name] = np.empty(shape, dtype)
        self.filled[name] = 0

    def append(self, name: str, rows: np.ndarray) -> None:
        first = self.filled[name]
        self.arrays[name][first : first + len(rows)] = rows
        self.filled[name] = first + len(rows)

    def held(self) -> dict[str, np.ndarray]:
        return self.arrays
