"""Shared case builders for the tests."""

from __future__ import annotations

import copy
import math

import pytest

STEEL = {"youngs_modulus": 2.1e11, "density": 7800.0}


def merge(base: dict, changes: dict) -> dict:
    """`base` with `changes` merged in, recursively (a None value removes the key)."""
    out = copy.deepcopy(base)
    for key, value in changes.items():
        if value is None:
            out.pop(key, None)
        elif isinstance(value, dict) and isinstance(out.get(key), dict):
            out[key] = merge(out[key], value)
        else:
            out[key] = value
    return out


BASE_CASE = {
    "name": "test",
    "striker": {"mass": 20.0, "velocity": 5.0},
    "tool": {"length": 1.2, "area": 0.014209, **STEEL},
    "contact": {"stiffness": 1e11, "exponent": 0.5, "tension_stiffness": 3e4, "damping": 1.2e3},
    "medium": {"stiffness": 2e8, "damping": 1e3},
    "numerics": {"duration": 1e-3, "time_step": 8.3e-7, "cells": 100, "gamma": 0.5},
}


@pytest.fixture
def base_case() -> dict:
    return copy.deepcopy(BASE_CASE)


class LinearImpact:
    """Reference 1 of model.md: linear contact on a long uniform rod, before the first reflection.

    `δ'' + (k/Z)δ' + (k/m1)δ = 0`, δ(0) = 0, δ'(0) = W1, with the rod's impedance Z = S·ρ·a.
    """

    m1, w1, area, length = 20.0, 5.0, 0.01, 2.0
    E, rho = STEEL["youngs_modulus"], STEEL["density"]

    def __init__(self, zeta: float = 0.3):
        self.a = math.sqrt(self.E / self.rho)
        self.impedance = self.area * self.rho * self.a
        self.k = (2 * zeta * self.impedance) ** 2 / self.m1
        omega = math.sqrt(self.k / self.m1)
        self.zeta = self.k / (2 * self.impedance * omega)
        self.omega_d = omega * math.sqrt(1 - self.zeta**2)
        self.decay = self.zeta * omega
        self.contact_time = math.pi / self.omega_d
        self.peak_time = math.atan2(self.omega_d, self.decay) / self.omega_d
        self.peak_force = self.force(self.peak_time)

    def force(self, t):
        """Contact force k·δ(t) while in contact."""
        return self.k * self.w1 / self.omega_d * math.exp(-self.decay * t) * math.sin(self.omega_d * t)

    def case(self, cells: int, courant: float = 0.5, **outputs) -> dict:
        h = self.length / cells
        return {
            "striker": {"mass": self.m1, "velocity": self.w1},
            "tool": {"length": self.length, "area": self.area, **STEEL},
            "contact": {"stiffness": self.k, "exponent": 0.0},
            "numerics": {"duration": 1.2 * self.contact_time, "cells": cells,
                         "time_step": courant * h / self.a},
            "outputs": outputs,
        }


@pytest.fixture
def linear_impact() -> LinearImpact:
    return LinearImpact()
