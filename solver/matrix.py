"""The validation matrix: seeded random cases over the whole valid parameter space, each with a
converged reference from the characteristics solver (`solver.characteristics`).

`draw_cases(seed, count)` gives the same cases for the same seed on any machine. A case is drawn
in the terms an engineer would vary:

- striker 0.5–200 kg at 0.5–20 m/s; a steel tool 0.1–3 m long, 20–150 mm across: uniform,
  tapered (area ratio 1:4 to 4:1), stepped (a shoulder over 5% of the length, ratio 1:4 to 4:1) or
  conical (a cone over the last 30–100% of the length, area ratio 1:10 to 10:1);
- contact exponent α 0–0.5, and a stiffness across six decades: its damping ratio against the
  tool, `ζ = √(k·m1)/(2Z)` with k the contact's tangent stiffness at the depth of a rigid-wall
  impact and Z = ρ·a·S(0), from 0.03 (a soft cushion, the tool moves as one) to 30 (a flat
  steel-on-steel blow, Saint-Venant's rigid impact); the weak link c0 0 or up to 1% of k;
- contact damping 0 to 3× critical (`b1 = 2ζ_b·√(k·m1)`), medium damping 0 to 3× the tool's
  impedance;
- no medium, a soft one (the tool's end stiffness E·S/L times 1e-3–1e-1) or a very stiff one
  (times 1–100);
- no force, sine, abs-sine or a pulse whose start and length fall on no grid, its amplitude such
  that it gives 0.1–5 times the striker's impact momentum over the run, pushing or pulling;
- a duration of 1.2–20 times the longer of the rigid-wall contact time and the wave's return time
  2L/a: from one contact to many.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .accuracy import left_out
from .case import Case, parse_case
from .characteristics import Reference, solve
from .grid import contact_time_estimate, wave_speed

STEEL = {"youngs_modulus": 2.1e11, "density": 7800.0}


def _log_uniform(rng: np.random.Generator, low: float, high: float) -> float:
    return float(math.exp(rng.uniform(math.log(low), math.log(high))))


def _profile(rng: np.random.Generator, shape: str, length: float, area: float) -> dict:
    if shape == "uniform":
        return {"area": area}
    if shape == "tapered":
        end = area * _log_uniform(rng, 0.25, 4.0)
        return {"profile": {"x": [0.0, length], "area": [area, end]}}
    if shape == "stepped":
        at = rng.uniform(0.2, 0.7) * length
        end = area * _log_uniform(rng, 0.25, 4.0)
        return {"profile": {"x": [0.0, at, at + 0.05 * length, length], "area": [area, area, end, end]}}
    start = rng.uniform(0.0, 0.7) * length  # the cone's first station
    ratio = _log_uniform(rng, 0.1, 10.0)
    x = [0.0] + list(np.linspace(start, length, 9)[0 if start > 0 else 1 :])
    diameter = np.sqrt(ratio) ** ((np.maximum(np.array(x) - start, 0.0)) / (length - start))
    return {"profile": {"x": [float(v) for v in x], "area": [float(area * d * d) for d in diameter]}}


def _contact_stiffness(m1: float, w1: float, alpha: float, tangent: float) -> float:
    """c1 whose tangent stiffness `(1+α)·c1·δ^α` at the rigid-wall depth is `tangent`."""
    # depth = ((α+2)·m1·W1²/(2·c1))^(1/(α+2)), so the tangent stiffness is a power of c1
    power = 1.0 - alpha / (alpha + 2.0)
    scale = (1.0 + alpha) * ((alpha + 2.0) * m1 * w1 * w1 / 2.0) ** (alpha / (alpha + 2.0))
    return (tangent / scale) ** (1.0 / power)


def draw_case(rng: np.random.Generator, index: int) -> dict:
    """One case of the matrix (see the module's docstring)."""
    m1 = _log_uniform(rng, 0.5, 200.0)
    w1 = _log_uniform(rng, 0.5, 20.0)
    length = _log_uniform(rng, 0.1, 3.0)
    diameter = _log_uniform(rng, 0.02, 0.15)
    area = math.pi * diameter * diameter / 4.0
    shape = ("uniform", "tapered", "stepped", "conical")[int(rng.integers(4))]
    tool = {"length": length, **STEEL, **_profile(rng, shape, length, area)}
    a = math.sqrt(STEEL["youngs_modulus"] / STEEL["density"])
    impedance = STEEL["density"] * a * area
    alpha = float(rng.choice([0.0, 0.5, rng.uniform(0.0, 0.5)]))
    zeta = _log_uniform(rng, 0.03, 30.0)
    tangent = (2.0 * zeta * impedance) ** 2 / m1
    c1 = _contact_stiffness(m1, w1, alpha, tangent)
    contact = {"stiffness": c1, "exponent": alpha}
    if rng.uniform() < 0.5:
        contact["tension_stiffness"] = tangent * _log_uniform(rng, 1e-5, 1e-2)
    if rng.uniform() < 0.6:
        contact["damping"] = 2.0 * rng.uniform(0.0, 3.0) * math.sqrt(tangent * m1)
    case = {"name": f"matrix-{index}", "striker": {"mass": m1, "velocity": w1}, "tool": tool, "contact": contact}
    end_stiffness = STEEL["youngs_modulus"] * area / length
    medium = ("none", "soft", "stiff")[int(rng.integers(3))]
    if medium != "none":
        factor = _log_uniform(rng, 1e-3, 1e-1) if medium == "soft" else _log_uniform(rng, 1.0, 100.0)
        case["medium"] = {"stiffness": end_stiffness * factor}
        if rng.uniform() < 0.7:
            case["medium"]["damping"] = rng.uniform(0.0, 3.0) * impedance
    parsed = parse_case({**case, "numerics": {"duration": 1.0}})
    contact_time = contact_time_estimate(parsed)
    span = max(contact_time, 2.0 * length / a)
    duration = span * _log_uniform(rng, 1.2, 20.0)
    force = ("none", "sine", "abs_sine", "pulse")[int(rng.integers(4))]
    if force != "none":
        # up to a few times the impact's momentum over the run
        amplitude = m1 * w1 / duration * _log_uniform(rng, 0.1, 5.0) * float(rng.choice([-1.0, 1.0]))
        if force == "pulse":
            start = rng.uniform(0.0, 0.6) * duration
            case["force"] = {
                "kind": "pulse",
                "amplitude": amplitude,
                "start": start,
                "duration": rng.uniform(0.05, 0.5) * duration,
            }
        else:
            case["force"] = {
                "kind": force,
                "amplitude": amplitude,
                "omega": 2.0 * math.pi / duration * _log_uniform(rng, 0.3, 5.0),
            }
    case["numerics"] = {"duration": duration}
    return case


def draw_cases(seed: int, count: int) -> list[dict]:
    """`count` cases drawn from `seed` (the same on every machine)."""
    rng = np.random.default_rng(seed)
    return [draw_case(rng, k) for k in range(count)]


def reference_cells(case: Case, points_per_contact: int = 20, fewest: int = 200, most: int = 2000) -> int:
    """The first grid of a reference: the rigid-wall contact time resolved by `points_per_contact`
    steps, within `fewest`–`most` cells (the ends' substeps resolve a contact that is shorter)."""
    a = wave_speed(case.tool)
    tau = contact_time_estimate(case) / points_per_contact
    return min(most, max(fewest, math.ceil(case.tool.length / (a * tau))))


def reference_left_out(case: Case, reference: Reference) -> dict[str, str]:
    """The headline quantities the reference has no meaningful relative error for."""
    return left_out(
        reference.headline(),
        case.impact_velocity,
        reference.initial + max(reference.external_work, 0.0),
        case.medium is not None,
        reference.contact_fade_time,
    )


def extrapolate(coarse: float, middle: float, fine: float) -> float:
    """Richardson's extrapolation of three grids each twice as fine as the last, at the order they
    show (clipped to 1–4); the finest value where they do not converge monotonically."""
    d1, d2 = middle - coarse, fine - middle
    if d2 == 0.0 or d1 == 0.0 or (d1 > 0) != (d2 > 0) or abs(d2) >= abs(d1):
        return fine
    order = min(4.0, max(1.0, math.log2(d1 / d2)))
    return fine + d2 / (2.0**order - 1.0)


@dataclass
class ConvergedReference:
    """A case's reference values (headline quantities under their dotted names, the meaningful
    ones only), each with its uncertainty relative to it, and the runs they come from."""

    values: dict[str, float]
    uncertainty: dict[str, float]
    left_out: dict[str, str]
    finest: Reference
    cells: list[int]


def converged_reference(case: Case, target: float = 1e-5, max_cells: int = 200_000) -> ConvergedReference:
    """The characteristics solution on grids doubled until, for every headline quantity with a
    meaningful relative error, the extrapolations (`extrapolate`) of the last two triplets of grids
    agree within `target` of the value; or until `max_cells`. The value is the last extrapolation,
    its uncertainty the two extrapolations' difference (or, where the grids do not converge
    monotonically, the finest grids' difference)."""
    cells = [reference_cells(case)]
    runs = [solve(case, cells[0])]
    while True:
        cells.append(2 * cells[-1])
        runs.append(solve(case, cells[-1]))
        skip = reference_left_out(case, runs[-1])
        values, uncertainty = {}, {}
        for name, fine in runs[-1].headline().items():
            if name in skip or fine is None:
                continue
            series = [r.headline()[name] for r in runs]
            if any(v is None for v in series[-4:]) or len(series) < 4:
                values[name], uncertainty[name] = fine, math.inf
                continue
            last = extrapolate(*series[-3:])
            before = extrapolate(*series[-4:-1])
            values[name] = last
            uncertainty[name] = abs(last - before) / abs(last) if last else math.inf
        if (uncertainty and max(uncertainty.values()) <= target) or 2 * cells[-1] > max_cells:
            return ConvergedReference(values, uncertainty, skip, runs[-1], cells)
