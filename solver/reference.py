"""Closed-form reference: linear contact on a long uniform rod (model.md, reference 1).

Before the first reflection is back (t < 2L/a) the struck end sees the impedance `Z = S·ρ·a`, and
the overlap obeys `δ'' + (k/Z)δ' + (k/m1)δ = 0`, δ(0) = 0, δ'(0) = W1, with `k = c1` (α = 0).
"""

from __future__ import annotations

import math

import numpy as np

from .adaptive import quantities
from .case import parse_case
from .controller import simulate_rod


class LinearImpact:
    """A striker `m1` at `W1` on a steel rod through a linear contact of damping ratio `ζ`."""

    def __init__(self, zeta: float = 0.3, m1: float = 20.0, w1: float = 5.0, area: float = 0.01,
                 length: float = 2.0, youngs_modulus: float = 2.1e11, density: float = 7800.0):
        self.m1, self.w1, self.area, self.length = m1, w1, area, length
        self.youngs_modulus, self.density = youngs_modulus, density
        self.a = math.sqrt(youngs_modulus / density)
        self.impedance = area * density * self.a
        self.k = (2 * zeta * self.impedance) ** 2 / m1  # ζ = k/(2Zω) with ω = sqrt(k/m1)
        omega = math.sqrt(self.k / m1)
        self.zeta = self.k / (2 * self.impedance * omega)
        self.omega_d = omega * math.sqrt(1 - self.zeta**2)
        self.decay = self.zeta * omega
        self.contact_time = math.pi / self.omega_d
        self.peak_time = math.atan2(self.omega_d, self.decay) / self.omega_d
        self.peak_force = float(self.force(self.peak_time))

    def force(self, t):
        """Contact force `k·δ(t)` while in contact (t a number or an array)."""
        return self.k * self.w1 / self.omega_d * np.exp(-self.decay * t) * np.sin(self.omega_d * t)

    def stress(self, t: np.ndarray, x: float) -> np.ndarray:
        """`σ(x, t) = −F_c(t − x/a)/S`: the contact pulse travelling down the rod, 0 outside it."""
        delayed = np.asarray(t, dtype=float) - x / self.a
        inside = (delayed >= 0) & (delayed <= self.contact_time)
        return np.where(inside, -self.force(delayed) / self.area, 0.0)

    def truth(self) -> dict[str, float]:
        """The exact values of the quantities a tolerance applies to."""
        return {"co_impact_time": self.contact_time, "peak_contact_force": self.peak_force,
                "max_stress": self.peak_force / self.area}

    def errors(self, summary: dict) -> tuple[float, float]:
        """Relative errors of a run's co-impact time and peak contact force."""
        return (summary["co_impact_time"] / self.contact_time - 1,
                summary["peak_contact_force"]["value"] / self.peak_force - 1)

    def case(self, cells: int, courant: float = 0.5, **outputs) -> dict:
        """The case as JSON-ready dict, on `cells` cells at Courant number `aτ/h`."""
        h = self.length / cells
        return {
            "name": "linear-impact-reference",
            "striker": {"mass": self.m1, "velocity": self.w1},
            "tool": {"length": self.length, "area": self.area,
                     "youngs_modulus": self.youngs_modulus, "density": self.density},
            "contact": {"stiffness": self.k, "exponent": 0.0},
            "numerics": {"duration": 1.2 * self.contact_time, "cells": cells,
                         "time_step": courant * h / self.a},
            "outputs": outputs,
        }


def observed_order(cells, errors) -> float:
    """Observed order of convergence: the least-squares slope of log|error| against log h over a
    ladder of grids, one number that the sampling noise of a single grid cannot swing."""
    return float(-np.polyfit(np.log(cells), np.log(np.abs(errors)), 1)[0])


# The fixed grids a tolerance run is measured against: every scheme, at two Courant numbers
FIXED_GRIDS = (("paper", 1.0), ("sigma", 1.0), ("sigma", 0.5), ("explicit", 1.0), ("explicit", 0.5))


def true_errors(summary: dict, truth: dict[str, float]) -> dict[str, float]:
    """Relative errors of a run's quantities against `truth` (`LinearImpact.truth`)."""
    found = quantities(summary)
    return {name: abs(found[name] / truth[name] - 1.0) for name in truth}


def work(runs: list[dict]) -> float:
    """The work of runs (a summary's `runs`): nodes × steps, summed."""
    return sum((r["cells"] + 1) * (r["steps"] + 1) for r in runs)


def cheapest_fixed_grid(reference: LinearImpact, tol: float) -> tuple[float, tuple]:
    """The least work of any of `FIXED_GRIDS` on a ladder of grids 2^(1/4) apart whose true error
    on every quantity is within `tol`, and that grid: a yardstick known only in hindsight."""
    truth = reference.truth()
    best = (math.inf, None)
    for scheme, courant in FIXED_GRIDS:
        for k in range(40):
            cells = round(8 * 2 ** (k / 4))
            case = reference.case(cells, courant=courant)
            case["numerics"]["scheme"] = scheme
            result = simulate_rod(parse_case(case))
            if max(true_errors(result.summary, truth).values()) <= tol:
                best = min(best, (work([result.summary["numerics"]]), (scheme, courant, cells)))
                break
    return best
