"""The tool's sawtooth mode over a long run: seed 1's matrix-31 of `bench/matrix.py` (a 69-kg
striker on a soft damped contact, the tool flying free for 0.22 s) on fixed grids.

    .venv/bin/python bench/sawtooth.py [--cells 5837] [--coarse 23 46 92 184]

The sawtooth `(−1)^(i+n)`, every node against its neighbours and every step against the last, is
an eigenvector of the explicit scheme's interior rows at Courant number 1 for any profile, a double
root at the limit of stability: `(−1)^n·(α + q·n)` solves them too. Its growth a step, q^n = p^n +
p^{n−1} (p the layer's projection on it with the nodes' masses, `amplitude`), is a constant of the
interior rows: only the ends change it. Printed, in order:
1. matrix-31 as drawn; without its external force (and so with its contact's tension line as stiff
   as its pressed one, with its striker three times as fast, and with its taper, an exponential
   through nine stations, through 180); without its contact's damper; and on a uniform tool of
   about its mean area (`VARIANTS`), each on `--cells` cells: the energy the scheme made
   (`energy.numerical`, < 0 is energy created; `max_excess_fraction`), what the explicit scheme's
   strain form holds at the end (< 0 only with a sawtooth in it), what the contact's damper took,
   how much the contact force alternates from step to step at a few times (the history kept every
   7 steps, an odd stride, so that a step-to-step alternation shows as one from row to row), and
   the tool's sawtooth at the same times, α + q·n (from fields kept at an odd stride);
2. the contact force and the sawtooth over the first 0.1 s without the external force: the
   kernel's, at the striker's speed and three times it, and those of the same equations written
   apart from the kernel (`replica_steps`, in Numba), with how closely its contact force follows
   the kernel's over the first steps (they part with the rounding afterwards), its interior rows
   added whole to the displacement, as the kernel's were, term by term, and summed, as the
   kernel's are (`FORMS`);
3. the case without its force on `--coarse` grids over as many steps (its duration scaled up):
   whether it grows with the steps alone;
4. in NumPy, apart from the kernel: a pulse on free rods of three profiles, the sawtooth after
   some steps and its growth a step q at the start and the end, on a uniform rod, an exponential
   taper and the same taper in straight pieces (a case's profile is straight between its
   stations), the pulse over a bend and clear of them, and the exponential taper displaced as a
   whole (rounding then works at that size);
5. in NumPy: the linear map of one step of a uniform rod with the ends' bookkeeping
   (`G_m = u_1^{m−1} − u_0^{m−2} + G_{m−2}`) at a struck end held by a damper b against a rigid
   striker and a free far end: its eigenvalue nearest −1, with its eigenvector, for several b/Z.
About 14 minutes.
"""

from __future__ import annotations

import argparse

import numba
import numpy as np

from percussim.solver.case import parse_case
from percussim.solver.controller import simulate_rod, warm_up
from percussim.solver.grid import explicit_numerics, make_grid, wave_speed
from percussim.solver.kernel.struck_end import SDIRK_GAMMA, limited_slope
from percussim.solver.matrix import draw_cases

STRIDE = 7  # odd: a step-to-step alternation alternates from row to row
TIMES = (0.05, 0.07, 0.08, 0.09, 0.1, 0.15, 0.19, 0.2, 0.205, 0.21, 0.215, 0.22)
FRAMES = 440  # the fields kept over a run
FIRST_STEPS_SPAN = 2e-4  # s: the first steps, over which the replica's force is compared step by step
REPLICA_SPAN = 0.1  # s: how long the kernel's run without its force is compared with the replica's
# How the replica rounds an interior row, u^{m+1} = 2u^m − u^{m−1} + Λu^m, where u is a
# displacement of up to tenths of a metre and Λu (`lower`, `upper`) a difference far smaller
FORMS = (
    "added whole, as the kernel did before it summed them: (2u^m − u^{m−1}) + Λu^m",
    "term by term: ((2u^m − u^{m−1}) + S_{i−½}·(…)) + S_{i+½}·(…)",
    "summed, as the kernel does: d^{m+1} = d^m + Λu^m, u^{m+1} = u^m + d^{m+1}",
)
SUMMED = 2  # the kernel's form (`rows.explicit_interior`)
COMPARED = {"without its external force": 1.0, "without its external force, its striker three times as fast": 3.0}


VARIANTS = (
    "as drawn",
    "without its external force",
    "without its external force, its tension line as stiff as the pressed one",
    "without its external force, its striker three times as fast",
    "without its external force, its taper an exponential through 180 stations",
    "without its contact's damper",
    "on a uniform tool",
)


def variant(name: str) -> dict:
    """matrix-31 as `name` in `VARIANTS` says."""
    raw = draw_cases(1, 72)[31]
    if name == "without its external force":
        raw.pop("force")
    elif name == "without its external force, its tension line as stiff as the pressed one":
        raw.pop("force")
        raw["contact"]["tension_stiffness"] = raw["contact"]["stiffness"]
    elif name == "without its external force, its striker three times as fast":
        raw.pop("force")
        raw["striker"]["velocity"] *= 3.0  # not a power of two, by which floating point scales exactly
    elif name == "without its external force, its taper an exponential through 180 stations":
        raw.pop("force")
        x, area = raw["tool"]["profile"]["x"], raw["tool"]["profile"]["area"]  # flat, then exponential
        stations = np.linspace(x[1], x[-1], 180)
        rate = np.log(area[-1] / area[1]) / (x[-1] - x[1])
        raw["tool"]["profile"] = {
            "x": [0.0, *stations.tolist()],
            "area": [area[0], *(area[1] * np.exp(rate * (stations - x[1]))).tolist()],
        }
    elif name == "without its contact's damper":
        raw["contact"].pop("damping")
    elif name == "on a uniform tool":
        raw["tool"].pop("profile")
        raw["tool"]["area"] = 7e-4  # about its mean
    return raw


def alternation(force: np.ndarray, time: np.ndarray, at: float) -> float:
    """Half the largest change of the contact force from row to row over the 40 rows before `at`."""
    i = max(2, int(np.searchsorted(time, at)))
    return 0.5 * float(np.abs(np.diff(force[i - 40 : i])).max())


def nearest(times: np.ndarray, t: float) -> int:
    """The index of the sample nearest `t` in `times`."""
    return int(np.abs(np.asarray(times) - t).argmin())


def at(history: dict, signed: tuple, t: float) -> str:
    """The contact force and the sawtooth at `t`, from a run's history and its sawtooth's samples."""
    force = history["contact/force"][nearest(history["time"], t)]
    return f"{t:g} s {force:.3g} N {signed[1][nearest(signed[0], t)]:.2g}"


def energy_line(energy: dict) -> str:
    return (
        f"energy.numerical {energy['numerical']:9.3g} J of {energy['initial'] + max(energy['external_work'], 0.0):.4g} J, "
        f"max_excess_fraction {energy['max_excess_fraction']:.2g}, strain form at the end {energy['tool_strain']:.2g} J, "
        f"the contact's damper {energy['dissipated_contact']:.3g} J"
    )


def rod_weights(area, cells: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A free 1-m rod of `area` (m², of x in m) on `cells` cells: its nodes' areas (half cells at
    the ends) and the weights of their neighbours, `lower_i = S_{i−½}/S̄_i`, `upper_i = S_{i+½}/S̄_i`."""
    x = np.linspace(0.0, 1.0, cells + 1)
    cell_area = np.array([np.mean(area(np.linspace(x[i], x[i + 1], 41))) for i in range(cells)])
    node_area = np.concatenate([[0.5 * cell_area[0]], 0.5 * (cell_area[1:] + cell_area[:-1]), [0.5 * cell_area[-1]]])
    lower, upper = np.zeros(cells + 1), np.zeros(cells + 1)
    lower[1:], upper[:-1] = cell_area / node_area[1:], cell_area / node_area[:-1]
    return node_area, lower, upper


def rod_step(now: np.ndarray, before: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """The next layer of the explicit scheme at Courant number 1, both ends free."""
    operator = np.zeros_like(now)
    operator[1:] += lower[1:] * (now[:-1] - now[1:])
    operator[:-1] += upper[:-1] * (now[1:] - now[:-1])
    return 2.0 * now - before + operator


PIECES = "the same taper in 7 straight pieces"  # bends at every seventh of the rod
PROFILES = {  # area (m²) along a 1-m free rod, x in m
    "uniform": lambda x: 1e-3 + 0.0 * x,
    "exponential taper": lambda x: 1.3e-3 * np.exp(-1.3 * x),
    PIECES: lambda x: np.interp(x, np.linspace(0.0, 1.0, 8), 1.3e-3 * np.exp(-1.3 * np.linspace(0.0, 1.0, 8))),
}


def amplitude(layer: np.ndarray, node_area: np.ndarray) -> float:
    """`p`: the layer's projection on the sawtooth `(−1)^i` with the nodes' masses. Smooth layers
    project on it only where the profile bends (the alternating sum of the nodes' areas is 0)."""
    return float(np.sum(node_area * (-1.0) ** np.arange(len(layer)) * layer) / np.sum(node_area))


def pulse_sawtooth(
    area, cells: int, checkpoints: list[int], centre: float, width: float, offset: float = 0.0
) -> list[tuple[float, float]]:
    """A Gaussian pulse of 1 mm at `centre` of `width` (m) on a free rod of `area`, displaced
    `offset` (m) as a whole (rounding then works at that size): at each of
    `checkpoints` steps, the sawtooth's amplitude |p^n| and its growth a step, q^n = p^n + p^{n−1}
    (the mode is `(−1)^n·(α + q·n)`, `amplitude`); q^0 first."""
    node_area, lower, upper = rod_weights(area, cells)
    x = np.linspace(0.0, 1.0, cells + 1)
    before, now = (offset + 1e-3 * np.exp(-(((x - centre + shift) / width) ** 2)) for shift in (1.0 / cells, 0.0))
    found = [(abs(amplitude(now, node_area)), abs(amplitude(now, node_area) + amplitude(before, node_area)))]
    for step in range(1, max(checkpoints) + 1):
        before, now = now, rod_step(now, before, lower, upper)
        if step in checkpoints:
            p = amplitude(now, node_area)
            found.append((abs(p), abs(p + amplitude(before, node_area))))
    return found


@numba.njit
def replica_stage(base: tuple, g: float, v: float, striker: tuple, contact: tuple, impedance: float) -> tuple:
    """One implicit stage `X = base + g·X'` of (y, w, u_0): the contact's force, linear on the line
    the stage lands on, and the rates."""
    mass, _ = striker
    c1, c0, b1 = contact
    y, w, u0 = base
    free = y + g * w - u0 - 2.0 * g * v  # the overlap were the force off
    compliance = g * g / mass + g / impedance
    give = compliance * b1 / g
    target = (free + give * (y - u0)) / (1.0 + give)
    stiffness = c1 if target >= 0.0 else c0
    delta = target / (1.0 + compliance / (1.0 + give) * stiffness)
    force = stiffness * delta + b1 * (delta - (y - u0)) / g
    w_rate = -force / mass
    return force, (w + g * w_rate, w_rate, force / impedance + 2.0 * v)


@numba.njit
def replica_steps(rod: tuple, striker: tuple, contact: tuple, steps: int, every: int, form: int) -> np.ndarray:
    """The same equations as the kernel's, written apart from it: the tapered tool at Courant number
    1 (`rod` = (lower, upper, node_area, τ, Z at the struck end)), a lumped striker (`striker` =
    (m1, its speed)) on a linear contact (`contact` = (c1, c0, b1)) integrated over each step by the
    two-stage SDIRK, the incoming waves from the ends' bookkeeping with the kernel's slope
    (`limited_slope`), a free far end; no force R. The interior rows rounded in the `form` of
    `FORMS`. Rows (time, sawtooth α + q·n, contact force) every `every` steps."""
    lower, upper, node_area, tau, impedance = rod
    n = len(lower) - 1
    u = np.zeros((3, n + 1))
    increments = np.zeros(n + 1)  # u^m − u^{m−1} at the interior nodes, for `form` 2
    sign = np.ones(n + 1)
    sign[1::2] = -1.0
    y, w = 0.0, striker[1]
    waves = np.zeros(6)  # G_{m−1}, G_{m−2}, G_{m−3} at the struck end, then at the far end
    rates = np.zeros(4)  # the incoming waves' mean and slope over the step, struck end then far end
    g = SDIRK_GAMMA * tau
    out = np.zeros((steps // every + 1, 3))
    for m in range(1, steps + 1):
        new, cur, old = m % 3, (m - 1) % 3, (m - 2) % 3
        for i in range(1, n):
            left, right = lower[i] * (u[cur, i - 1] - u[cur, i]), upper[i] * (u[cur, i + 1] - u[cur, i])
            if form == 0:  # added whole
                u[new, i] = (2.0 * u[cur, i] - u[old, i]) + (left + right)
            elif form == 1:  # term by term
                u[new, i] = ((2.0 * u[cur, i] - u[old, i]) + left) + right
            else:  # summed: the step's increment kept apart from the displacement
                increments[i] += left + right
                u[new, i] = u[cur, i] + increments[i]
        for k in range(2):
            inner, edge = (1, 0) if k == 0 else (n - 1, n)
            last, before, earlier = waves[3 * k], waves[3 * k + 1], waves[3 * k + 2]
            now = u[cur, inner] - u[old, edge] + before
            after = u[new, inner] - u[cur, edge] + last
            rates[2 * k] = (now - last) / tau
            rates[2 * k + 1] = limited_slope(
                (before - earlier) / tau, (last - before) / tau, rates[2 * k], (after - now) / tau, tau
            )
            waves[3 * k], waves[3 * k + 1], waves[3 * k + 2] = now, last, before
        start, slope = rates[0] - 0.5 * tau * rates[1], rates[1]
        x = (y, w, u[cur, 0])
        _, k1 = replica_stage(x, g, start + slope * g, striker, contact, impedance)
        span = (1.0 - SDIRK_GAMMA) * tau
        base = (x[0] + span * k1[0], x[1] + span * k1[1], x[2] + span * k1[2])
        force, k2 = replica_stage(base, g, start + slope * tau, striker, contact, impedance)
        y, w, u[new, 0] = base[0] + g * k2[0], base[1] + g * k2[1], base[2] + g * k2[2]
        start, slope = rates[2] - 0.5 * tau * rates[3], rates[3]
        u[new, n] = u[cur, n] + span * 2.0 * (start + slope * g) + g * 2.0 * (start + slope * tau)
        if m % every == 0:
            parity = 1.0 if m % 2 == 0 else -1.0
            out[m // every] = (m * tau, parity * np.sum(node_area * sign * u[new]) / np.sum(node_area), force)
    return out


def replica(raw: dict, cells: int, duration: float, every: int, form: int = SUMMED) -> np.ndarray:
    """`replica_steps` of the case `raw` (a lumped striker on a linear contact, no force, no medium)
    on `cells` cells over `duration` s, its interior rows rounded in the `form` of `FORMS`."""
    case = parse_case(raw)
    numerics = explicit_numerics(case, cells)
    grid = make_grid(case.tool, cells, True)
    impedance = case.tool.density * wave_speed(case.tool) * grid.end_area[0]
    contact = case.contact
    return replica_steps(
        (grid.lower, grid.upper, grid.node_area, numerics.time_step, impedance),
        (case.striker.mass, case.striker.velocity),
        (contact.stiffness, contact.tension_stiffness, contact.damping),
        round(duration / numerics.time_step),
        every,
        form,
    )


def bookkeeping_step(state: np.ndarray, weights: tuple, damper_over_impedance: float) -> np.ndarray:
    """One step of a rod's layers (u^{m−1}, u^{m−2}) and the struck end's G_{m−1}, G_{m−2}
    (`weights` = (lower, upper), `rod_weights`): the struck end moved by the wave arriving over the
    step as a damper b against a rigid striker lets it, `Δu_0 = 2Z/(Z + b)·ΔG`."""
    n = len(weights[0]) - 1
    now, before, g_last, g_before = state[: n + 1], state[n + 1 : 2 * n + 2], state[-2], state[-1]
    new = rod_step(now, before, *weights)
    g_now = now[1] - before[0] + g_before
    new[0] = now[0] + 2.0 / (1.0 + damper_over_impedance) * (g_now - g_last)
    return np.concatenate([new, now, [g_now, g_last]])


def sawtooth_eigenvalue(cells: int, damper_over_impedance: float) -> tuple[complex, float]:
    """On a uniform rod: the step's eigenvalue nearest −1 and how far its eigenvector's layer is
    from the sawtooth."""
    weights = rod_weights(PROFILES["uniform"], cells)[1:]
    size = 2 * cells + 4
    step = np.column_stack([bookkeeping_step(e, weights, damper_over_impedance) for e in np.eye(size)])
    values, vectors = np.linalg.eig(step)
    k = int(np.argmin(np.abs(values + 1.0)))
    layer = np.real(vectors[: cells + 1, k] / vectors[0, k])
    return values[k], float(np.abs(layer - (-1.0) ** np.arange(cells + 1)).max())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--cells", type=int, default=5837)
    parser.add_argument("--coarse", type=int, nargs="*", default=[23, 46, 92, 184])
    args = parser.parse_args()
    warm_up()
    kept = {}  # the runs compared with the replica: their histories and sawtooth
    for name in VARIANTS:
        raw = variant(name)
        case = parse_case(raw)
        numerics = explicit_numerics(case, args.cells)
        stride = numerics.steps // FRAMES | 1  # odd: the sawtooth's sign alternates from frame to frame
        raw["outputs"] = {"history_stride": STRIDE, "fields": True, "field_stride": stride}
        result = simulate_rod(parse_case(raw), numerics=numerics)
        history, fields = result.history, result.fields
        node_area = make_grid(case.tool, args.cells, True).node_area
        steps = np.rint(fields.time / numerics.time_step)
        signed = (
            fields.time,
            [(-1.0) ** n * amplitude(layer, node_area) for n, layer in zip(steps, fields.displacement)],
        )
        if name in COMPARED:
            kept[COMPARED[name]] = history, signed
        print(f"\nmatrix-31 {name}, {args.cells} cells: {energy_line(result.summary['energy'])}")
        print(
            "  the contact force's step-to-step alternation (N): "
            + ", ".join(f"{t:g} s {alternation(history['contact/force'], history['time'], t):.2g}" for t in TIMES)
        )
        print(
            "  the tool's sawtooth α + q·n (m): "
            + ", ".join(f"{t:g} s {signed[1][nearest(signed[0], t)]:.2g}" for t in TIMES)
        )
    print(f"\nmatrix-31 without its external force, {args.cells} cells, its contact force and sawtooth (m):")
    early = [t for t in TIMES if t <= REPLICA_SPAN]
    for label, speed in (("the kernel", 1.0), ("the kernel, its striker three times as fast", 3.0)):
        history, signed = kept[speed]
        print(f"  {label}: " + ", ".join(at(history, signed, t) for t in early))
    raw = variant("without its external force")
    raw["numerics"]["duration"], raw["outputs"] = FIRST_STEPS_SPAN, {"history_stride": 1}
    first = simulate_rod(parse_case(raw), numerics=explicit_numerics(parse_case(raw), args.cells)).history
    rows = replica(variant("without its external force"), args.cells, FIRST_STEPS_SPAN, 1)
    count = min(len(first["time"]), len(rows)) - 1
    force = first["contact/force"][1 : count + 1]
    print(
        f"  over the first {count} steps the replica's contact force is the kernel's to "
        f"{np.max(np.abs(rows[1 : count + 1, 2] - force) / np.abs(force)):.2g} (relative)"
    )
    for form, how in enumerate(FORMS):
        for name, speed in COMPARED.items():
            rows = replica(variant(name), args.cells, REPLICA_SPAN, 1001, form)
            samples = [(t, rows[nearest(rows[:, 0], t)]) for t in early]
            print(
                f"  the same equations apart from the kernel, {how}{', three times as fast' if speed > 1 else ''}: "
                + ", ".join(f"{t:g} s {row[2]:.3g} N {row[1]:.2g}" for t, row in samples)
            )
    steps = explicit_numerics(parse_case(variant("as drawn")), args.cells).steps
    print(f"\nmatrix-31 without its external force, {steps} steps on coarser grids:")
    for cells in args.coarse:
        raw = variant("without its external force")
        case = parse_case(raw)
        raw["numerics"]["duration"] = case.numerics.duration * steps / explicit_numerics(case, cells).steps
        case = parse_case(raw)
        print(f"  {cells:5d} cells, {case.numerics.duration:6.2f} s: ", end="", flush=True)
        print(energy_line(simulate_rod(case.summary_only(), numerics=explicit_numerics(case, cells)).summary["energy"]))
    checkpoints = [1_000, 10_000, 100_000]
    print("\nA 1-mm pulse on a free rod of 200 cells at Courant number 1 (NumPy): the sawtooth |p| after")
    print(
        "  " + " ".join(f"{n:>10,d}" for n in checkpoints) + " steps (m), its growth a step |q| at 0 and 100,000 steps"
    )
    pulses = [(name, area, 0.3, 0.05, 0.0) for name, area in PROFILES.items()]
    pulses.append(("the same, the pulse clear of its bends", PROFILES[PIECES], 0.357, 0.015, 0.0))
    pulses.append(("the exponential taper displaced 0.3 m", PROFILES["exponential taper"], 0.3, 0.05, 0.3))
    for name, area, centre, width, offset in pulses:
        found = pulse_sawtooth(area, 200, checkpoints, centre, width, offset)
        print(
            "  "
            + " ".join(f"{p:10.2e}" for p, _ in found[1:])
            + f"  {found[0][1]:9.2e} {found[-1][1]:9.2e}  {name} (at {centre} m, {width} m wide)"
        )
    print("\nA uniform rod of 20 cells, the struck end's bookkeeping with a damper b against a rigid striker:")
    for ratio in (0.0, 0.075, 1.0, 3.0):
        value, off = sawtooth_eigenvalue(20, ratio)
        print(
            f"  b/Z = {ratio:5.3f}: eigenvalue {value.real:+.12f}{value.imag:+.1e}j, its layer the sawtooth to {off:.1e}"
        )


if __name__ == "__main__":
    main()
