"""One-dimensional impacts with closed forms: the cases and the formulas that the tests
(test_striker_rod.py, test_media.py, test_blows.py, test_measured_records.py) and the validation report
(bench/validation.py) hold the solver to. docs/model.md derives each formula.

A steel piston of length L_s at v strikes a steel tool of length L through a stiff linear contact.
The piston's impedance is r times the tool's Z = ρ·a·S (its area r·S); T = 2·L_s/a is its wave's
round trip. The force at the struck end is `F_1 = Z_s·Z·v/(Z_s + Z) = r·Z·v/(1 + r)` while that
wave runs, then `R = (r − 1)/(r + 1)` times the step before, every T (r < 1: it separates, having
passed `4r/(1 + r)²` of its energy, and leaves at `R·v`). With r = 1 the tool carries a rectangular
wave `F_i = Z·v/2` lasting T to its working end, where bilinear rock takes Lundberg's share and
Smith's soil sets as `smith_set` says.

An anvil (a lumped body between a lumped striker and the tool, `anvil_case`): the two bodies of a
short stiff contact part as two-body impact says (`two_body_impact`); with linear contacts on a tool
whose far end sends nothing back, striker, anvil and struck end are a linear system whose matrix
exponential gives the forces (`linear_three_bodies`).

A split Hopkinson bar (`Hopkinson`): a uniform striker on a uniform bar through a contact spring,
by d'Alembert (`rods_through_a_spring`), and the record a recorder triggered by the pulse writes.

Plain Python, NumPy and SciPy: no test framework, no solver.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
from scipy.linalg import expm

from percussim.solver.drive import Hydraulics, Valve

from .reference import LundbergRock

STEEL = {"youngs_modulus": 2.1e11, "density": 7800.0}
V = 10.0  # m/s, the piston at impact
AREA = 1e-3  # m², the tool's (and a piston of r = 1)
SPEED = math.sqrt(STEEL["youngs_modulus"] / STEEL["density"])
Z = STEEL["density"] * SPEED * AREA  # the tool's impedance, N·s/m
PISTON, TOOL = 0.2, 1.0  # m
PISTON_MASS = STEEL["density"] * AREA * PISTON  # kg, the equal piston's
T = 2.0 * PISTON / SPEED  # the piston's wave there and back
INCIDENT = Z * V / 2.0  # F_i: the wave an equal piston sends into the tool

# The piston alone: past its pulse (T = 77 µs), before the tool's far end sends anything back (5T)
PISTON_DURATION = 1.5e-4
PISTON_FINE = {"scheme": "explicit", "cells": 2000}
STEPPED_DURATION = 3.2 * T  # a higher-impedance piston's first three steps, before 2L/a
# On a medium: past the wave's passage (L/a + T = 1.4·L/a), and short of the instant (2L/a + L_s/a)
# the wave the free struck end reflects meets, at x = L_s, the peak of the medium's reflection: a
# stress peak at the run's end would be in one grid's run and not in the next one's
MEDIUM_DURATION = 2.1 * TOOL / SPEED
MEDIUM_FINE = {"scheme": "explicit", "cells": 1000}
UNLOADING = 10.0  # rock's k_u/k
OPTIMUM = 1.2564  # x = k·T/Z where Lundberg's η is largest
# Smith soil that flows under the wave (R_u < 2F_i), elastic at 5·Z/T below R_u
SOIL_RESISTANCE = 1.2 * INCIDENT
SOIL_STIFFNESS = 5.0 * Z / T
# Blow after blow: each blow of 10·L/a (the tool's waves die down between blows)
BLOW_DURATION = 10 * TOOL / SPEED
BLOW_NUMERICS = {"scheme": "explicit", "cells": 500}


def piston_case(ratio: float, numerics: dict | None = None, **changes) -> dict:
    """A piston of `ratio` times the tool's impedance on the tool, no medium, recorded every step."""
    return {
        "striker": {"velocity": V, "length": PISTON, "area": ratio * AREA, **STEEL},
        "tool": {"length": TOOL, "area": AREA, **STEEL},
        "contact": {"stiffness": 1e13, "exponent": 0.0},
        "numerics": {"duration": PISTON_DURATION, **(numerics or {})},
        "outputs": {"history_stride": 1},
        **changes,
    }


def matched_tool_case(ratio: float) -> dict:
    """A piston of `ratio` on the tool whose far end is a dashpot of its impedance Z (nothing
    reflects), run until the piston's first pulse has passed it (L/a + T): the medium receives
    `passed_share(ratio)` of the piston's energy, largest at r = 1. A linear contact of 1e11 N/m."""
    return piston_case(
        ratio,
        {"duration": TOOL / SPEED + T},
        contact={"stiffness": 1e11, "exponent": 0.0},
        medium={"stiffness": 1.0, "damping": Z},
    )


def stepped_piston_case(cells: int) -> dict:
    """An equal piston whose back half has twice the area, on `cells` of the explicit scheme: with
    2000 its length is a whole number of its cells, with 2003 not (a delay at its free end)."""
    profile = {"x": [0.0, PISTON / 2, PISTON / 2 + 1e-9, PISTON], "area": [AREA, AREA, 2 * AREA, 2 * AREA]}
    return piston_case(
        1.0,
        {"scheme": "explicit", "cells": cells},
        striker={"velocity": V, "length": PISTON, "profile": profile, **STEEL},
    )


def rock_case(x: float, numerics: dict, **medium) -> dict:
    """The equal piston's wave on bilinear rock of `x` = k·T/Z, unloading at `UNLOADING`·k."""
    k = rock_stiffness(x)
    return piston_case(
        1.0,
        {"duration": MEDIUM_DURATION, **numerics},
        medium={"kind": "bilinear", "stiffness": k, "unloading_stiffness": UNLOADING * k, **medium},
    )


def soil_case(
    numerics: dict,
    resistance: float = SOIL_RESISTANCE,
    quake: float = SOIL_RESISTANCE / SOIL_STIFFNESS,
    damping_factor: float = 0.0,
) -> dict:
    """The equal piston's wave on Smith soil (R_u, q, J)."""
    case = rock_case(1.0, numerics)
    case["medium"] = {
        "kind": "smith",
        "ultimate_resistance": resistance,
        "quake": quake,
        "damping_factor": damping_factor,
    }
    return case


def rectangular_force_case(
    numerics: dict | None = None,
    resistance: float = SOIL_RESISTANCE,
    quake: float = SOIL_RESISTANCE / SOIL_STIFFNESS,
    drive: str = "force",
) -> dict:
    """The equal piston's wave without the piston: the tool's struck end driven (`struck_end`) by
    the force F_i lasting T (or by its velocity F_i/Z), on undamped Smith soil (R_u, q). After T
    the end is free, so the toe's reflection, compression for R_u ≥ F_i, returns as tension and
    sets the toe no deeper: the set is `smith_set`'s."""
    value = INCIDENT if drive == "force" else INCIDENT / Z
    case = soil_case(numerics or {}, resistance, quake)
    del case["striker"], case["contact"]
    case["struck_end"] = {drive: {"time": [0.0, T], "values": [value, value]}}
    return case


def drilling(blows: int, numerics: dict | None = None) -> dict:
    """`blows` blows of the equal piston on rock at Lundberg's optimum (`BLOW_NUMERICS` unless
    `numerics` says otherwise), no recordings."""
    case = rock_case(OPTIMUM, {"duration": BLOW_DURATION, **(numerics or BLOW_NUMERICS)})
    case.pop("outputs")
    return {**case, "blows": {"count": blows}}


# --- the piston: one-dimensional impact ----------------------------------------------------------


def first_force(ratio: float) -> float:
    """F_1 = Z_s·Z·v/(Z_s + Z): the two impedances in series while the piston's wave runs."""
    return ratio * Z * Z * V / (ratio * Z + Z)


def reflection(ratio: float) -> float:
    """R = (Z_s − Z)/(Z_s + Z): what each return of the piston's wave leaves of the force."""
    return (ratio - 1.0) / (ratio + 1.0)


def passed_share(ratio: float) -> float:
    """The share of its energy a piston of lower impedance passes before it separates."""
    return 4.0 * ratio / (1.0 + ratio) ** 2


def piston_force(ratio: float, t: float) -> float:
    """The contact force at t (before the tool's far end sends anything back, t < 2L/a): F_1 on
    [0, T), then R times the step before on each T; 0 once a lower-impedance piston has left."""
    step = math.floor(t / T)
    if ratio <= 1.0 and step >= 1:
        return 0.0
    return first_force(ratio) * reflection(ratio) ** step


# --- media that yield at the working end ---------------------------------------------------------


def rock_stiffness(x: float) -> float:
    """k with k·T/Z = x."""
    return x * Z / T


def lundberg_rock(x: float, unloading: float = UNLOADING) -> LundbergRock:
    """Lundberg's rock (`reference.LundbergRock`) at x = k·T/Z under the piston's wave F_i."""
    return LundbergRock(INCIDENT, T, Z, rock_stiffness(x), unloading * rock_stiffness(x))


def lundberg(x: float, unloading: float = UNLOADING) -> float:
    """Lundberg's η = 2(1 − e^(−x))²/x·(1 − k/k_u): the share of the wave's energy rock keeps."""
    return lundberg_rock(x, unloading).efficiency


def lundberg_optimum() -> tuple[float, float]:
    """(x, η) where η is largest for k_u → ∞: dη/dx = 0 is e^x = 1 + 2x, where η = 8x/(1 + 2x)²."""
    x = 1.0
    for _ in range(50):  # Newton on e^x − 1 − 2x, convex, from the right of its root
        x -= (math.exp(x) - 1.0 - 2.0 * x) / (math.exp(x) - 2.0)
    return x, 8.0 * x / (1.0 + 2.0 * x) ** 2


def rock_penetration(x: float, unloading: float = UNLOADING) -> tuple[float, float]:
    """(deepest, permanent): F_max/k with F_max = 2F_i(1 − e^(−x)), and (1 − k/k_u) of it."""
    rock = lundberg_rock(x, unloading)
    return rock.max_penetration, rock.permanent_penetration


def smith_set(resistance: float = SOIL_RESISTANCE, stiffness: float = SOIL_STIFFNESS) -> tuple[float, float]:
    """(t_q, set) of undamped Smith soil under the rectangular wave F_i lasting T: elastic until
    `t_q = −(Z/k)·ln(1 − R_u/(2F_i))`, then flowing at `(2F_i − R_u)/Z` until T; refusal (no set,
    t_q = ∞) when R_u ≥ 2F_i."""
    if resistance >= 2.0 * INCIDENT:
        return math.inf, 0.0
    t_q = -(Z / stiffness) * math.log(1.0 - resistance / (2.0 * INCIDENT))
    return t_q, (2.0 * INCIDENT - resistance) * max(T - t_q, 0.0) / Z


# --- the anvil --------------------------------------------------------------------------------

ANVIL_DURATION = 1e-3


def anvil_case(
    mass: float,
    numerics: dict,
    *,
    anvil_contact: dict,
    striker_mass: float = 2.0,
    contact: dict | None = None,
    **changes,
) -> dict:
    """A lumped striker at V on an anvil of `mass` resting on the tool (a linear medium behind
    it), each history row recorded."""
    return {
        "striker": {"mass": striker_mass, "velocity": V},
        "anvil": {"mass": mass, "contact": anvil_contact},
        "tool": {"length": TOOL, "area": AREA, **STEEL},
        "contact": contact or {"stiffness": 2e9, "exponent": 0.0},
        "medium": {"stiffness": 5e7},
        "numerics": {"duration": ANVIL_DURATION, **numerics},
        "outputs": {"history_stride": 1},
        **changes,
    }


def two_body_impact(striker_mass: float, anvil_mass: float, stiffness: float) -> tuple[float, float, float]:
    """(v1', v_a', contact time) of a striker at V on a free anvil at rest through a linear
    contact: `(m1 − m_a)/(m1 + m_a)·V`, `2·m1/(m1 + m_a)·V`, `π·sqrt(μ/k)`."""
    total = striker_mass + anvil_mass
    reduced = striker_mass * anvil_mass / total
    return (
        (striker_mass - anvil_mass) / total * V,
        2.0 * striker_mass / total * V,
        math.pi * math.sqrt(reduced / stiffness),
    )


def linear_three_bodies(m1: float, ma: float, k1: float, k2: float, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(F1, F2) from rest at impact of `m1·y'' = −k1·(y − y_a)`, `m_a·y_a'' = k1·(y − y_a) −
    k2·(y_a − u_0)`, `Z·u_0' = k2·(y_a − u_0)` (the tool's end as a dashpot of its impedance),
    valid while both contacts are closed and nothing returns from the tool's far end."""
    a = np.zeros((5, 5))  # state (y, w, y_a, w_a, u_0)
    a[0, 1] = 1.0
    a[1, 0], a[1, 2] = -k1 / m1, k1 / m1
    a[2, 3] = 1.0
    a[3, 0], a[3, 2], a[3, 4] = k1 / ma, -(k1 + k2) / ma, k2 / ma
    a[4, 2], a[4, 4] = k2 / Z, -k2 / Z
    x0 = np.array([0.0, V, 0.0, 0.0, 0.0])
    states = np.array([expm(a * t) @ x0 for t in times])
    return k1 * (states[:, 0] - states[:, 2]), k2 * (states[:, 2] - states[:, 4])


def rods_through_a_spring(
    velocity: float,
    striker_transit: float,
    striker_impedance: float,
    impedance: float,
    stiffness: float,
    times: np.ndarray,
) -> np.ndarray:
    """The force (compression +) at the struck end of a uniform tool hit by a uniform elastic
    striker through a linear contact spring `k` with no tension, by d'Alembert: the striker's
    face sends back the wave `f = F − g` and gets, from its free back end 2·L_s/a_s later,
    `g(t) = −f(t − 2·L_s/a_s)`; the face moves at `V − (F − 2g)/Z_s`, the tool's end at `F/Z`,
    and `δ' = V − F/Z_s + 2g/Z_s − F/Z`, `F = k·max(δ, 0)`: a delay equation, integrated by
    classical Runge–Kutta at 1/4000 of the striker's round trip. Valid at `times` until the
    tool's far end sends something back (2L/a)."""
    round_trip = 2.0 * striker_transit
    dt = round_trip / 4000.0
    steps = int(math.ceil(times[-1] / dt)) + 1
    grid = np.arange(steps + 1) * dt
    force, sent = np.zeros(steps + 1), np.zeros(steps + 1)  # F and f on the grid

    def returning(t: float) -> float:  # g(t), from what the face sent a round trip before
        return -float(np.interp(t - round_trip, grid, sent, left=0.0)) if t >= round_trip else 0.0

    def rate(t: float, delta: float) -> float:
        f_contact = stiffness * max(delta, 0.0)
        return velocity - f_contact / striker_impedance + 2.0 * returning(t) / striker_impedance - f_contact / impedance

    delta = 0.0
    for k in range(steps):
        t = grid[k]
        k1 = rate(t, delta)
        k2 = rate(t + dt / 2, delta + dt / 2 * k1)
        k3 = rate(t + dt / 2, delta + dt / 2 * k2)
        k4 = rate(t + dt, delta + dt * k3)
        delta += dt / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4)
        force[k + 1] = stiffness * max(delta, 0.0)
        sent[k + 1] = force[k + 1] - returning(grid[k + 1])
    return np.interp(times, grid, force)


class Hopkinson:
    """The incident bar of a split Hopkinson bar: steel, Ø20 mm, 2.1 m, a strain gauge 1.082 m
    from the struck end, and a striker of the bar's own section at 5 m/s: a pulse of ρ·c·v/2 =
    101.5 MPa lasting 2·L_s/c = 236 µs, its front rising over 20 µs (10–90%) through a contact
    spring. The record a recorder triggered by the pulse writes: 12.5 MHz from where the stress
    reaches 10% of its plateau, for 340 µs (before the bar's far end sends anything back)."""

    E, RHO = 2.1e11, 7850.0
    AREA = math.pi * 0.010**2
    C = math.sqrt(E / RHO)
    Z = RHO * C * AREA
    BAR, GAUGE = 2.1, 1.082  # m
    VELOCITY, STRIKER = 5.0, 0.61  # m/s, m
    RISE = 20e-6  # s, 10–90% of the front: the contact's time constant Z/(2k) times ln 9
    STIFFNESS = (Z / 2.0) / (RISE / math.log(9.0))
    RATE = 12.5e6  # Hz
    TRIGGER = 0.10  # of the plateau: where the recorder starts
    SPAN = 340e-6  # s of record
    NOISE = 0.01  # of the plateau

    @classmethod
    def case(cls, velocity: float = VELOCITY, length: float = STRIKER, stiffness: float = STIFFNESS) -> dict:
        rod = {"youngs_modulus": cls.E, "density": cls.RHO, "area": cls.AREA}
        return {
            "name": "shpb",
            "striker": {"velocity": velocity, "length": length, **rod},
            "tool": {"length": cls.BAR, **rod},
            "contact": {"stiffness": stiffness, "exponent": 0.0},
            "numerics": {"duration": 6.5e-4},
        }

    @classmethod
    def gauge_stress(cls, times: np.ndarray) -> np.ndarray:
        """The stress at the gauge (compression negative) at the model's `times`: the struck end's
        force x/c earlier, until the bar's far end sends its reflection back, at (2L − x)/c."""
        assert times[-1] < (2.0 * cls.BAR - cls.GAUGE) / cls.C
        force = rods_through_a_spring(
            cls.VELOCITY, cls.STRIKER / cls.C, cls.Z, cls.Z, cls.STIFFNESS, np.maximum(times - cls.GAUGE / cls.C, 0.0)
        )
        return -force / cls.AREA

    @classmethod
    def triggered_record(cls, seed: int = 0, digits: int = 3) -> tuple[str, float]:
        """The record as CSV, its time column rounded to `digits` significant digits, from the
        trigger; and the true time_offset (the trigger's instant after the impact)."""
        fine = np.arange(0.0, 3e-4, 1e-8)
        trigger = fine[np.argmax(cls.gauge_stress(fine) <= -cls.TRIGGER * cls.RHO * cls.C * cls.VELOCITY / 2.0)]
        times = trigger + np.arange(0.0, cls.SPAN, 1.0 / cls.RATE)
        values = cls.gauge_stress(times)
        values = values + cls.NOISE * np.abs(values).max() * np.random.default_rng(seed).standard_normal(len(times))
        lines = [f"time,stress@{cls.GAUGE}"] + [f"{t:.{digits}g},{v:.6g}" for t, v in zip(times - trigger, values)]
        return "\n".join(lines) + "\n", float(trigger)

    @classmethod
    def half_width_excess(cls) -> float:
        """How much longer than 2·L_s/c the pulse's half-amplitude width is (s). The contact spring
        (time constant τ = Z/(2k)) loads as 1 − e^(−s/τ), half at τ·ln 2; after the striker's round
        trip it unloads as (1 + s/τ)·e^(−s/τ) (from `rods_through_a_spring`'s equation), half at
        τ·1.6783: the width is 2·L_s/c + τ·(1.6783 − ln 2)."""
        from scipy.optimize import brentq

        tau = (cls.Z / 2.0) / cls.STIFFNESS
        return tau * (brentq(lambda x: (1.0 + x) * math.exp(-x) - 0.5, 0.5, 5.0) - math.log(2.0))

    @classmethod
    def reading(cls, times: np.ndarray, stress) -> dict[str, float]:
        """The wave theory's reading of an incident pulse: v = 2|σ|/(ρc) from the plateau (the
        median of the middle half between the half-amplitude crossings); L_s = c·T/2 from the
        half-amplitude width T (crossings interpolated linearly), and from the impulse's width
        ∫|σ|dt/|σ_plateau| (which is 2·L_s/c only when the striker is left at rest)."""
        t, s = np.asarray(times), -np.asarray(stress)
        rough = np.median(s[s > 0.5 * s.max()])
        above = np.flatnonzero(s >= 0.5 * rough)
        first, last = above[0], above[-1]
        plateau = float(np.median(s[first + (last - first) // 4 : last - (last - first) // 4]))
        rise = np.interp(0.5 * plateau, s[first - 1 : first + 1], t[first - 1 : first + 1])
        fall = np.interp(0.5 * plateau, s[last : last + 2][::-1], t[last : last + 2][::-1])
        impulse = float(np.sum(s) * (t[1] - t[0]))
        return {
            "velocity": 2.0 * plateau / (cls.RHO * cls.C),
            "half_width_length": cls.C * (fall - rise) / 2.0,
            "impulse_length": cls.C * impulse / plateau / 2.0,
        }


# --- Soil along the tool's side (`shaft`) -------------------------------------------------------


def shaft_rigid_mode(stiffness_per_length: float, density: float, area: float) -> float:
    """ω0 = √(k′/(ρA)) (rad/s): a free uniform rod on elastic shaft springs of k′ (N/m per m).
    Its mass-weighted mean displacement obeys ρAL·Ü = −k′L·U once nothing else acts on it, so it
    rings at ω0 whatever its elastic waves do."""
    return math.sqrt(stiffness_per_length / (density * area))


def free_pile_on_springs(frequency_hz: float = 50.0, cells: int = 50) -> dict:
    """A 10-m steel rod, free at its toe, on shaft springs that ring its rigid mode at
    `frequency_hz`, struck by a 10-kg ram at 5 m/s: the springs (quake 2.5 mm) never yield."""
    area, density, length, quake = 0.01, 7850.0, 10.0, 0.0025
    stiffness_per_length = (2.0 * math.pi * frequency_hz) ** 2 * density * area
    return {
        "name": "free pile on shaft springs",
        "striker": {"mass": 10.0, "velocity": 5.0},
        "tool": {"length": length, "youngs_modulus": 2.1e11, "density": density, "area": area},
        "contact": {"stiffness": 1e8, "exponent": 0.0},
        "shaft": [
            {
                "from": 0.0,
                "to": length,
                "ultimate_resistance": stiffness_per_length * length * quake,
                "quake": quake,
                "damping_factor": 0.0,
            }
        ],
        "numerics": {"duration": 0.05, "scheme": "explicit", "cells": cells},
        "outputs": {"fields": True, "field_stride": 1},
    }


# --- Gravity (`gravity`) ----------------------------------------------------------------------------


def pile_under_its_weight(cells: int = 200, anvil: bool = False) -> dict:
    """A 20-m steel pile (0.01 m², free at its head) on elastic shaft springs along its whole length
    and an elastic Smith toe (neither yields under its weight), vertical (g = 9.81), struck by a
    ram too light to move it (1 mg at 1 mm/s): it stays at rest. `anvil`: with a 500-kg helmet on a
    linear cushion."""
    case = {
        "name": "pile under its own weight",
        "striker": {"mass": 1e-6, "velocity": 1e-3},
        "tool": {"length": 20.0, "youngs_modulus": 2.1e11, "density": 7850.0, "area": 0.01},
        "contact": {"stiffness": 1e8, "exponent": 0.0},
        "medium": {"kind": "smith", "ultimate_resistance": 2e6, "quake": 0.0025, "damping_factor": 0.5},
        "shaft": [{"from": 0.0, "to": 20.0, "ultimate_resistance": 4e6, "quake": 0.0025, "damping_factor": 0.2}],
        "gravity": {"acceleration": 9.81},
        "numerics": {"duration": 0.02, "scheme": "explicit", "cells": cells},
    }
    if anvil:
        case["anvil"] = {"mass": 500.0, "contact": {"stiffness": 2e9, "exponent": 0.0}}
    return case


def driven_pile(numerics: dict | None = None) -> dict:
    """A 4-t ram at 4.43 m/s (a 1-m fall) on a cast-nylon cushion (5.89e9 N/m, e = 0.8) on a
    15-m steel pipe pile (0.0157 m²) with Smith soil on its shaft (153 kN from 3 to 9 m and 345 kN
    from 9 to 15 m, q = 2.54 mm, J = 0.16 s/m) and at its toe (1.245 MN, 2.54 mm, 0.492 s/m), no
    gravity: shaft and toe both yield, the soil's dampers act, and the cushion loses energy. The
    case `smith_model.smith_pile` takes."""
    return {
        "name": "driven pile",
        "striker": {"mass": 4000.0, "velocity": 4.4294},
        "tool": {"length": 15.0, "youngs_modulus": 2.1e11, "density": 7850.0, "area": 0.0157079},
        "contact": {"stiffness": 5.89e9, "exponent": 0.0, "restitution": 0.8},
        "medium": {"kind": "smith", "ultimate_resistance": 1.245e6, "quake": 2.54e-3, "damping_factor": 0.492},
        "shaft": [
            {"from": 3.0, "to": 9.0, "ultimate_resistance": 1.53e5, "quake": 2.54e-3, "damping_factor": 0.16},
            {"from": 9.0, "to": 15.0, "ultimate_resistance": 3.45e5, "quake": 2.54e-3, "damping_factor": 0.16},
        ],
        "numerics": numerics or {"duration": 0.03},
    }


def yielding_pile_under_gravity(**changes) -> dict:
    """`pile_under_its_weight` with its 500-kg helmet struck by a 4-t ram falling 1 m through a
    cushion (5.89e9 N/m, e = 0.8), on soil that yields: 0.3 MN of shaft from 5 to 12 m and 0.6 MN
    from 12 to 20 m (J = 0.16 s/m), a 0.6-MN toe (J = 0.5 s/m); blows of 40 ms. `changes` replace
    the case's fields."""
    case = pile_under_its_weight(anvil=True)
    case["striker"] = {"mass": 4000.0, "stroke": 1.0}
    case["contact"] = {"stiffness": 5.89e9, "exponent": 0.0, "restitution": 0.8}
    case["medium"] = {"kind": "smith", "ultimate_resistance": 6e5, "quake": 0.0025, "damping_factor": 0.5}
    case["shaft"] = [
        {"from": 5.0, "to": 12.0, "ultimate_resistance": 3e5, "quake": 0.0025, "damping_factor": 0.16},
        {"from": 12.0, "to": 20.0, "ultimate_resistance": 6e5, "quake": 0.0025, "damping_factor": 0.16},
    ]
    case["numerics"] = {"duration": 0.04}
    return case | changes


def static_compression(
    x: np.ndarray,
    *,
    length: float,
    stiffness: float,
    weight_per_length: float,
    shaft_stiffness_per_length: float,
    toe_stiffness: float,
    head_load: float = 0.0,
) -> np.ndarray:
    """u(x) (m) of a uniform rod (S·E = `stiffness`) at rest under its weight w (N/m) and a load P
    at its head, on shaft springs k′ (N/m per m) and a toe spring k_t:
    `S·E·u'' − k′·u + w = 0`, `S·E·u'(0) = −P`, `S·E·u'(L) = −k_t·u(L)`. With β = √(k′/(S·E)),
    `u = w/k′ + A·cosh βx + B·sinh βx`."""
    beta = math.sqrt(shaft_stiffness_per_length / stiffness)
    base = weight_per_length / shaft_stiffness_per_length
    b = -head_load / (stiffness * beta)
    bl = beta * length
    # S·E·β(A sinh βL + B cosh βL) = −k_t (base + A cosh βL + B sinh βL)
    a = -(toe_stiffness * (base + b * math.sinh(bl)) + stiffness * beta * b * math.cosh(bl)) / (
        stiffness * beta * math.sinh(bl) + toe_stiffness * math.cosh(bl)
    )
    return base + a * np.cosh(beta * x) + b * np.sinh(beta * x)


# --- A cushion (`contact.restitution`) ------------------------------------------------------------


def cushion_on_a_wall(restitution: float, exponent: float = 0.0, numerics: dict | None = None) -> dict:
    """A 100-kg ram at 2 m/s on a cushion against a near-rigid wall (a 1-m² tool 1000× stiffer
    than steel on a 1e14-N/m medium): the cushion alone sets the contact."""
    return {
        "name": f"cushion e = {restitution}",
        "striker": {"mass": 100.0, "velocity": 2.0},
        "tool": {"length": 1.0, "youngs_modulus": 2e14, "density": 7850.0, "area": 1.0},
        "contact": {"stiffness": 1e8 if exponent == 0.0 else 1e11, "exponent": exponent, "restitution": restitution},
        "medium": {"kind": "linear", "stiffness": 1e14},
        "numerics": numerics or {"duration": 0.01},
    }


def cushion_rebound(mass: float, stiffness: float, velocity: float, restitution: float) -> tuple[float, float]:
    """A linear cushion of stiffness k and restitution e struck by a mass m at v against a rigid
    wall: the rebound velocity −e·v and the contact time (π/2)·√(m/k)·(1 + e) (a quarter period
    loading at k, a quarter unloading at k/e²)."""
    return -restitution * velocity, 0.5 * math.pi * math.sqrt(mass / stiffness) * (1.0 + restitution)


# --- A hammer at work (`drive`, `cycles`) -----------------------------------------------------------


def hammer_at_work(**changes) -> dict:
    """A 2-kg striker at 8 m/s on a 1-m steel tool and rock, driven by ideal hydraulics (15 MPa,
    A_f = 1 cm², A_r = 3 cm², a 50-mm stroke: constant pressures, an instant valve, no friction)
    for 4 cycles of 2-ms blows on 50 cells. `changes` replace the case's fields (None removes one)."""
    case = {
        "striker": {"mass": 2.0, "velocity": 8.0},
        "tool": {"length": 1.0, "youngs_modulus": 2.1e11, "density": 7800.0, "area": 1e-3},
        "contact": {"stiffness": 1e9, "exponent": 0.0},
        "medium": {"kind": "bilinear", "stiffness": 5e7, "unloading_stiffness": 5e8},
        "drive": {"kind": "hydraulic", "supply_pressure": 15e6, "front_area": 1e-4, "rear_area": 3e-4, "stroke": 0.05},
        "cycles": {"count": 4},
        "numerics": {"duration": 0.002, "scheme": "explicit", "cells": 50},
    }
    return {key: value for key, value in (case | changes).items() if value is not None}


def lundberg_cycles(count: int = 4) -> dict:
    """The equal piston on Lundberg's rock at its optimum, each blow over `MEDIUM_DURATION` (its
    wave's first passage and the rock's reflection back to the struck end), driven `count` cycles
    by `hammer_at_work`'s ideal drive: every blow from a tool at rest gives the rock `lundberg(OPTIMUM)`
    of its energy, the piston stops dead, and the flight strikes from rest at √(2·p_s·A_r·s/m)."""
    case = rock_case(OPTIMUM, {"scheme": "explicit", "cells": 1000})
    case.pop("outputs")
    return case | {"drive": hammer_at_work()["drive"], "cycles": {"count": count}}


# The hammer's drive as `solver.drive.fly` takes it: ideal (constant pressures, an instant valve, no
# friction), and with every loss and store (a return line, a valve's time, friction, a pump and
# its accumulator, the striker's weight)
IDEAL_DRIVE = Hydraulics(
    mass=2.0, front_area=1e-4, rear_area=3e-4, supply_pressure=15e6, return_pressure=0.0, stroke=0.05
)
RETURNING = Valve(target=0.0, since=0.0, start=0.0)  # the rear on return from a flight's start
LOSSY_DRIVE = replace(
    IDEAL_DRIVE,
    return_pressure=5e5,
    valve_time=2e-3,
    friction=40.0,
    flow=1e-3,
    accumulator_volume=5e-4,
    precharge=8e6,
    weight=2.0 * 9.81,
)


def ideal_flight(drive, start: float, velocity: float, impact_point: float) -> tuple[float, float, float]:
    """`(t_back, t_in, v_impact)` of a flight under ideal hydraulics (`drive`, a
    `solver.drive.Hydraulics` with constant pressures, an instant valve, no friction): back from
    `start` at `velocity` (< 0) under (A_f·p_s − A_r·p_r)/m until `stroke` from the impact point,
    then in under (A_r − A_f)·p_s/m: v_i² = v² + 2·(F_b·D + F_w·s)/m."""
    back = (drive.front_area * drive.supply_pressure - drive.rear_area * drive.return_pressure) / drive.mass
    work = (drive.rear_area - drive.front_area) * drive.supply_pressure / drive.mass
    distance = start - (impact_point - drive.stroke)
    t_back = (velocity + math.sqrt(velocity**2 + 2 * back * distance)) / back
    v_switch = -math.sqrt(velocity**2 + 2 * back * distance)
    t_in = (-v_switch + math.sqrt(v_switch**2 + 2 * work * drive.stroke)) / work
    return t_back, t_in, math.sqrt(v_switch**2 + 2 * work * drive.stroke)


def blow_ends(result) -> list[tuple[float, float, float]]:
    """Where each blow of a hammer at work (a `Result` of `cycles`) left the striker and the tool,
    from its history: `(striker's displacement, its velocity, the struck end's displacement)` at
    each blow's last record before its flight, once the tool has come to rest on the medium at its
    permanent penetration (pushing back a striker it would overlap)."""
    cycle, h, grid = result.summary["cycle"], result.history, result.summary["runs"][-1]
    duration = grid["steps"] // len(cycle["impact_velocity"]) * grid["time_step"]  # a blow, in whole steps
    ends = [
        np.flatnonzero(h["time"] <= sum(cycle["cycle_time"][:k]) + duration * (1 + 1e-9))[-1]
        for k in range(len(cycle["cycle_time"]))
    ]
    rests = [h["medium/permanent_penetration"][end] for end in ends]
    return [
        (min(h["striker/displacement"][end], rest), h["striker/velocity"][end], rest) for end, rest in zip(ends, rests)
    ]


def supply_work_per_cycle(supply_pressure: float, rear_area: float, front_area: float, stroke: float, advance: float):
    """The ideal supply's work over a cycle, `p_s·(A_r·s − A_f·Δ)`: the rear fills on supply from
    the switch point, `stroke` back from the impact point, to the impact; the front, always on
    supply, gives back what the tool advanced (Δ, the blow's set)."""
    return supply_pressure * (rear_area * stroke - front_area * advance)
