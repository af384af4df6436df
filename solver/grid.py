"""The tool on its grid and the numerics a case resolves to (τ, N, γ, number of steps)."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from .case import Case, CaseError, FieldError, Tool

DEFAULT_CELLS = 100
STEPS_PER_CONTACT = 200  # default τ resolves the estimated contact by this many steps


def tool_area(tool: Tool, x: np.ndarray) -> np.ndarray:
    """Cross-section `S(x)` (m²) at stations `x`."""
    if tool.profile is None:
        return np.full_like(np.asarray(x, dtype=float), tool.area)
    return np.interp(x, tool.profile.x, tool.profile.area)


def tool_mass(tool: Tool) -> float:
    """`m2 = ρ∫S dx`, exact for the piecewise-linear profile."""
    if tool.profile is None:
        return tool.density * tool.area * tool.length
    return tool.density * float(np.trapezoid(tool.profile.area, tool.profile.x))


def wave_speed(tool: Tool) -> float:
    """`a = sqrt(E/ρ)` (m/s)."""
    return math.sqrt(tool.youngs_modulus / tool.density)


def contact_time_estimate(case: Case) -> float:
    """Duration of the striker's contact with a rigid wall under the case's contact law (s).

    The tool yields, so the true contact is longer: a time step from this estimate errs on the
    fine side. With no impact velocity the external force sets the indentation instead.
    """
    c1, alpha, m1 = case.contact.stiffness, case.contact.exponent, case.striker.mass
    p = 1.0 + alpha  # force exponent
    w1 = abs(case.striker.velocity)
    if w1 > 0:
        depth = ((p + 1.0) * m1 * w1 * w1 / (2.0 * c1)) ** (1.0 / (p + 1.0))  # inf, not an error
    elif case.force is not None and case.force.amplitude != 0:
        depth = (abs(case.force.amplitude) / c1) ** (1.0 / p)
    else:
        return case.numerics.duration
    stiffness = c1 * depth**alpha
    return math.pi * math.sqrt(m1 / stiffness)


@dataclass(frozen=True)
class ResolvedNumerics:
    """The numerics a run actually uses; stored with every result."""

    model: str
    time_step: float
    cells: int
    gamma: float
    steps: int
    courant: float  # a·τ/h

    def as_dict(self) -> dict:
        return asdict(self)


def resolve_numerics(case: Case, model: str | None = None) -> ResolvedNumerics:
    """Fill in the defaults: N = 100 cells; τ the smaller of h/a (Courant 1) and the estimated
    contact time / 200, so that both the wave and the lagged contact stiffness are resolved."""
    num = case.numerics
    cells = num.cells or DEFAULT_CELLS
    h = case.tool.length / cells
    a = wave_speed(case.tool)
    tau = num.time_step or min(h / a, contact_time_estimate(case) / STEPS_PER_CONTACT)
    steps = num.duration / tau if tau > 0 else math.inf
    if not math.isfinite(steps):
        raise CaseError([FieldError(
            field="numerics.time_step",
            message=f"no time step can be chosen for this case (the estimated contact time is "
                    f"{tau * STEPS_PER_CONTACT:.3g} s): give numerics.time_step")])
    steps = max(1, math.ceil(steps - 1e-9))
    return ResolvedNumerics(
        model=model or num.model, time_step=tau, cells=cells, gamma=num.gamma,
        steps=steps, courant=a * tau / h,
    )


@dataclass(frozen=True)
class Grid:
    """The tool on `N + 1` nodes `x_i = i·h`.

    `area` is `S_i`, `area_mid` the cell areas `(S_i + S_{i+1})/2`, and `q` the scheme's
    area-gradient factor `q_i = (S_{i+1} − S_{i−1})/(4 S_i)` (0 at the ends and on a uniform tool).
    """

    x: np.ndarray
    area: np.ndarray
    area_mid: np.ndarray
    q: np.ndarray
    h: float
    youngs_modulus: float
    density: float

    @property
    def cells(self) -> int:
        return len(self.x) - 1

    @property
    def uniform(self) -> bool:
        return not np.any(self.q)


def make_grid(tool: Tool, cells: int) -> Grid:
    x = np.linspace(0.0, tool.length, cells + 1)
    area = tool_area(tool, x)
    q = np.zeros_like(area)
    q[1:-1] = (area[2:] - area[:-2]) / (4.0 * area[1:-1])
    return Grid(
        x=x, area=area, area_mid=0.5 * (area[1:] + area[:-1]), q=q, h=tool.length / cells,
        youngs_modulus=tool.youngs_modulus, density=tool.density,
    )
