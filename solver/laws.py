"""The laws at the struck end, in one place: the external force R(t) on the striker and the
contact law (7). Plain Python on scalars: the kernel compiles them (`kernel.contact`), and the
lumped model, the benches and the tests call them as they are. No Numba here.
"""

from __future__ import annotations

import math

import numpy as np

# R(t)'s kinds, as the kernel takes them (`ForceLaw.kind`), and the case's names for them
FORCE_NONE, FORCE_SINE, FORCE_ABS_SINE, FORCE_PULSE = 0, 1, 2, 3
FORCE_KINDS = {"sine": FORCE_SINE, "abs_sine": FORCE_ABS_SINE, "pulse": FORCE_PULSE}


def external_force(t, kind, amplitude, omega, start, duration):
    """`R(t)`: P·sin(ωt), P·|sin(ωt)|, or P on [t1, t1 + Δt]; 0 with no force."""
    if kind == FORCE_SINE:
        return amplitude * np.sin(omega * t)
    if kind == FORCE_ABS_SINE:
        return amplitude * abs(np.sin(omega * t))
    if kind == FORCE_PULSE:
        if start <= t <= start + duration:
            return amplitude
    return 0.0


def contact_law(delta, stiffness, exponent, tension_stiffness, restitution=1.0, deepest=0.0):
    """`(Φ'(δ), Φ(δ))`: the spring force G(δ)·δ of (7), `c1·δ^(α+1)` in contact and `c0·δ` in
    separation, and the energy Φ the contact stores, `c1·δ^(α+2)/(α+2)` or `c0·δ²/2`; one power
    for both, as on a small grid the contact solve is a large part of a step.

    A cushion (`restitution` e < 1) pressed to `deepest` δ_m unloads below it along
    `c1·((δ − δ_p)/e²)^(α+1)`, δ_p = (1 − e²)·δ_m: the same power, stiffer, continuous at δ_m and
    0 at δ_p. It gives back e² of the `c1·δ_m^(α+2)/(α+2)` the loading stored; the rest is
    `cushion_loss`. Φ is then what unloading from δ would give back."""
    if delta >= 0.0:
        share = 1.0  # of the squeeze's energy the contact gives back
        if restitution < 1.0 and delta <= deepest:
            share = restitution * restitution
            delta = max(0.0, (delta - deepest * (1.0 - share)) / share)
        force = stiffness * delta ** (exponent + 1.0)
        return force, share * force * delta / (exponent + 2.0)
    return tension_stiffness * delta, 0.5 * tension_stiffness * delta * delta


def contact_spring(delta, stiffness, exponent, tension_stiffness, restitution=1.0, deepest=0.0):
    """`(Φ'(δ), Φ''(δ))`: the spring force G(δ)·δ and its stiffness (a cushion's unloading as
    `contact_law`'s); the common exponents without a power."""
    if delta >= 0.0:
        scale = 1.0  # dδ'/dδ of the squeeze δ' the law is read at
        if restitution < 1.0 and delta <= deepest:
            scale = 1.0 / (restitution * restitution)
            delta = max(0.0, (delta - deepest * (1.0 - restitution * restitution)) * scale)
        if exponent == 0.0:
            return stiffness * delta, stiffness * scale
        if exponent == 0.5:
            root = math.sqrt(delta)
            return stiffness * delta * root, 1.5 * stiffness * root * scale
        power = delta**exponent
        return stiffness * delta * power, (exponent + 1.0) * stiffness * power * scale
    return tension_stiffness * delta, tension_stiffness


def linear_branch(delta, stiffness, tension_stiffness, restitution=1.0, deepest=0.0):
    """`(slope, offset, low, high)`: the line a linear contact's force (α = 0) follows at δ,
    `F = slope·δ + offset`, and the overlaps it holds over (`contact_spring`'s lines): c0·δ in
    tension; pressed, for a cushion pressed to δ_m, nothing up to its set δ_p = (1 − e²)·δ_m and
    c1·(δ − δ_p)/e² from there to δ_m; c1·δ beyond (from 0 for a contact that is no cushion)."""
    if delta < 0.0:
        return tension_stiffness, 0.0, -math.inf, 0.0
    e2 = restitution * restitution
    if e2 < 1.0 and delta <= deepest:
        set_ = deepest * (1.0 - e2)
        if delta < set_:
            return 0.0, 0.0, 0.0, set_
        return stiffness / e2, -stiffness / e2 * set_, set_, deepest
    return stiffness, 0.0, deepest if e2 < 1.0 else 0.0, math.inf


def cushion_loss(stiffness, exponent, restitution, deepest):
    """What a cushion pressed to `deepest` δ_m has lost (`contact_law`): `(1 − e²)·c1·δ_m^(α+2)/(α+2)`."""
    return (1.0 - restitution * restitution) * stiffness * deepest ** (exponent + 2.0) / (exponent + 2.0)


def pressed_branch(delta, stiffness, exponent):
    """The contact's branch `c1·|δ|^α·δ`, continued as an odd function past δ = 0: the law's force
    where δ ≥ 0, and smooth across 0, so that an integrator that locates the contact's end as an
    event sees no kink before it (the lumped model)."""
    return stiffness * np.abs(delta) ** exponent * delta


def contact_law_on(deltas, stiffness, exponent, tension_stiffness):
    """`contact_law` at every overlap of an array, in NumPy (the lumped model's histories): the
    pressed branch as `pressed_branch` and its energy `c1·|δ|^(α+2)/(α+2)`, which are the scalar
    law's where δ ≥ 0 (tests/test_laws.py holds them to it)."""
    deltas = np.asarray(deltas, dtype=float)
    pressed = deltas >= 0.0
    force = np.where(pressed, pressed_branch(deltas, stiffness, exponent), tension_stiffness * deltas)
    stored = stiffness * np.abs(deltas) ** (exponent + 2.0) / (exponent + 2.0)
    return force, np.where(pressed, stored, 0.5 * tension_stiffness * deltas * deltas)


def external_force_on(times, kind, amplitude, omega, start, duration):
    """`external_force` at every instant of an array, in NumPy."""
    times = np.asarray(times, dtype=float)
    if kind == FORCE_SINE:
        return amplitude * np.sin(omega * times)
    if kind == FORCE_ABS_SINE:
        return amplitude * np.abs(np.sin(omega * times))
    if kind == FORCE_PULSE:
        return np.where((start <= times) & (times <= start + duration), amplitude, 0.0)
    return np.zeros_like(times)
