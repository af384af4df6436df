"""Closed-form references the solver is held to.

- `LinearImpact`: a striker on a long uniform rod through a linear contact (model.md, reference 1).
  Before the first reflection is back (t < 2L/a) the struck end sees the impedance `Z = S·ρ·a`, and
  the overlap obeys `δ'' + (k/Z)δ' + (k/m1)δ = 0`, δ(0) = 0, δ'(0) = W1: a damped oscillator.
- `RigidImpact`: Saint-Venant's problem, a rigid mass striking a uniform bar whose far end is
  fixed; the struck end's stress is `σ0·e^(−βt)` until the wave is back at 2L/a, then the
  reflected wave adds to it.
- `CushionedImpact`: a lumped ram on a long uniform pile through a linear cushion, of any damping
  ratio (a pile hammer's first peak force, before the toe's reflection is back).
- `LundbergRock`: a rectangular wave on rock with a bilinear force–penetration law (Lundberg):
  the peak force at the bit, the penetration, the share of the wave's energy the rock keeps.
- `recorded_force`: a run's recorded contact force against an independent solver's.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from percussim.solver.accuracy import headline
from percussim.solver.grid import wave_speed


class LinearImpact:
    """A striker `m1` at `W1` on a steel rod through a linear contact of damping ratio `ζ`."""

    def __init__(
        self,
        zeta: float = 0.3,
        m1: float = 20.0,
        w1: float = 5.0,
        area: float = 0.01,
        length: float = 2.0,
        youngs_modulus: float = 2.1e11,
        density: float = 7800.0,
    ):
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
        # the striker's impulse ∫k·δ dt over the contact takes m1·W1·(1 + e^(−decay·T)) from it
        self.rebound_velocity = -w1 * math.exp(-self.decay * self.contact_time)

    def force(self, t):
        """Contact force `k·δ(t)` while in contact (t a number or an array)."""
        return self.k * self.w1 / self.omega_d * np.exp(-self.decay * t) * np.sin(self.omega_d * t)

    def stress(self, t: np.ndarray, x: float) -> np.ndarray:
        """`σ(x, t) = −F_c(t − x/a)/S`: the contact pulse travelling down the rod, 0 outside it."""
        delayed = np.asarray(t, dtype=float) - x / self.a
        inside = (delayed >= 0) & (delayed <= self.contact_time)
        return np.where(inside, -self.force(delayed) / self.area, 0.0)

    def truth(self) -> dict[str, float]:
        """The exact values of the headline quantities the closed form gives."""
        return {
            "co_impact_time": self.contact_time,
            "peak_contact_force": self.peak_force,
            "max_compressive_stress": self.peak_force / self.area,
            "striker_rebound_velocity": self.rebound_velocity,
        }

    def errors(self, summary: dict) -> tuple[float, float]:
        """Relative errors of a run's co-impact time and peak contact force."""
        return (
            summary["co_impact_time"] / self.contact_time - 1,
            summary["peak_contact_force"]["value"] / self.peak_force - 1,
        )

    def case(self, cells: int, courant: float = 0.5, **outputs) -> dict:
        """The case as JSON-ready dict, on `cells` cells at Courant number `aτ/h`."""
        h = self.length / cells
        return {
            "name": "linear-impact-reference",
            "striker": {"mass": self.m1, "velocity": self.w1},
            "tool": {
                "length": self.length,
                "area": self.area,
                "youngs_modulus": self.youngs_modulus,
                "density": self.density,
            },
            "contact": {"stiffness": self.k, "exponent": 0.0},
            "numerics": {"duration": 1.2 * self.contact_time, "cells": cells, "time_step": courant * h / self.a},
            "outputs": outputs,
        }


class RigidImpact:
    """Saint-Venant's problem: a rigid mass `m1` at `W1` strikes a uniform bar of length L whose far
    end is fixed. With `β = Z/m1`, `σ0 = ρ·a·W1` (compression), `T = 2L/a` and `μ = βT = 2·m2/m1`,
    the struck end's stress is `σ0·e^(−βt)` for t < T and `σ0·e^(−βs)·(e^(−μ) + 2 − 2βs)`, s = t − T,
    after the wave reflected by the fixed end is back, until the contact's force falls to 0
    (within 2T when μ > 1.2). So the contact force is largest, `σ0·S·(2 + e^(−μ))`, at t = T; the
    fixed end, where the stress is twice the wave arriving, sees `2σ0` at t = L/a and then
    `2σ0·(1 + e^(−μ))` at t = 3L/a, the largest compression of the run.

    In the solver the mass strikes through a contact, of damping ratio ζ on the bar, and the end
    rests on a medium; the contact's compliance changes the answer by about ζ^−2/4. The medium
    must be far stiffer than the contact: a spring end reflects a front as a free end would for
    a moment (Z/c2) before it holds, and that tensile spike, back at the striker, pulls the struck
    end by about 2ΔF/c2, which must stay below the contact's overlap F/k (`case`: c2 = 100·k).
    """

    def __init__(
        self,
        m1: float = 80.0,
        w1: float = 5.0,
        area: float = 0.01,
        length: float = 1.0,
        youngs_modulus: float = 2.1e11,
        density: float = 7800.0,
    ):
        self.m1, self.w1, self.area, self.length = m1, w1, area, length
        self.youngs_modulus, self.density = youngs_modulus, density
        self.a = math.sqrt(youngs_modulus / density)
        self.impedance = density * self.a * area
        self.beta = self.impedance / m1
        self.sigma0 = density * self.a * w1
        self.return_time = 2.0 * length / self.a
        self.mu = self.beta * self.return_time  # = 2·m2/m1
        if self.mu <= 1.2:
            raise ValueError("the contact must end within two returns of the wave: m1 < 1.66·m2")
        self.contact_time = self.return_time + (2.0 + math.exp(-self.mu)) / (2.0 * self.beta)

    def struck_end_stress(self, t) -> np.ndarray:
        """Compression (positive) at the struck end while in contact."""
        t = np.asarray(t, dtype=float)
        s = t - self.return_time
        first = self.sigma0 * np.exp(-self.beta * t)
        second = (
            self.sigma0 * np.exp(-self.beta * s) * (math.exp(-self.beta * self.return_time) + 2.0 - 2.0 * self.beta * s)
        )
        return np.where(t < self.return_time, first, second)

    def truth(self) -> dict[str, float]:
        """The exact co-impact time, peak contact force (at t = 2L/a) and largest compression (at
        the fixed end at t = 3L/a)."""
        echo = math.exp(-self.mu)
        return {
            "co_impact_time": self.contact_time,
            "peak_contact_force": self.sigma0 * self.area * (2.0 + echo),
            "max_compressive_stress": 2.0 * self.sigma0 * (1.0 + echo),
        }

    def case(self, contact_zeta: float = 100.0) -> dict:
        """The case, its numerics left to the solver: a linear contact of damping ratio
        `contact_zeta` against the bar (`k = (2ζZ)²/m1`), a medium 100·k, over a run 10% longer
        than the contact."""
        k = (2.0 * contact_zeta * self.impedance) ** 2 / self.m1
        return {
            "name": "saint-venant",
            "striker": {"mass": self.m1, "velocity": self.w1},
            "tool": {
                "length": self.length,
                "area": self.area,
                "youngs_modulus": self.youngs_modulus,
                "density": self.density,
            },
            "contact": {"stiffness": k, "exponent": 0.0},
            "medium": {"stiffness": 100.0 * k},
            "numerics": {"duration": 1.1 * self.contact_time},
        }


def impedance(rod) -> float:
    """`Z = ρ·a·A` of a uniform rod: a `Tool`, or an elastic striker's `rod()`."""
    return rod.density * wave_speed(rod) * rod.area


class CushionedImpact:
    """A lumped ram `mass` at `velocity` on a uniform rod of impedance `impedance` (a pile) through
    a linear cushion of `stiffness`, until the far end's reflection is back (t < 2L/a): the
    cushion's compression obeys `δ'' + (k/Z)·δ' + (k/m)·δ = 0`, δ(0) = 0, δ'(0) = v, its force is
    k·δ. The damping ratio `ζ = √(k·m)/(2Z)` is any: a soft cushion rings (ζ < 1), a stiff one
    (ζ > 1) gives nearly the rigid ram's Z·v at once and lets it decay."""

    def __init__(self, mass: float, velocity: float, stiffness: float, impedance: float):
        omega = math.sqrt(stiffness / mass)
        self.zeta = math.sqrt(stiffness * mass) / (2.0 * impedance)
        decay = self.zeta * omega
        if self.zeta < 1.0:
            omega_d = omega * math.sqrt(1.0 - self.zeta**2)
            self.peak_time = math.atan2(omega_d, decay) / omega_d
            overlap = velocity / omega_d * math.exp(-decay * self.peak_time) * math.sin(omega_d * self.peak_time)
        elif self.zeta == 1.0:
            self.peak_time = 1.0 / omega
            overlap = velocity * self.peak_time * math.exp(-1.0)
        else:  # δ = v·(e^(r1·t) − e^(r2·t))/(r1 − r2), its maximum where r1·e^(r1·t) = r2·e^(r2·t)
            spread = omega * math.sqrt(self.zeta**2 - 1.0)
            r1, r2 = -decay + spread, -decay - spread
            self.peak_time = math.log(r2 / r1) / (r1 - r2)
            overlap = velocity * (math.exp(r1 * self.peak_time) - math.exp(r2 * self.peak_time)) / (r1 - r2)
        self.peak_force = stiffness * overlap

    @classmethod
    def of_case(cls, case) -> CushionedImpact:
        """A case's lumped striker on its uniform tool through its linear contact (exponent 0,
        no damper: what the closed form assumes, the caller checks)."""
        return cls(case.striker.mass, case.impact_velocity, case.contact.stiffness, impedance(case.tool))


class LundbergRock:
    """Lundberg's rock under a rectangular incident wave of force `incident` lasting `duration`
    in a rod of impedance `impedance`, the bit resting on the rock: loading at `stiffness` k,
    `u' = (2F_i − F)/Z` gives `F = 2F_i·(1 − e^(−kt/Z))` until the wave has passed, then the rock
    unloads at `unloading_stiffness` k_u. With `x = k·T/Z` the bit's peak force is
    `2F_i·(1 − e^(−x))`, the deepest penetration that over k, the permanent one (1 − k/k_u) of it,
    and the rock keeps `2(1 − e^(−x))²/x·(1 − k/k_u)` of the wave's energy F_i²·T/Z (the piston's
    own when its impedance is the rod's), largest (0.8145 for k_u → ∞) at x = 1.2564."""

    def __init__(
        self, incident: float, duration: float, impedance: float, stiffness: float, unloading_stiffness: float
    ):
        self.incident = incident
        self.x = stiffness * duration / impedance
        kept = 1.0 - stiffness / unloading_stiffness
        self.peak_force = 2.0 * incident * (1.0 - math.exp(-self.x))
        self.max_penetration = self.peak_force / stiffness
        self.permanent_penetration = self.max_penetration * kept
        self.efficiency = 2.0 * (1.0 - math.exp(-self.x)) ** 2 / self.x * kept

    @classmethod
    def of_case(cls, case) -> LundbergRock:
        """A case's uniform elastic piston on its uniform tool on bilinear rock: the wave of
        `Z_p·Z·v/(Z_p + Z)` lasting 2L_p/a_p its impact sends (through a contact too stiff to
        shape it). The efficiency is of the piston's energy only when Z_p = Z."""
        piston, tool, rock = case.striker.rod(), case.tool, case.medium
        z_piston, z_tool = impedance(piston), impedance(tool)
        incident = z_piston * z_tool * case.striker.velocity / (z_piston + z_tool)
        return cls(incident, 2.0 * piston.length / wave_speed(piston), z_tool, rock.stiffness, rock.unloading_stiffness)


def observed_order(cells, errors) -> float:
    """Observed order of convergence: the least-squares slope of log|error| against log h over a
    ladder of grids, one number that the sampling noise of a single grid cannot swing."""
    return float(-np.polyfit(np.log(cells), np.log(np.abs(errors)), 1)[0])


def true_errors(summary: dict, truth: dict[str, float]) -> dict[str, float]:
    """Relative errors of a run's headline quantities against `truth` (`LinearImpact.truth`)."""
    found = headline(summary)
    return {name: abs(found[name] / truth[name] - 1.0) for name in truth}


class RecordedForce(NamedTuple):
    """A run's recorded contact force against an independent solver's, as fractions of its peak."""

    deviation: float  # the largest difference, once the reference's first sample is twice past
    second_difference: float  # the largest second difference of the samples
    alternating: float  # the share of second differences that alternate: a period-2τ ripple


def recorded_force(history: dict[str, np.ndarray], peak: float, reference: dict[str, np.ndarray]) -> RecordedForce:
    """Compare `history['contact/force']` (at `history['time']`) with the reference's `contact`
    force (at its `time`), interpolated onto the run's instants; `peak` scales each figure."""
    t, force = history["time"], history["contact/force"]
    expected = np.interp(t, reference["time"], reference["contact"])
    late = t > 2 * reference["time"][0]
    second = force[2:] - 2.0 * force[1:-1] + force[:-2]
    alternating = np.abs(second[1:] + second[:-1]) < 0.5 * np.abs(second[1:] - second[:-1])
    return RecordedForce(
        float(np.abs(force - expected)[late].max() / peak),
        float(np.abs(second).max() / peak),
        float(alternating.mean()),
    )


class Ringing(NamedTuple):
    """The rigid-body mode a run's tool rings at: its angular frequency (rad/s, from the mean
    half period), the half periods' spread over their mean, and how many were seen."""

    omega: float
    spread: float
    half_periods: int


def ringing(result, grid) -> Ringing:
    """The mass-weighted mean displacement of the tool (`result.fields` on `grid`) after the first
    contact, its zero crossings (linear between samples) and what they say of its frequency: the
    mean ignores the elastic waves, whose momentum along the tool sums to none."""
    fields = result.fields
    mean = fields.displacement @ grid.node_area / grid.node_area.sum()
    after = fields.time > result.summary["contacts"][0]["end"]
    t, u = fields.time[after], mean[after]
    crossings = [t[k] - u[k] * (t[k + 1] - t[k]) / (u[k + 1] - u[k]) for k in np.flatnonzero(np.diff(np.sign(u)))]
    half = np.diff(crossings)
    return Ringing(float(math.pi / half.mean()), float(np.ptp(half) / half.mean()), len(half))
