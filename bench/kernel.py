"""The Numba kernel's cost per node-step against three other ways of computing the same run.

    .venv/bin/python bench/kernel.py [--repeat 7]

Cases: the Fig. 3 preset (uniform tool, paper scheme γ = 0.5, 100 cells, τ = 8.3e-7 s, 4820 steps),
the same case on 2000 cells (same τ, so the same steps), and the explicit scheme at Courant
number 1 on 100 and 2000 cells. A node-step is one node of the tool advanced one time step:
(cells + 1) × steps. Times are CPU times (`time.process_time`), the least over repeats after
compilation, the contenders of a case timed in alternation so that a busy machine slows them alike.

1. **Numba**: `solver.kernel.advance` called directly, as `simulate_rod` calls it, for the whole
   run in one call with a summary-only setup (extremes, energy, contact intervals; no history,
   probes or fields). The time of the whole `simulate_rod` call (the same run plus a history row a
   step, the summary, the setup) is printed beside it.
2. **C** (`bench/kernel_c/step.c`): the same step in C for a uniform tool without external force,
   compiled here with `gcc -O3 -march=native -shared -fPIC` into a temporary directory and called
   through `ctypes` with NumPy arrays. Written to the algorithm's limit: the tool rows eliminated
   once, so that a step is a vectorised pass for the right-hand sides, one sweep and one
   substitution with the precomputed factors (a fused multiply-add a node on the critical path of
   each, split as the kernel splits them into 4 segments swept as independent chains, with their
   carries; no recurrence at all for the explicit scheme, whose rows are summed as the kernel's,
   each node's increment kept apart) and the scalar contact solve; the energy
   sums and the stress extremes in one pass of 8 independent lanes, which vectorises. It computes
   what the summary needs (extremes, energy, contact intervals, in the kernel's slots) and is
   checked against Numba: co-impact time and energy terms should agree to about 1e-9; the peak
   force and the stress extremes differ by the size of a step's change, as the kernel records the
   force the scheme applies (centred on a layer) and refines the ends' extremes between layers,
   where the yardstick keeps the layers'.
3. **solve_banded**: the same scheme in NumPy/SciPy, a Python loop over steps. The tool's rows
   form a constant tridiagonal matrix (assembled once); each step assembles the right-hand side
   with array operations and calls `scipy.linalg.solve_banded` (LAPACK gbsv: a banded LU and a
   solve); the contact force enters the struck-end row, so the new layer is `x + F·z` with z the
   (constant) response to a unit force, and the overlap solves the same scalar equation, here by
   `scipy.optimize.brentq`. Trackers and energy as the kernel's. Checked against Numba too.
4. **solve_ivp** (method of lines): the rod semi-discretised in space (the kernel's conservative
   operator with half-cell end masses, second order in h, as the explicit scheme), the striker
   and the contact law as ODEs, integrated by `scipy.integrate.solve_ivp` over the case's 4 ms,
   with events for the end of the first contact (δ = 0) and for the maxima of the contact force
   (dF/dt = 0); atol is rtol times 0.1 mm for displacements and times W1 for velocities.
   Compared at equal accuracy, since its cost depends on the accuracy asked: the Numba run's
   relative errors on co-impact time and peak contact force, against a converged reference (the
   explicit scheme at Courant number 1 on 1600 and 3200 cells, Richardson-extrapolated at order
   2; its uncertainty is printed), are the target; a ladder of solve_ivp runs (methods RK23, RK45,
   DOP853; rtol 1e-3 … 1e-8; cells 6 … 128, walked up until both errors are within the target)
   gives the cheapest run that meets both, and its least CPU time over repeats is set against the
   Numba run's. The cheapest run may meet the target by luck (on a coarser grid than the trend
   of its errors would need): that only favours solve_ivp. Done for the Fig. 3 preset and for the
   explicit scheme on 100 cells, whose errors are 30–50× smaller: the preset's paper scheme is
   first order (massless ends), so its errors are those of a second-order semi-discretisation on
   a handful of cells. So each accuracy is also met by the kernel at its cheapest, as solve_ivp
   is: the cheaper of the run itself and the explicit scheme at Courant number 1 on the fewest
   cells of the same ladder whose errors are within the target (the same walk as solve_ivp's,
   luck included), timed the same way.

Printed: ns per node-step of each (for solve_ivp per node and right-hand-side evaluation), the
agreement of C and solve_banded with Numba, and the ratios Numba/C (goal ≤ 1.3), solve_banded/Numba
(goal ≥ 50) and solve_ivp/Numba at equal accuracy (goal ≥ 100).

5. **End conditions** (`--ends` runs only this): the kernel's ns per node-step at the ends that
   integrate their own equations (the explicit scheme at Courant number 1, on 100 and 2000 cells)
   for each law they take: a lumped striker on a linear medium (the paper's ends), on bilinear
   rock and on Smith soil, an elastic striker on a linear medium and on rock, and an anvil between
   a lumped striker and the tool. A rock-drill case (a 0.2-m piston at 10 m/s, a 1-m rod, rock at
   x = k·T/Z = 1.26 that unloads 10× as stiff, `ROCK_DRILL`), the whole `percussim.simulate` call
   at `numerics.tolerance` 0.01 and at the default accuracy, is timed beside the paper's presets
   at the default accuracy.
"""

from __future__ import annotations

import argparse
import ctypes
import json
import math
import subprocess
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp
from scipy.linalg import solve_banded
from scipy.optimize import brentq

from percussim.solver import kernel as K
from percussim.solver.case import Case, load_case, parse_case
from percussim.solver.controller import (
    anvil_on,
    end_conditions,
    force_law,
    rod_constants,
    scheme_weights,
    simulate_rod,
    striker_on,
    tool_on,
)
from percussim.solver.grid import Grid, ResolvedNumerics, make_grid, resolve_numerics, wave_speed
from percussim.solver.laws import contact_law
from percussim.solver.layout import HISTORY_COLUMNS
from percussim.solver.summary import MAX_CONTACTS

ROOT = Path(__file__).resolve().parents[1]
C_SOURCE = ROOT / "bench" / "kernel_c" / "step.c"
# Just below Courant number 1, where the explicit scheme's ends carry their half-cell masses as the
# C and solve_banded yardsticks do (at 1 they integrate their own equations, `kernel.struck_end_step`,
# a different algorithm at the ends; `simulate_rod`'s line times that one).
COURANT_ONE = 1.0 - 1e-5
GOALS = {"Numba/C": 1.3, "solve_banded/Numba": 50.0, "solve_ivp/Numba": 100.0}


# ---------------------------------------------------------------------------------------------
# The run as simulate_rod prepares it


@dataclass
class Setup:
    """One case on its grid: what `simulate_rod` hands the kernel."""

    label: str
    short: str  # for the table of ratios
    case: Case
    num: ResolvedNumerics
    grid: Grid
    tool: K.Tool
    rod: K.Rod
    weights: K.Weights
    medium: K.Medium
    rows: K.ToolRows

    @property
    def n(self) -> int:
        return self.grid.cells

    @property
    def node_steps(self) -> int:
        return (self.n + 1) * self.num.steps


def prepare(label: str, short: str, case: Case, **numerics) -> Setup:
    num = resolve_numerics(case, model="rod", **numerics)
    grid = make_grid(case.tool, num.cells, num.end_masses)
    tool, rod, weights = tool_on(grid), rod_constants(case, num, grid), scheme_weights(num)
    medium = end_conditions(case, grid)[1]
    rows = K.factor_tool_rows(tool, rod, weights, medium)
    return Setup(label, short, case, num, grid, tool, rod, weights, medium, rows)


def explicit_courant_one(case: Case, cells: int) -> dict:
    h = case.tool.length / cells
    return {"scheme": "explicit", "cells": cells, "time_step": COURANT_ONE * h / wave_speed(case.tool)}


def reported(state: K.State, observed: K.Observed) -> dict[str, float]:
    """What the summary reports, from the kernel's slots."""
    extremes, contacts = observed.extremes, observed.contacts
    count = int(extremes[K.X_CONTACTS])
    found = {
        "co-impact time": extremes[K.X_CO_IMPACT],
        "peak contact force": extremes[K.X_PEAK_FORCE],
        "max compressive stress": extremes[K.X_MAX_COMPRESSION],
        "max tensile stress": extremes[K.X_MAX_TENSION],
        "contacts": count + state.ends[K.S_IN_CONTACT],
        "last contact end": contacts[min(count, MAX_CONTACTS) - 1, 1] if count else math.nan,
    }
    names = (
        "external work",
        "dissipated contact",
        "dissipated medium",
        "striker kinetic",
        "tool kinetic",
        "tool strain",
        "contact potential",
        "medium potential",
    )
    found.update({f"energy: {name}": state.energy[0, i] for i, name in enumerate(names)})
    return found


# ---------------------------------------------------------------------------------------------
# 1. Numba


def numba_run(s: Setup) -> dict[str, float]:
    case = s.case
    assert case.force is None
    striker = striker_on(case, s.num, s.tool, s.rod)
    striker_cells = len(striker.tool.node_area) - 1 if striker.elastic else 0
    state, observed = K.new_state(s.n, striker_cells), K.new_observed(MAX_CONTACTS)
    no_fields = np.empty((0, s.n + 1))
    recorders = K.Recorders(
        history=np.empty((HISTORY_COLUMNS, 0)),
        history_stride=0,
        probe_node=np.empty(0, np.int64),
        probe_weight=np.empty(0),
        probes=np.empty((0, 0)),
        field_u=no_fields,
        field_stress=no_fields,
        field_stride=0,
        striker_u=no_fields,
        striker_stress=no_fields,
        shaft_share=np.empty((0, s.n + 1)),
        shaft_span=np.empty((0, 2), np.int64),
        shaft_history=np.empty((0, 0)),
        shaft_field=no_fields,
    )
    contact, medium = end_conditions(case, s.grid)  # as simulate_rod makes them for each run
    anvil = anvil_on(case, s.grid, contact)
    status, _, _ = K.advance(
        0,
        s.num.steps,
        s.tool,
        s.rows,
        s.rod,
        s.weights,
        contact,
        striker,
        anvil,
        medium,
        force_law(case.force),
        K.no_shaft(),
        state,
        observed,
        recorders,
    )
    assert status == K.STATUS_OK
    return reported(state, observed)


# ---------------------------------------------------------------------------------------------
# 2. C


# The order of step.c's prm[] enum
C_PARAMETERS = (
    "h",
    "tau",
    "r",
    "youngs_modulus",
    "density",
    "area",
    "weight_new",
    "weight_old",
    "centered",
    "end_masses",
    "m1",
    "w1",
    "c1",
    "alpha",
    "c0",
    "b1",
    "c2",
    "b2",
)


def build_c(directory: str) -> ctypes.CDLL:
    library = Path(directory) / "step.so"
    subprocess.run(
        ["gcc", "-O3", "-march=native", "-shared", "-fPIC", "-o", str(library), str(C_SOURCE), "-lm"], check=True
    )
    lib = ctypes.CDLL(str(library))
    array = np.ctypeslib.ndpointer(np.float64, flags="C_CONTIGUOUS")
    lib.run.argtypes = [
        ctypes.c_long,
        ctypes.c_long,
        array,
        array,
        array,
        array,
        array,
        array,
        array,
        array,
        ctypes.c_long,
    ]
    lib.run.restype = ctypes.c_int
    return lib


def c_run(lib: ctypes.CDLL, s: Setup) -> dict[str, float]:
    case, weights = s.case, s.weights
    assert s.grid.uniform and case.force is None, "step.c covers uniform tools without force"
    values = {
        "h": s.grid.h,
        "tau": s.num.time_step,
        "r": s.rod.courant_squared,
        "youngs_modulus": case.tool.youngs_modulus,
        "density": case.tool.density,
        "area": case.tool.area,
        "weight_new": weights.new,
        "weight_old": weights.old,
        "centered": float(weights.centered),
        "end_masses": float(weights.end_masses),
        "m1": case.striker.mass,
        "w1": case.striker.velocity,
        "c1": case.contact.stiffness,
        "alpha": case.contact.exponent,
        "c0": case.contact.tension_stiffness,
        "b1": case.contact.damping,
        "c2": s.medium.stiffness,
        "b2": s.medium.damping,
    }
    parameters = np.array([values[name] for name in C_PARAMETERS])
    state, observed = K.new_state(s.n), K.new_observed(MAX_CONTACTS)
    work = np.zeros(5 * (s.n + 1))
    status = lib.run(
        s.n,
        s.num.steps,
        parameters,
        state.u,
        state.y,
        work,
        state.ends,
        observed.extremes,
        state.energy,
        observed.contacts,
        MAX_CONTACTS,
    )
    assert status == 0
    return reported(state, observed)


# ---------------------------------------------------------------------------------------------
# 3. NumPy/SciPy: solve_banded a step


def contact_potential(d: float, c1: float, alpha: float, c0: float) -> float:
    return contact_law(d, c1, alpha, c0)[1]


def contact_spring_force(d: float, c1: float, alpha: float, c0: float) -> float:
    return contact_law(d, c1, alpha, c0)[0]


def quotient_force(d: float, ref: float, ref_potential: float, law: tuple) -> float:
    """`(Φ(δ) − Φ_ref)/(δ − ref)`, Φ'(midpoint) when δ ≈ ref (the kernel's contact force)."""
    if abs(d - ref) > 1e-7 * (abs(d) + abs(ref)):
        return (contact_potential(d, *law) - ref_potential) / (d - ref)
    return contact_spring_force(0.5 * (d + ref), *law)


def crossing(before_that: float, before: float, now: float) -> float:
    """The kernel's `crossing`: where in the last step the overlap crossed zero."""
    linear = before / (before - now)
    if math.isnan(before_that):
        return linear
    a, b = 0.5 * (now + before_that) - before, 0.5 * (now - before_that)
    disc = b * b - 4.0 * a * before
    if a == 0.0 or disc < 0.0:
        return linear
    for x in ((-b + math.sqrt(disc)) / (2.0 * a), (-b - math.sqrt(disc)) / (2.0 * a)):
        if 0.0 <= x <= 1.0:
            return x
    return linear


def banded_run(s: Setup) -> dict[str, float]:
    case, g, weights = s.case, s.grid, s.weights
    n, tau, h, r = s.n, s.num.time_step, g.h, s.rod.courant_squared
    m1, w1 = case.striker.mass, case.striker.velocity
    law = (case.contact.stiffness, case.contact.exponent, case.contact.tension_stiffness)
    b1, c2, b2 = case.contact.damping, s.medium.stiffness, s.medium.damping
    end_weight, spring_weight, damper_factor, back = K.boundary_weights(weights, tau)
    k0, kn = s.rod.struck_end_stiffness, s.rod.working_end_stiffness
    wn, wo = weights.new, weights.old
    wc = 1.0 - wn - wo
    mass = case.tool.density * h * g.node_area / tau**2
    a_y = m1 / tau**2
    e_over_h = case.tool.youngs_modulus / h
    strain_sigma = wn if weights.centered else 0.25
    lower, upper = g.lower[1:n], g.upper[1:n]

    # The tool's rows (9), (8), (10) in solve_banded's layout: ab[1 + i − j, j] = A[i, j]
    ab = np.zeros((3, n + 1))
    ab[1, 0], ab[0, 1] = mass[0] + end_weight * k0, -end_weight * k0
    ab[2, : n - 1] = -wn * r * lower
    ab[1, 1:n] = 1.0 + wn * r * (lower + upper)
    ab[0, 2:] = -wn * r * upper
    ab[2, n - 1] = -end_weight * kn
    ab[1, n] = mass[n] + end_weight * kn + spring_weight * c2 + b2 * damper_factor
    unit = np.zeros(n + 1)
    unit[0] = 1.0
    z = solve_banded((1, 1), ab, unit)  # the tool's response to a unit contact force

    state, observed = K.new_state(s.n), K.new_observed(MAX_CONTACTS)
    extremes, contacts, u, y, ends = observed.extremes, observed.contacts, state.u, state.y, state.ends
    energy = state.energy[0]  # the kernel's latest layer; this solve needs no other
    y[2] = -w1 * tau
    ends[K.S_IN_CONTACT] = 1.0
    initial_energy = 0.5 * m1 * w1 * w1
    for m in range(1, s.num.steps + 1):
        new, cur, old, ref = m % 3, (m - 1) % 3, (m - 2) % 3, (m - back) % 3
        uc, uo, ur = u[cur], u[old], u[ref]
        t = m * tau
        delta_cur, delta_old, delta_ref = y[cur] - uc[0], y[old] - uo[0], y[ref] - ur[0]
        v = wc * uc + wo * uo
        rhs = np.empty(n + 1)
        rhs[1:n] = 2.0 * uc[1:n] - uo[1:n] + r * (lower * (v[: n - 1] - v[1:n]) + upper * (v[2:] - v[1:n]))
        rhs[0] = mass[0] * (2.0 * uc[0] - uo[0])
        rhs[n] = mass[n] * (2.0 * uc[n] - uo[n]) - c2 * (1.0 - spring_weight) * ur[n] + b2 * damper_factor * ur[n]
        if weights.end_masses:
            rhs[0] += k0 * (v[1] - v[0])
            rhs[n] -= kn * (v[n] - v[n - 1])
        x = solve_banded((1, 1), ab, rhs)

        # The new layer is x + F·z, the striker's y = (b_y − F)/a_y: one equation in δ.
        b_y = a_y * (2.0 * y[cur] - y[old])
        free, compliance = b_y / a_y - x[0], 1.0 / a_y + z[0]
        ref_potential = contact_potential(delta_ref, *law) if m >= back else 0.0

        def force(d: float) -> float:
            return quotient_force(d, delta_ref, ref_potential, law) + b1 * damper_factor * (d - delta_ref)

        other = free - compliance * force(free)
        lo, hi = min(free, other), max(free, other)
        delta = (
            free
            if lo == hi
            else brentq(
                lambda d: d + compliance * force(d) - free, lo, hi, xtol=1e-15 * (abs(lo) + abs(hi)), rtol=1e-15
            )
        )
        f = force(delta)
        un = x + f * z
        u[new] = un
        y[new] = (b_y - f) / a_y

        delta = y[new] - un[0]
        if m == 1:
            delta_rate, end_rate, velocity = (delta - delta_cur) / tau, (un[n] - uc[n]) / tau, w1
        else:
            delta_rate = (3.0 * delta - 4.0 * delta_cur + delta_old) / (2.0 * tau)
            end_rate = (3.0 * un[n] - 4.0 * uc[n] + uo[n]) / (2.0 * tau)
            velocity = (3.0 * y[new] - 4.0 * y[cur] + y[old]) / (2.0 * tau)
        contact_force = contact_spring_force(delta, *law) + b1 * delta_rate
        medium_force = c2 * un[n] + b2 * end_rate

        du, ea, eb = un - uc, np.diff(un), np.diff(uc)
        energy[K.E_DISSIPATED_CONTACT] += b1 * (damper_factor * (delta - delta_ref)) ** 2 * tau
        energy[K.E_DISSIPATED_MEDIUM] += b2 * (damper_factor * (un[n] - ur[n])) ** 2 * tau
        energy[K.E_STRIKER_KINETIC] = 0.5 * m1 * (y[new] - y[cur]) ** 2 / tau**2
        energy[K.E_TOOL_KINETIC] = 0.5 * case.tool.density * h / tau**2 * g.node_area @ (du * du)
        energy[K.E_TOOL_STRAIN] = (
            0.5 * e_over_h * g.area_mid @ (strain_sigma * (ea * ea + eb * eb) + (1.0 - 2.0 * strain_sigma) * ea * eb)
        )
        energy[K.E_CONTACT_POTENTIAL] = spring_weight * contact_potential(delta, *law) + (
            1.0 - spring_weight
        ) * contact_potential(delta_cur, *law)
        energy[K.E_MEDIUM_POTENTIAL] = 0.5 * c2 * (spring_weight * un[n] ** 2 + (1.0 - spring_weight) * uc[n] ** 2)
        balance = energy[K.E_DISSIPATED_CONTACT :].sum() - initial_energy - energy[K.E_EXTERNAL_WORK]
        extremes[K.X_ENERGY_EXCESS] = max(extremes[K.X_ENERGY_EXCESS], balance)

        stress = np.empty(n + 1)
        stress[0], stress[n] = -contact_force / g.area[0], -medium_force / g.area[-1]
        stress[1:n] = 0.5 * e_over_h * (un[2:] - un[: n - 1])
        for sign, slot in ((-1.0, K.X_MAX_COMPRESSION), (1.0, K.X_MAX_TENSION)):
            node = int(np.argmax(sign * stress))
            if sign * stress[node] > extremes[slot]:
                extremes[slot : slot + 3] = sign * stress[node], node * h, t

        if contact_force > extremes[K.X_PEAK_FORCE]:
            extremes[K.X_PEAK_FORCE], extremes[K.X_PEAK_FORCE_TIME] = contact_force, t
        f1, f2 = ends[K.S_FORCE_BEFORE], ends[K.S_FORCE_BEFORE_THAT]
        if m >= 3 and f1 >= f2 and f1 > contact_force:
            offset = 0.5 * (contact_force - f2) / (2.0 * f1 - f2 - contact_force)
            vertex = f1 + 0.25 * (contact_force - f2) * offset
            if vertex > extremes[K.X_PEAK_FORCE]:
                extremes[K.X_PEAK_FORCE] = vertex
                extremes[K.X_PEAK_FORCE_TIME] = t - tau + offset * tau
        ends[K.S_FORCE_BEFORE_THAT], ends[K.S_FORCE_BEFORE] = f1, contact_force

        previous = delta_old if m >= 2 else math.nan
        if ends[K.S_IN_CONTACT] and delta < 0.0:
            t_cross = t - tau + tau * crossing(previous, delta_cur, delta)
            k = int(extremes[K.X_CONTACTS])
            contacts[k] = ends[K.S_CONTACT_START], t_cross
            extremes[K.X_CONTACTS] = k + 1
            if k == 0:
                extremes[K.X_CO_IMPACT], extremes[K.X_REBOUND_VELOCITY] = t_cross, velocity
            ends[K.S_IN_CONTACT] = 0.0
        elif not ends[K.S_IN_CONTACT] and delta >= 0.0:
            ends[K.S_IN_CONTACT] = 1.0
            ends[K.S_CONTACT_START] = t - tau + tau * crossing(previous, delta_cur, delta)
    return reported(state, observed)


# ---------------------------------------------------------------------------------------------
# 4. Method of lines with solve_ivp


@dataclass
class MolRun:
    method: str
    rtol: float
    cells: int
    co_impact: float
    peak_force: float
    evaluations: int


def mol_run(case: Case, cells: int, method: str, rtol: float) -> MolRun:
    """The case's rod on `cells` cells as ODEs (kernel's operator, half-cell end masses)."""
    assert case.force is None
    g = make_grid(case.tool, cells, end_masses=True)
    stiffness = case.tool.youngs_modulus / g.h * g.area_mid  # of each cell
    inv_mass = 1.0 / (case.tool.density * g.h * g.node_area)
    m1, w1 = case.striker.mass, case.striker.velocity
    c1, alpha = case.contact.stiffness, case.contact.exponent
    c0, b1 = case.contact.tension_stiffness, case.contact.damping
    c2 = case.medium.stiffness if case.medium else 0.0
    b2 = case.medium.damping if case.medium else 0.0
    nodes = cells + 1

    # state: y, u_0 … u_N, then their velocities
    def accelerations(state: np.ndarray) -> tuple[float, np.ndarray, float]:
        y, u, vy, v = state[0], state[1 : nodes + 1], state[nodes + 1], state[nodes + 2 :]
        d = y - u[0]
        contact = (c1 * d ** (alpha + 1.0) if d >= 0.0 else c0 * d) + b1 * (vy - v[0])
        cell = stiffness * np.diff(u)
        f = np.zeros(nodes)
        f[:-1] += cell
        f[1:] -= cell
        f[0] += contact
        f[-1] -= c2 * u[-1] + b2 * v[-1]
        return -contact / m1, f * inv_mass, contact

    def rhs(t: float, state: np.ndarray) -> np.ndarray:
        ay, au, _ = accelerations(state)
        return np.concatenate((state[nodes + 1 :], [ay], au))

    def separation(t: float, state: np.ndarray) -> float:
        return state[0] - state[1]

    def force_rate(t: float, state: np.ndarray) -> float:
        ay, au, _ = accelerations(state)
        d, rate = state[0] - state[1], state[nodes + 1] - state[nodes + 2]
        spring = (alpha + 1.0) * c1 * d**alpha if d >= 0.0 else c0
        return spring * rate + b1 * (ay - au[0])

    separation.direction = -1.0
    force_rate.direction = -1.0
    start = np.zeros(2 * nodes + 2)
    start[nodes + 1] = w1
    # Absolute tolerances on the scale of the overlap (0.1 mm) and of the impact velocity
    scale = np.concatenate((np.full(nodes + 1, 1e-4), np.full(nodes + 1, abs(w1))))
    sol = solve_ivp(
        rhs,
        (0.0, case.numerics.duration),
        start,
        method=method,
        rtol=rtol,
        atol=rtol * scale,
        events=(separation, force_rate),
    )
    co_impact = sol.t_events[0][0] if len(sol.t_events[0]) else math.nan
    peak = max((accelerations(state)[2] for state in sol.y_events[1]), default=math.nan)
    return MolRun(method, rtol, cells, co_impact, peak, sol.nfev)


MOL_METHODS = ("RK23", "RK45", "DOP853")
MOL_RTOLS = (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8)
MOL_CELLS = (6, 8, 10, 12, 16, 20, 24, 32, 40, 48, 64, 80, 96, 128)


def mol_errors(run: MolRun, reference: tuple[float, float]) -> tuple[float, float]:
    return abs(run.co_impact / reference[0] - 1.0), abs(run.peak_force / reference[1] - 1.0)


def cheapest_mol(case: Case, target: tuple[float, float], reference: tuple[float, float]) -> tuple[MolRun | None, int]:
    """The solve_ivp run of least CPU time whose errors are within `target` (None if none of the
    ladder is), and how many runs the search took. For each method and rtol the cells are walked
    up until the target is met, or until a run costs 3× the best so far (finer grids only cost
    more)."""
    best, best_cpu, tried = None, math.inf, 0
    for method in MOL_METHODS:
        for rtol in MOL_RTOLS:
            for cells in MOL_CELLS:
                start = time.process_time()
                run = mol_run(case, cells, method, rtol)
                cpu = time.process_time() - start
                tried += 1
                if cpu > 3.0 * best_cpu:
                    break
                errors = mol_errors(run, reference)
                if errors[0] <= target[0] and errors[1] <= target[1]:
                    if cpu < best_cpu:
                        best, best_cpu = run, cpu
                    break
    return best, tried


def errors_of(found: dict[str, float], reference: tuple[float, float]) -> tuple[float, float]:
    return (abs(found["co-impact time"] / reference[0] - 1.0), abs(found["peak contact force"] / reference[1] - 1.0))


def cheapest_kernel(case: Case, target: tuple[float, float], reference: tuple[float, float]) -> Setup | None:
    """A cheap kernel run within `target`: the explicit scheme at Courant number 1 on `MOL_CELLS`
    and on, walked up until both errors are within it (as `cheapest_mol` walks)."""
    for cells in (*MOL_CELLS, *range(160, 2001, 32)):
        s = prepare(
            f"explicit, Courant 1, {cells} cells", f"explicit {cells}", case, **explicit_courant_one(case, cells)
        )
        errors = errors_of(numba_run(s), reference)
        if errors[0] <= target[0] and errors[1] <= target[1]:
            return s
    return None


# ---------------------------------------------------------------------------------------------
# Timing and comparison


def least_cpu(runners: dict, repeat: int, budget: float) -> dict[str, float]:
    """The least CPU time of each runner, timed in alternation: at least `repeat` rounds, more
    while the rounds took less than `budget` seconds; a runner whose one run takes longer than
    `budget` is timed once."""
    best = {name: math.inf for name in runners}
    spent, rounds = 0.0, 0
    while rounds < repeat or spent < budget:
        for name, run in runners.items():
            if rounds and best[name] > budget:
                continue
            start = time.process_time()
            run()
            took = time.process_time() - start
            best[name] = min(best[name], took)
            spent += took
        rounds += 1
    return best


def agreement(found: dict[str, float], numba: dict[str, float], initial_energy: float) -> str:
    """Largest relative difference from Numba: the summary's quantities relative to their value,
    the energy terms relative to the impact energy."""
    worst_value, worst_energy = 0.0, 0.0
    for key, value in numba.items():
        if key.startswith("energy"):
            worst_energy = max(worst_energy, abs(found[key] - value) / initial_energy)
        elif key == "contacts":
            assert found[key] == value, f"{found[key]} contacts against {value}"
        else:
            worst_value = max(worst_value, abs(found[key] / value - 1.0))
    return (
        f"co-impact time {abs(found['co-impact time'] / numba['co-impact time'] - 1):.1e}, "
        f"peak force {abs(found['peak contact force'] / numba['peak contact force'] - 1):.1e}, "
        f"worst of times/force/stresses {worst_value:.1e}, energy terms {worst_energy:.1e} of "
        f"the impact energy; {int(numba['contacts'])} contact(s) in both"
    )


def ns(seconds: float, s: Setup) -> str:
    return f"{seconds / s.node_steps * 1e9:7.2f} ns"


def reference_run(case: Case) -> tuple[tuple[float, float], float]:
    """Co-impact time and peak force, Richardson-extrapolated from the explicit scheme at Courant
    number 1 on 1600 and 3200 cells, and its uncertainty (a third of their difference, relative)."""
    runs = [numba_run(prepare("reference", "", case, **explicit_courant_one(case, cells))) for cells in (1600, 3200)]
    values, uncertainty = [], 0.0
    for key in ("co-impact time", "peak contact force"):
        coarse, fine = runs[0][key], runs[1][key]
        values.append(fine + (fine - coarse) / 3.0)
        uncertainty = max(uncertainty, abs(fine - coarse) / 3.0 / abs(values[-1]))
    return (values[0], values[1]), uncertainty


STEEL = {"youngs_modulus": 2.1e11, "density": 7800.0}
_SPEED = math.sqrt(STEEL["youngs_modulus"] / STEEL["density"])
_Z = STEEL["density"] * _SPEED * 1e-3  # the rod's impedance (N·s/m), 1e-3 m² of steel
_ROCK_K = 1.2564 * _Z / (2 * 0.2 / _SPEED)  # Lundberg's optimum x = k·T/Z for the piston
ROCK_DRILL = {
    "striker": {"velocity": 10.0, "length": 0.2, "area": 1e-3, **STEEL},
    "tool": {"length": 1.0, "area": 1e-3, **STEEL},
    "contact": {"stiffness": 1e11, "exponent": 0.0},
    "medium": {"kind": "bilinear", "stiffness": _ROCK_K, "unloading_stiffness": 10 * _ROCK_K},
    "numerics": {"duration": 1e-3},
}
END_CONDITIONS = {
    "lumped striker, linear medium": {"striker": {"mass": 1.6, "velocity": 10.0}, "medium": {"stiffness": _ROCK_K}},
    "lumped striker, bilinear rock": {"striker": {"mass": 1.6, "velocity": 10.0}},
    "lumped striker, Smith soil": {
        "striker": {"mass": 1.6, "velocity": 10.0},
        "medium": {"kind": "smith", "ultimate_resistance": 1e5, "quake": 2.5e-3, "damping_factor": 0.5},
    },
    "elastic striker, linear medium": {"medium": {"stiffness": _ROCK_K}},
    "elastic striker, bilinear rock": {},
    "anvil, lumped striker, linear": {
        "striker": {"mass": 1.6, "velocity": 10.0},
        "medium": {"stiffness": _ROCK_K},
        "anvil": {"mass": 0.5, "contact": {"stiffness": 5e9, "exponent": 0.0}},
    },
}


def end_condition_costs(repeat: int) -> None:
    """Section 5: ns per node-step for each end condition, and the rock drill's whole call."""
    import percussim

    print("\nEnd conditions at the ends that integrate their own equations (explicit, Courant 1):")
    print(f"  {'':34s} {'100 cells':>12s} {'2000 cells':>12s}")
    for label, changes in END_CONDITIONS.items():
        case = parse_case({**ROCK_DRILL, **changes})
        costs = []
        for cells in (100, 2000):
            s = prepare(label, label, case, scheme="explicit", cells=cells)
            numba_run(s)  # compile
            cpu = least_cpu({"Numba": lambda: numba_run(s)}, repeat, budget=1.0)["Numba"]
            costs.append(ns(cpu, s))
        print(f"  {label:34s} {costs[0]:>12s} {costs[1]:>12s}")

    print("\nWhole calls (percussim.simulate, least CPU time over repeats):")
    calls = {
        "rock drill, tolerance 0.01": {**ROCK_DRILL, "numerics": {"duration": 1e-3, "tolerance": 0.01}},
        "rock drill, default accuracy": ROCK_DRILL,
        **{f"preset {name}, default accuracy": _default_accuracy(name) for name in ("fig3", "fig4", "fig5", "fig6")},
    }
    for label, case in calls.items():
        summary = percussim.simulate(case).summary
        cpu = least_cpu({"call": lambda: percussim.simulate(case)}, repeat, budget=2.0)["call"]
        runs = summary["runs"]
        print(
            f"  {label:34s} {cpu * 1e3:9.1f} ms  ({len(runs)} runs, finest {runs[-1]['cells']} "
            f"cells, error estimate {summary['error_estimate']['worst']:.2g})"
        )


def _default_accuracy(name: str) -> dict:
    """A preset with its numerics left to the default accuracy (its duration kept)."""
    case = json.loads((ROOT / "solver" / "presets" / f"{name}.json").read_text())
    case["numerics"] = {"duration": case["numerics"]["duration"]}
    return case


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeat", type=int, default=7)
    parser.add_argument("--ends", action="store_true", help="only section 5, the end conditions")
    args = parser.parse_args()
    if args.ends:
        end_condition_costs(args.repeat)
        return

    fig3 = load_case(ROOT / "solver" / "presets" / "fig3.json")
    setups = [
        prepare("Fig. 3 preset: paper γ=0.5, 100 cells", "paper 100", fig3),
        prepare("Fig. 3, paper γ=0.5, 2000 cells, same τ", "paper 2000", fig3, cells=2000),
        prepare("Fig. 3, explicit, Courant 1, 100 cells", "explicit 100", fig3, **explicit_courant_one(fig3, 100)),
        prepare("Fig. 3, explicit, Courant 1, 2000 cells", "explicit 2000", fig3, **explicit_courant_one(fig3, 2000)),
    ]
    for s in setups:  # compile every specialisation before timing
        numba_run(s)
    simulate_rod(fig3)
    initial_energy = 0.5 * fig3.striker.mass * fig3.striker.velocity**2
    kernel_cpu = {}
    ratios: dict[str, list[tuple[str, float]]] = {name: [] for name in GOALS}

    with tempfile.TemporaryDirectory() as directory:
        lib = build_c(directory)
        for s in setups:
            print(
                f"\n{s.label}: {s.num.steps} steps, τ = {s.num.time_step:.3g} s, Courant "
                f"{s.num.courant:.2f}, {s.node_steps:,} node-steps"
            )
            numba, c, banded = numba_run(s), c_run(lib, s), banded_run(s)
            for name, found in (("C", c), ("solve_banded", banded)):
                print(f"  agreement with Numba, {name + ':':13s} {agreement(found, numba, initial_energy)}")
            cpu = least_cpu({"Numba": lambda: numba_run(s), "C": lambda: c_run(lib, s)}, args.repeat, budget=1.0)
            cpu.update(least_cpu({"solve_banded": lambda: banded_run(s)}, 2, budget=2.0))
            kernel_cpu[s.label] = cpu["Numba"]
            for name, seconds in cpu.items():
                print(f"  {name:13s} {ns(seconds, s)} per node-step  ({seconds * 1e3:9.2f} ms)")
            if s is setups[0]:
                user = least_cpu({"simulate_rod": lambda: simulate_rod(fig3)}, args.repeat, 1.0)
                print(
                    f"  (simulate_rod, the whole user call with a history row a step and the "
                    f"summary: {ns(user['simulate_rod'], s)} per node-step, "
                    f"{user['simulate_rod'] * 1e3:.2f} ms)"
                )
            ratios["Numba/C"].append((s.short, cpu["Numba"] / cpu["C"]))
            ratios["solve_banded/Numba"].append((s.short, cpu["solve_banded"] / cpu["Numba"]))
            print(
                f"  Numba/C {cpu['Numba'] / cpu['C']:.2f}, solve_banded/Numba {cpu['solve_banded'] / cpu['Numba']:.0f}"
            )

    reference, uncertainty = reference_run(fig3)
    print(
        f"\nReference (explicit, Courant 1, 1600 and 3200 cells, Richardson): co-impact time "
        f"{reference[0] * 1e6:.4f} µs, peak contact force {reference[1] / 1e3:.3f} kN "
        f"(uncertainty {uncertainty:.1e})"
    )
    for s in (setups[0], setups[2]):
        target = errors_of(numba_run(s), reference)
        print(
            f"\n{s.label}: errors co-impact {target[0]:.2e}, peak force {target[1]:.2e}; "
            f"Numba {kernel_cpu[s.label] * 1e3:.2f} ms"
        )
        run, tried = cheapest_mol(fig3, target, reference)
        if run is None:
            print(f"  no solve_ivp run of the ladder meets both ({tried} runs tried)")
            continue
        mol_cpu = least_cpu({"mol": lambda: mol_run(fig3, run.cells, run.method, run.rtol)}, args.repeat, budget=1.0)[
            "mol"
        ]
        errors = mol_errors(run, reference)
        print(
            f"  cheapest solve_ivp meeting both ({tried} runs tried): {run.method}, rtol "
            f"{run.rtol:g}, {run.cells} cells: errors {errors[0]:.2e}, {errors[1]:.2e}; "
            f"{run.evaluations} right-hand sides, {mol_cpu * 1e3:.2f} ms "
            f"({mol_cpu / (run.evaluations * (run.cells + 1)) * 1e9:.0f} ns per node and "
            f"right-hand side)"
        )
        ratio = mol_cpu / kernel_cpu[s.label]
        ratios["solve_ivp/Numba"].append((f"{s.short} (this run)", ratio))
        print(f"  solve_ivp/Numba at equal accuracy, against this run: {ratio:.0f}")
        # Both at their cheapest for this accuracy: the kernel's own choice of scheme and grid
        # (this run itself, or a coarser explicit one)
        cheap, cheap_cpu = s, kernel_cpu[s.label]
        walked = cheapest_kernel(fig3, target, reference)
        if walked is not None:
            walked_cpu = least_cpu({"Numba": lambda: numba_run(walked)}, args.repeat, 1.0)["Numba"]
            if walked_cpu < cheap_cpu:
                cheap, cheap_cpu = walked, walked_cpu
        errors = errors_of(numba_run(cheap), reference)
        ratio = mol_cpu / cheap_cpu
        ratios["solve_ivp/Numba"].append((f"{s.short} accuracy, both cheapest", ratio))
        print(
            f"  the kernel's cheapest run meeting both: {cheap.label}: errors {errors[0]:.2e}, "
            f"{errors[1]:.2e}; {cheap_cpu * 1e3:.3f} ms"
        )
        print(f"  solve_ivp/Numba at equal accuracy, each at its cheapest: {ratio:.0f}")

    print("\nRatios against their goals:")
    for name, values in ratios.items():
        goal, at_most = GOALS[name], name == "Numba/C"
        print(f"  {name} (goal {'≤' if at_most else '≥'} {goal:g}):")
        for short, value in values:
            met = value <= goal if at_most else value >= goal
            print(f"    {short:34s} {value:8.2f}  {'met' if met else 'NOT met'}")
    end_condition_costs(args.repeat)


if __name__ == "__main__":
    main()
