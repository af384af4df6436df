"""What a pile's head record says by itself, before any model: the waves going down and up, the
Case method's capacity, and whether force and velocity are proportional at impact.

A record is the axial force F (compression positive) and the particle velocity v (toward the toe
positive) at gauges near the head, on a pile of impedance Z = E·A/c and length L below them. The
wave going down is W↓ = (F + Z·v)/2, the one coming up W↑ = (F − Z·v)/2; before the first
reflection returns (2L/c after impact) the record holds F = Z·v, and W↑ stays 0 but for what the
shaft sends up.

The Case method (Goble, Likins and Rausche, 1975) reads the soil's total resistance from the head,
a wave's passage apart: R_T(t₁) = W↓(t₁) + W↑(t₂), t₂ = t₁ + 2L/c, exact for a uniform elastic pile
whose soil acts at the toe. Its static part subtracts the damping the toe's velocity at t₁ + L/c
makes, J_c·Z·v_toe with Z·v_toe = 2·W↓(t₁) − R_T: R_S = R_T − J_c·(2·W↓(t₁) − R_T), J_c the
dimensionless Case damping factor. `case_method` gives RMX, the largest R_S as t₁ moves over the
2L/c after the first velocity peak (which a toe that yields late needs).
"""

from __future__ import annotations

import numpy as np

CASE_DAMPING = (0.2, 0.3, 0.4, 0.5, 0.6, 0.7)  # J_c, from sands to clays, as the method's users pick them


def waves(force: np.ndarray, velocity: np.ndarray, impedance: float) -> tuple[np.ndarray, np.ndarray]:
    """`(W↓, W↑)` = ((F + Z·v)/2, (F − Z·v)/2): the waves going down and coming up."""
    return 0.5 * (force + impedance * velocity), 0.5 * (force - impedance * velocity)


def case_method(
    time: np.ndarray,
    force: np.ndarray,
    velocity: np.ndarray,
    impedance: float,
    travel: float,
    damping: tuple[float, ...] = CASE_DAMPING,
) -> list[dict]:
    """RMX for each Case damping factor J_c of `damping`: the largest static resistance R_S(t₁) for
    t₁ from the first velocity peak over `travel` (2L/c, s) more, with t₂ = t₁ + travel (the record
    read linearly between its samples). One `{"damping_factor", "capacity" (N), "time" (t₁, s)}`
    each."""
    down, up = waves(np.asarray(force, float), np.asarray(velocity, float), impedance)
    peak = time[int(np.argmax(velocity))]
    t1 = time[(time >= peak) & (time <= peak + travel) & (time + travel <= time[-1])]
    if t1.size == 0:
        raise ValueError("the record ends before 2L/c after its velocity peak: the Case method needs it")
    going_down = np.interp(t1, time, down)
    total = going_down + np.interp(t1 + travel, time, up)
    rows = []
    for j in damping:
        static = total - j * (2.0 * going_down - total)
        k = int(np.argmax(static))
        rows.append({"damping_factor": j, "capacity": float(static[k]), "time": float(t1[k])})
    return rows


def proportionality(time: np.ndarray, force: np.ndarray, velocity: np.ndarray, impedance: float) -> float:
    """F/(Z·v) at the first velocity peak: 1 on a record whose gauge, area and wave speed agree
    with the pile's impedance (before any reflection returns)."""
    k = int(np.argmax(velocity))
    return float(force[k] / (impedance * velocity[k]))
