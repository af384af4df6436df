"""Synthetic head records of a pile for signal matching's tests and validation: the pile driven at
its head by a hammer's force pulse on a fine grid, its head's force and velocity sampled as a
pile driving analyser does, with noise added."""

from __future__ import annotations

import numpy as np

from percussim.solver.case import parse_case
from percussim.solver.controller import simulate_rod
from percussim.solver.grid import explicit_numerics

STEEL_PIPE = {"length": 10.0, "youngs_modulus": 2.1e11, "density": 7850.0, "area": 0.01}
SHAFT = [{"from": 3.0, "to": 10.0, "ultimate_resistance": 4e5, "quake": 2.5e-3, "damping_factor": 0.2}]
TOE = {"kind": "smith", "ultimate_resistance": 4e5, "quake": 2.5e-3, "damping_factor": 0.5}
BLOW = 4e-3  # s: the hammer's half-sine force pulse
PEAK_FORCE = 2.0e6  # N


def pile(**changes) -> dict:
    """The test pile (`STEEL_PIPE`, sand along its lower 7 m and at its toe) without its drive;
    `changes` replace its fields."""
    return {"tool": STEEL_PIPE, "shaft": SHAFT, "medium": TOE, "numerics": {"duration": 0.012}} | changes


def head_record(
    truth: dict, cells: int = 2000, rate: float = 2e4, noise: float = 0.02, seed: int = 1, peak: float = PEAK_FORCE
) -> dict:
    """The record (JSON: x, time, force, velocity) of the pile `truth` (a `pile`) struck at its
    head by a half-sine force of `peak` over `BLOW`: solved on `cells` cells (the explicit scheme
    at Courant number 1), sampled at `rate` (Hz) over its `numerics.duration`, each of force and
    velocity with Gaussian noise of `noise` × its peak (`seed`)."""
    t = np.linspace(0.0, BLOW, 81)
    case = parse_case(
        truth | {"struck_end": {"force": {"time": t.tolist(), "values": (peak * np.sin(np.pi * t / BLOW)).tolist()}}}
    )
    h = simulate_rod(case, numerics=explicit_numerics(case, cells)).history
    velocity = np.gradient(h["tool/struck_end_displacement"], h["time"])
    samples = np.arange(0.0, case.numerics.duration, 1.0 / rate)
    clean = {
        "x": 0.0,
        "time": samples.tolist(),
        "force": np.interp(samples, h["time"], h["contact/force"]).tolist(),
        "velocity": np.interp(samples, h["time"], velocity).tolist(),
    }
    return with_noise(clean, noise, noise, seed)


def with_noise(record: dict, force_noise: float, velocity_noise: float, seed: int) -> dict:
    """`record` with Gaussian noise of `force_noise` × the force's peak on its force and
    `velocity_noise` × the velocity's peak on its velocity (`seed`)."""
    rng = np.random.default_rng(seed)
    noisy = dict(record)
    for name, share in (("force", force_noise), ("velocity", velocity_noise)):
        values = np.asarray(record[name])
        noisy[name] = (values + share * np.max(np.abs(values)) * rng.standard_normal(values.size)).tolist()
    return noisy
