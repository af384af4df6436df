"""Where a run under gravity starts: the tool and the anvil at rest on the soil under their weight.

The static problem on the run's own grid, so that the kernel's first steps find every node in
balance: each interior node i carries its weight W_i (`grid.node_weights`) against the cells on
either side, `S·E/h` each, and its shaft's soil (elastic at k_i up to ±r_i, then slipping); the
struck end carries the anvil's weight through its contact, the working end rests on the medium
(elastic, or Smith soil up to R_u). The soil that slips is what makes the problem nonlinear: its
force is then known (r_i, R_u), so the elastic–plastic balance is a linear tridiagonal solve for
each guess of which soil slips, repeated until the guess holds (it grows monotonically with the
load, as the weight is applied once). `Case._gravity_supported` refuses a tool the soil cannot
carry, so the repetition ends.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .case import Case
from .grid import Grid, node_weights, shaft_nodes

MAX_GUESSES = 200  # of which soil slips; each adds at least one node that slips


@dataclass(frozen=True)
class Rest:
    """The tool and the anvil at rest under gravity: the tool's displacements `u` (m, along its
    grid), each shaft node's set (m, its permanent displacement against its soil), the medium's
    force (N) and state (the kernel's `medium_state`: set, deepest, surface, spent), and the
    anvil's displacement, its contact's overlap (m) and force (N: its weight). The kernel counts
    the energy this state stores (`start_impact`)."""

    u: np.ndarray
    shaft_sets: np.ndarray
    medium_force: float
    medium_state: tuple[float, float, float, float]
    anvil_displacement: float
    anvil_overlap: float
    anvil_force: float


@dataclass(frozen=True)
class Soil:
    """The soil a static problem sees on the run's grid: each node's shaft resistance r_i (N) and
    stiffness k_i (N/m), and the toe's stiffness (N/m) and resistance (N, inf: no cap)."""

    resistance: np.ndarray
    stiffness: np.ndarray
    toe_stiffness: float
    toe_cap: float

    @classmethod
    def of(cls, case: Case, grid: Grid) -> Soil:
        resistance, stiffness, _ = shaft_nodes(case.shaft or [], grid)
        medium = case.medium
        return cls(
            resistance=resistance,
            stiffness=stiffness,
            toe_stiffness=medium.loading_stiffness if medium is not None else 0.0,
            toe_cap=medium.ultimate_resistance if medium is not None and medium.kind == "smith" else np.inf,
        )

    @property
    def capacity(self) -> float:
        """What the soil holds at most: every shaft node's resistance and the toe's."""
        return float(np.sum(self.resistance) + self.toe_cap)


def balance(grid: Grid, load: np.ndarray, soil: Soil) -> tuple[np.ndarray, np.ndarray, bool] | None:
    """The tool's displacements under the nodal `load` (N, toward the toe positive), loaded once
    from rest on `soil`: `(u, which shaft nodes slip, whether the toe slips)`, or None where the
    soil cannot hold it (everything slips and the tool moves off)."""
    from scipy.linalg import solve_banded  # where a tool rests on soil: not in the API, as in calibrate

    n = grid.cells
    cell = grid.youngs_modulus * grid.area_mid / grid.h  # S·E/h of each cell
    slipping = np.zeros(n + 1, bool)
    toe_slips = False
    for _ in range(MAX_GUESSES):
        bands = np.zeros((3, n + 1))  # solve_banded's: upper, diagonal, lower
        bands[1, :-1] += cell
        bands[1, 1:] += cell
        bands[0, 1:] = -cell
        bands[2, :-1] = -cell
        held = load - np.where(slipping, soil.resistance, 0.0)
        bands[1] += np.where(slipping, 0.0, soil.stiffness)
        if toe_slips:
            held[n] -= soil.toe_cap
        else:
            bands[1, n] += soil.toe_stiffness
        springs = np.sum(np.where(slipping, 0.0, soil.stiffness)) + (0.0 if toe_slips else soil.toe_stiffness)
        if springs <= 0.0:
            return None  # every spring slips: nothing holds the tool in place
        u = solve_banded((1, 1), bands, held)
        now_slipping = slipping | ((soil.stiffness * u > soil.resistance) & (soil.resistance > 0))
        now_toe = toe_slips or soil.toe_stiffness * u[n] > soil.toe_cap
        if np.array_equal(now_slipping, slipping) and now_toe == toe_slips:
            return u, slipping, toe_slips
        slipping, toe_slips = now_slipping, now_toe
    return None


def at_rest(case: Case, grid: Grid) -> Rest:
    """The static equilibrium the case's run starts from (the case has `gravity`)."""
    g = case.gravity.acceleration
    n = grid.cells
    soil = Soil.of(case, grid)
    resistance, stiffness, toe_stiffness, toe_cap = soil.resistance, soil.stiffness, soil.toe_stiffness, soil.toe_cap
    anvil_weight = case.anvil.mass * g if case.anvil else 0.0
    medium = case.medium
    load = node_weights(grid, g)
    load[0] += anvil_weight
    u, slipping, toe_slips = balance(grid, load, soil)  # `Case._gravity_supported`: the soil holds it
    quakes = np.divide(resistance, stiffness, out=np.zeros(n + 1), where=stiffness > 0)
    medium_state = (u[n] - toe_cap / toe_stiffness if toe_slips else 0.0, 0.0, 0.0, 0.0)
    if medium is not None and medium.kind == "bilinear":  # loaded once from its surface
        medium_state = (u[n] * (1.0 - toe_stiffness / medium.unloading_stiffness), u[n], 0.0, 0.0)
    overlap = 0.0
    if case.anvil is not None:
        c = case.anvil.contact
        overlap = (anvil_weight / c.stiffness) ** (1.0 / (c.exponent + 1.0))  # Φ'(δ) = c1·δ^(α+1)
    return Rest(
        u=u,
        shaft_sets=np.where(slipping, u - quakes, 0.0),
        medium_force=float(toe_cap if toe_slips else toe_stiffness * u[n]),
        medium_state=tuple(float(v) for v in medium_state),
        anvil_displacement=float(u[0] + overlap),
        anvil_overlap=float(overlap),
        anvil_force=anvil_weight,
    )


LOAD_TEST_POINTS = 40  # loads of a static load test, evenly up to the soil's capacity
LAST_LOAD = 1.0 - 1e-6  # of the capacity: the last load, where one spring still holds the rest


def static_load_test(case: Case, grid: Grid, points: int = LOAD_TEST_POINTS) -> dict:
    """A static load test of the case's pile on its soil (shaft and a Smith toe, loaded once from
    rest; the tool's weight left out): the head's settlement (m) under loads (N) evenly up to the
    soil's capacity, Σr_i + R_u, which plunges it. `{"load": [...], "settlement": [...]}`, from 0."""
    soil = Soil.of(case, grid)
    loads, settlements = [0.0], [0.0]
    for k in range(1, points + 1):
        load = np.zeros(grid.cells + 1)
        load[0] = soil.capacity * min(k / points, LAST_LOAD)
        held = balance(grid, load, soil)
        if held is None:
            break
        loads.append(float(load[0]))
        settlements.append(float(held[0][0]))
    return {"load": loads, "settlement": settlements}
