"""Smith's lumped-mass pile (E. A. L. Smith, 1960): an independent discretisation to hold the
solver's piles to.

The pile is cut into M segments, each a mass `ρ·S·Δx` at its middle, joined by springs `E·S/Δx`;
the ram strikes the first through a cushion (linear, `k`, unloading at `k/e²` from its deepest
compression as a cushion of restitution e does, and not pulling); each mass carries its share of
the shaft's soil, the last the toe's. The soil is Smith's, as the solver states it: on the shaft
`F = F_s + J·|F_s|·v`, `F_s = k_i·(u − p)` within ±r_i (slipping moves the set p); at the toe
`F = F_s·(1 + J·v)`, `F_s = k·(u − p)` within [0, R_u], never pulling. Masses and springs stepped
by central differences, the soil's dampers at the half step before: a scheme of its own, written
apart from the solver's, converging to first order in Δt and second in Δx.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np


class SmithPile(NamedTuple):
    """What a run of the lumped model gives: the toe's set (m), the largest force at the pile's head
    (the cushion's, N), the largest spring force along the pile over its area (compression, Pa),
    the work done on the pile through its head (the largest over time, J), the ram's velocity at
    the end (m/s)."""

    set: float
    peak_force: float
    max_compressive_stress: float
    transferred: float
    ram_velocity: float


def smith_pile(case: dict, segments: int = 300, courant: float = 0.25) -> SmithPile:
    """Run the case (a percussim case as JSON: a lumped `striker`, a uniform `tool`, a linear
    `contact` with its `restitution`, `shaft` segments and a Smith `medium`, no gravity or anvil)
    for `numerics.duration`, on `segments` masses and a time step of `courant`·Δx/a."""
    tool, ram, cushion, toe = case["tool"], case["striker"], case["contact"], case["medium"]
    length, area, modulus, density = tool["length"], tool["area"], tool["youngs_modulus"], tool["density"]
    dx = length / segments
    dt = courant * dx / np.sqrt(modulus / density)
    mass = np.full(segments, density * area * dx)
    spring = modulus * area / dx
    middle = (np.arange(segments) + 0.5) * dx
    r = np.zeros(segments)
    k = np.zeros(segments)
    jr = np.zeros(segments)  # J·r: a segment's damping weighted by its share
    for s in case.get("shaft", []):
        share = np.clip(np.minimum(middle + dx / 2, s["to"]) - np.maximum(middle - dx / 2, s["from"]), 0, None)
        part = s["ultimate_resistance"] * share / (s["to"] - s["from"])
        r += part
        k += part / s["quake"]
        jr += part * s.get("damping_factor", 0.0)
    shaft_j = np.divide(jr, r, out=np.zeros(segments), where=r > 0)
    r_toe, k_toe, j_toe = toe["ultimate_resistance"], toe["ultimate_resistance"] / toe["quake"], toe["damping_factor"]
    k_c, e = cushion["stiffness"], cushion.get("restitution", 1.0)

    u, v = np.zeros(segments), np.zeros(segments)
    p = np.zeros(segments)  # the shaft's sets
    p_toe, deepest = 0.0, 0.0
    y, w, m_ram = 0.0, ram["velocity"], ram["mass"]
    peak, most_compression, work, transferred = 0.0, 0.0, 0.0, 0.0
    for _ in range(int(np.ceil(case["numerics"]["duration"] / dt))):
        delta = y - u[0]
        deepest = max(deepest, delta)
        # a cushion unloads along k/e² from its deepest compression, down to its set (1 − e²)·δ_m
        cushion_force = max(0.0, min(k_c * delta, k_c * (delta - (1.0 - e * e) * deepest) / (e * e)))
        if delta < 0.0:
            deepest = 0.0
        stretch = spring * np.diff(u)  # tension positive
        static = np.clip(k * (u - p), -r, r)
        p = np.where(np.abs(k * (u - p)) > r, u - static / np.where(k > 0, k, 1.0), p)
        shaft = static + shaft_j * np.abs(static) * v
        toe_static = min(max(k_toe * (u[-1] - p_toe), 0.0), r_toe)
        if k_toe * (u[-1] - p_toe) > r_toe:
            p_toe = u[-1] - r_toe / k_toe
        toe_force = max(0.0, toe_static * (1.0 + j_toe * v[-1]))
        force = -shaft
        force[:-1] += stretch
        force[1:] -= stretch
        force[0] += cushion_force
        force[-1] -= toe_force
        v_before = v[0]
        v = v + dt * force / mass
        u = u + dt * v
        w -= dt * cushion_force / m_ram
        y += dt * w
        work += cushion_force * 0.5 * (v_before + v[0]) * dt
        transferred = max(transferred, work)
        peak = max(peak, cushion_force)
        most_compression = max(most_compression, -stretch.min(initial=0.0), cushion_force)
    return SmithPile(
        set=float(p_toe),
        peak_force=float(peak),
        max_compressive_stress=float(most_compression / area),
        transferred=float(transferred),
        ram_velocity=float(w),
    )
