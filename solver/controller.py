"""Runs a case: the kernel in chunks of steps, with progress, cancellation, probes and sampling.

Between chunks the controller reports progress and checks for cancellation; each chunk's kept
layers go to a `Recorder`. Memory is O(N) for the state plus what the outputs ask for.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from . import kernel as K
from .case import Case
from .grid import Grid, ResolvedNumerics, make_grid, resolve_numerics
from .summary import build_summary

MAX_CONTACTS = 10_000  # contact intervals kept for the summary; more are counted
CHUNK_NODE_STEPS = 2_000_000  # work between two progress reports (about 10 ms)

ProgressCallback = Callable[[float], None]
CancelCheck = Callable[[], bool]

# History columns as stored under their HDF5 paths.
HISTORY_PATHS = {
    "time": K.H_TIME,
    "striker/displacement": K.H_STRIKER_DISP,
    "striker/velocity": K.H_STRIKER_VEL,
    "tool/struck_end_displacement": K.H_STRUCK_END,
    "tool/working_end_displacement": K.H_WORKING_END,
    "contact/force": K.H_CONTACT_FORCE,
    "contact/overlap": K.H_OVERLAP,
    "medium/force": K.H_MEDIUM_FORCE,
    "external/force": K.H_EXTERNAL_FORCE,
    "energy/external_work": K.H_EXTERNAL_WORK,
    "energy/dissipated_contact": K.H_DISSIPATED_CONTACT,
    "energy/dissipated_medium": K.H_DISSIPATED_MEDIUM,
    "energy/striker_kinetic": K.H_STRIKER_KINETIC,
    "energy/tool_kinetic": K.H_TOOL_KINETIC,
    "energy/tool_strain": K.H_TOOL_STRAIN,
    "energy/contact_potential": K.H_CONTACT_POTENTIAL,
    "energy/medium_potential": K.H_MEDIUM_POTENTIAL,
}


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


@dataclass
class Fields:
    """Displacement and stress along the tool at the sampled times."""

    x: np.ndarray
    time: np.ndarray
    displacement: np.ndarray  # (samples, N + 1)
    stress: np.ndarray  # (samples, N + 1)


@dataclass
class Result:
    """A finished run: the case, the numerics used, histories, probes, fields, summary."""

    case: Case
    numerics: ResolvedNumerics
    history: dict[str, np.ndarray]
    probe_x: np.ndarray
    probe_stress: np.ndarray  # (samples, probes)
    fields: Fields | None
    summary: dict


@dataclass
class Recorder:
    """Keeps the sampled history, probe and field blocks of each chunk."""

    history: list[np.ndarray] = field(default_factory=list)
    probes: list[np.ndarray] = field(default_factory=list)
    field_time: list[np.ndarray] = field(default_factory=list)
    field_u: list[np.ndarray] = field(default_factory=list)
    field_stress: list[np.ndarray] = field(default_factory=list)

    def add(self, history, probes, field_time, field_u, field_stress) -> None:
        if len(history):
            self.history.append(history.copy())
            self.probes.append(probes.copy())
        if len(field_u):
            self.field_time.append(field_time.copy())
            self.field_u.append(field_u.copy())
            self.field_stress.append(field_stress.copy())


def _kept(first: int, last: int, stride: int) -> int:
    """How many layers in [first, last] are multiples of `stride`."""
    return last // stride - (first - 1) // stride if stride > 0 else 0


def _probe_nodes(grid: Grid, probes: list[float]) -> tuple[np.ndarray, np.ndarray]:
    """Each probe as the node left of it and the linear weight of the node to its right."""
    s = np.asarray(probes, dtype=float) / grid.h
    node = np.minimum(np.floor(s).astype(np.int64), grid.cells)
    weight = np.where(node >= grid.cells, 0.0, s - node)
    return node, weight


def _force_parameters(case: Case) -> tuple[int, float, float, float, float]:
    f = case.force
    if f is None:
        return K.FORCE_NONE, 0.0, 0.0, 0.0, 0.0
    if f.kind == "pulse":
        return K.FORCE_PULSE, f.amplitude, 0.0, f.start, f.duration
    kind = K.FORCE_SINE if f.kind == "sine" else K.FORCE_ABS_SINE
    return kind, f.amplitude, f.omega, 0.0, 0.0


def simulate_rod(
    case: Case,
    numerics: ResolvedNumerics | None = None,
    progress: ProgressCallback | None = None,
    cancelled: CancelCheck | None = None,
) -> Result:
    """Solve the case with the tool as an elastic rod (the paper's scheme (8)–(13))."""
    num = numerics or resolve_numerics(case, model="rod")
    scheme = num.weights()
    grid = make_grid(case.tool, num.cells, scheme.end_masses)
    n, tau, h = grid.cells, num.time_step, grid.h
    tool = case.tool
    r = (tool.youngs_modulus / tool.density) * tau * tau / (h * h)
    c2 = case.medium.stiffness if case.medium else 0.0
    b2 = case.medium.damping if case.medium else 0.0
    end_stiffness = (grid.end_area[0] * tool.youngs_modulus / h,
                     grid.end_area[1] * tool.youngs_modulus / h)
    p, inv_den, carry = K.factor_tool_rows(
        grid.lower, grid.upper, grid.node_area, end_stiffness[1], c2, b2, r, tau, tool.density, h,
        scheme.weight_new, scheme.centered, scheme.end_masses)

    out = case.outputs
    probe_node, probe_weight = _probe_nodes(grid, out.probes)
    field_stride = out.field_stride if out.fields else 0
    u = np.zeros((3, n + 1))
    y = np.zeros(3)
    trackers = K.new_trackers()
    energy = np.zeros(K.ENERGY_SLOTS)
    contacts = np.zeros((MAX_CONTACTS, 2))
    recorder = Recorder()

    chunk = max(1, CHUNK_NODE_STEPS // (n + 1))
    first = 0
    while first <= num.steps:
        last = min(num.steps, first + chunk - 1)
        rows = _kept(first, last, out.history_stride)
        frames = _kept(first, last, field_stride)
        history = np.empty((rows, K.HISTORY_COLUMNS))
        probes = np.empty((rows, len(probe_node)))
        field_u = np.empty((frames, n + 1))
        field_stress = np.empty((frames, n + 1))
        status, n_hist, n_field = K.advance(
            first, last, u, y, grid.lower, grid.upper, grid.node_area, grid.area_mid,
            grid.uniform, p, inv_den, carry,
            h, tau, r, tool.youngs_modulus, tool.density, *end_stiffness,
            grid.area[0], grid.area[-1],
            scheme.weight_new, scheme.weight_old, scheme.centered, scheme.end_masses,
            case.striker.mass, case.striker.velocity,
            case.contact.stiffness, case.contact.exponent, case.contact.tension_stiffness,
            case.contact.damping, c2, b2, *_force_parameters(case),
            trackers, energy, contacts,
            history, out.history_stride, probe_node, probe_weight, probes,
            field_u, field_stress, field_stride,
        )
        if status == K.STATUS_NON_FINITE:
            raise NumericalFailure(trackers[K.T_FAILED_TIME], num)
        field_time = (np.arange(-(-first // field_stride) * field_stride, last + 1, field_stride)
                      * tau if field_stride else np.empty(0))
        recorder.add(history[:n_hist], probes[:n_hist], field_time, field_u[:n_field],
                     field_stress[:n_field])
        first = last + 1
        if progress is not None:
            progress(min(1.0, first / (num.steps + 1)))
        if cancelled is not None and first <= num.steps and cancelled():
            raise Cancelled(f"cancelled at t = {first * tau:.6g} s")

    table = np.concatenate(recorder.history) if recorder.history else np.empty((0, K.HISTORY_COLUMNS))
    history = {path: table[:, col].copy() for path, col in HISTORY_PATHS.items()}
    probe_stress = (np.concatenate(recorder.probes) if recorder.probes
                    else np.empty((0, len(probe_node))))
    fields = None
    if out.fields:
        fields = Fields(
            x=grid.x.copy(),
            time=np.concatenate(recorder.field_time),
            displacement=np.concatenate(recorder.field_u),
            stress=np.concatenate(recorder.field_stress),
        )
    summary = build_summary(
        case=case, numerics=num, trackers=trackers, contacts=contacts, energy=energy,
        history=history,
    )
    return Result(case=case, numerics=num, history=history, probe_x=np.asarray(out.probes, float),
                  probe_stress=probe_stress, fields=fields, summary=summary)


def warm_up() -> None:
    """Compile the kernel into Numba's on-disk cache (a no-op when it is there already)."""
    from .case import parse_case

    simulate_rod(parse_case({
        "striker": {"mass": 1.0, "velocity": 1.0},
        "tool": {"length": 1.0, "youngs_modulus": 1e9, "density": 1e3, "area": 1e-3},
        "contact": {"stiffness": 1e8, "exponent": 0.5},
        "force": {"kind": "pulse", "amplitude": 1.0, "duration": 1e-5},
        "numerics": {"duration": 1e-4, "cells": 4},
        "outputs": {"probes": [0.5], "fields": True},
    }))
