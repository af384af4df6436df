"""Signal matching's speed and what it recovers: a 20-m steel pipe pile (two shaft segments and a
toe: 7 unknowns, the default ones) matched to a head record made by a 20,000-cell run of the
true pile (finer than any grid the match runs on), struck by a 2.5-MN half-sine over 4 ms,
sampled at 20 kHz for 25 ms with 2% noise on force and velocity; the match starts from guesses 1.6× the shaft's, 0.67× the toe's resistance, and
quakes and damping factors off by half or more.

    .venv/bin/python bench/signal_match.py [--processes 2] [--write]

Then the same match with the noise on the force and the velocity, on the force alone and on the
velocity alone, three seeds each: how far each unknown lands, in its standard errors. Then refits
with the velocity's noise drawn again: the bias and spread that noise puts in each unknown.

Prints each unknown against the truth with its standard error and how many of them it is off,
the capacity, the match quality, the Case method's RMX, the runs and the wall time (the goal: 30 s
on 2 cores). `--write` puts them in docs/signal_matching.md between its `signal match` markers,
and the speed in docs/performance.md between its `signal match speed` markers.
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import numpy as np
from marked import write_marked

from percussim.solver.adaptive import solve_to_tolerance
from percussim.solver.controller import warm_up
from percussim.solver.grid import DEFAULT_TOLERANCE
from percussim.solver.record import scatter
from percussim.solver.signal_match import driven_case, parse_signal_match, signal_match
from percussim.testing.pile_records import head_record, pile, with_noise

ROOT = Path(__file__).resolve().parents[1]
TOOL = {"length": 20.0, "youngs_modulus": 2.1e11, "density": 7850.0, "area": 0.01}
SHAFT = [
    {"from": 5.0, "to": 12.0, "ultimate_resistance": 3e5, "quake": 2.5e-3, "damping_factor": 0.2},
    {"from": 12.0, "to": 20.0, "ultimate_resistance": 6e5, "quake": 2.5e-3, "damping_factor": 0.2},
]
TOE = {"kind": "smith", "ultimate_resistance": 6e5, "quake": 2.5e-3, "damping_factor": 0.5}
TRUTH = {
    "shaft.0.ultimate_resistance": 3e5,
    "shaft.1.ultimate_resistance": 6e5,
    "shaft.*.quake": 2.5e-3,
    "shaft.*.damping_factor": 0.2,
    "medium.ultimate_resistance": 6e5,
    "medium.quake": 2.5e-3,
    "medium.damping_factor": 0.5,
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--processes", type=int, default=2)
    parser.add_argument("--write", action="store_true", help="write the figures into docs/signal_matching.md")
    args = parser.parse_args()
    warm_up()
    numerics = {"duration": 0.025}
    clean = head_record(
        pile(tool=TOOL, shaft=SHAFT, medium=TOE, numerics=numerics), cells=20_000, peak=2.5e6, noise=0.0
    )
    record = with_noise(clean, 0.02, 0.02, seed=1)
    guess = pile(
        tool=TOOL,
        shaft=[
            s | {"ultimate_resistance": 1.6 * s["ultimate_resistance"], "quake": 4e-3, "damping_factor": 0.4}
            for s in SHAFT
        ],
        medium=TOE | {"ultimate_resistance": 4e5, "quake": 4e-3, "damping_factor": 0.3},
        numerics=numerics,
    )
    start = time.perf_counter()
    match = signal_match({"case": guess, "record": record}, processes=args.processes)
    seconds = time.perf_counter() - start
    lines = ["| unknown | truth | matched | standard error | off by |", "|---|---|---|---|---|"]
    for path, truth in TRUTH.items():
        found = match["parameters"][path]
        off = abs(found["value"] - truth) / found["standard_error"]
        lines.append(f"| `{path}` | {truth:.4g} | {found['value']:.4g} | {found['standard_error']:.2g} | {off:.2f} σ |")
    grid = match["grid"]
    speed = (
        f"{match['evaluations']} runs, {seconds:.1f} s on {args.processes} processes (goal: 30 s on 2 cores); the "
        f"fit's grid {grid['cells']} cells after {grid['refinements']} doublings, the last moving the values by "
        f"{grid['moved']:.2f} of their standard errors; the tolerance machinery's grid for the pile at its "
        f"guesses: {tolerance_grid(guess, record)} cells"
    )
    capacity = match["capacity"]
    off = abs(capacity["value"] - 1.5e6) / capacity["standard_error"]
    quality = match["match_quality"]
    rmx = ", ".join(f"{row['damping_factor']:g}: {row['capacity'] / 1e3:.0f}" for row in match["case_method"])
    lines += [
        "",
        f"capacity {capacity['value'] / 1e3:.1f} ± {capacity['standard_error'] / 1e3:.1f} kN against 1500 kN "
        f"({off:.2f} σ); match quality {quality['value']:.4f} (2L/c window {quality['window']:.4f}, after "
        f"{quality['after']:.4f}); Case method RMX (kN) for J_c {rmx}",
        "",
        f"warnings: {'; '.join(match['warnings']) or 'none'}",
        "",
        speed,
    ]
    text = "\n".join(lines)
    print(text)
    sources = noise_sources(clean, guess, args.processes)
    print(sources)
    refitted = refits(clean, guess, args.processes)
    print(refitted)
    if args.write:
        write_marked(ROOT / "docs" / "signal_matching.md", "signal match", text)
        write_marked(ROOT / "docs" / "signal_matching.md", "signal match noise", sources)
        write_marked(ROOT / "docs" / "signal_matching.md", "signal match refits", refitted)
        write_marked(ROOT / "docs" / "performance.md", "signal match speed", speed)


REFITS = 4  # refits a match, each with the velocity's noise drawn again


def refits(clean: dict, guess: dict, processes: int) -> str:
    """What the velocity's noise does to a match, measured by refits: each of three matches (2% noise
    on both, seeds 1–3) fitted again `REFITS` times from its answer, the velocity given noise of its
    own scatter once more. Per unknown, in the match's standard errors: its distance from the truth,
    that distance once the refits' mean shift is taken off (the shift a second dose of the noise
    makes, as an estimate of the first's), and the refits' spread."""
    short = [path.replace("ultimate_resistance", "R_u").replace("damping_factor", "J") for path in TRUTH]
    lines = [
        "| seed | " + " | ".join(f"`{name}`" for name in short) + " |",
        "|---|" + "---|" * len(TRUTH),
    ]
    for seed in (1, 2, 3):
        record = with_noise(clean, 0.02, 0.02, seed)
        match = signal_match({"case": guess, "record": record}, processes=processes)
        found = {path: match["parameters"][path] for path in TRUTH}
        start = {name: value for name, value in match["case"].items() if name != "struck_end"}
        noise, rng = scatter(record["velocity"]), np.random.default_rng(100 + seed)
        shifts = []
        for _ in range(REFITS):
            velocity = np.asarray(record["velocity"]) + noise * rng.standard_normal(len(record["velocity"]))
            again = signal_match(
                {"case": start, "record": record | {"velocity": velocity.tolist()}}, processes=processes
            )
            shifts.append([math.log(again["parameters"][p]["value"] / found[p]["value"]) for p in TRUTH])
        shift, spread = np.mean(shifts, axis=0), np.std(shifts, axis=0, ddof=1)
        cells = []
        for (path, truth), d, sd in zip(TRUTH.items(), shift, spread):
            value, error = found[path]["value"], found[path]["standard_error"]
            corrected = value * math.exp(-d)
            cells.append(
                f"{(value - truth) / error:+.2f} → {(corrected - truth) / error:+.2f} ({value * sd / error:.2f})"
            )
        lines.append(f"| {seed} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def tolerance_grid(guess: dict, record: dict) -> int:
    """The cells the tolerance machinery (1%) takes the record-driven pile to, on its summary."""
    case = driven_case(parse_signal_match({"case": guess, "record": record}))
    result, _ = solve_to_tolerance(case.summary_only(), DEFAULT_TOLERANCE)
    return result.numerics.cells


def noise_sources(clean: dict, guess: dict, processes: int) -> str:
    """How far each unknown lands from the truth, in its standard errors, with the 2% noise on the
    force and the velocity, on the force alone, and on the velocity alone, for three seeds."""
    short = [path.replace("ultimate_resistance", "R_u").replace("damping_factor", "J") for path in TRUTH]
    lines = [
        "| noise on | seed | " + " | ".join(f"`{name}`" for name in short) + " | capacity |",
        "|---|---|" + "---|" * (len(TRUTH) + 1),
    ]
    for label, force, velocity in (("force and velocity", 0.02, 0.02), ("force", 0.02, 0.0), ("velocity", 0.0, 0.02)):
        for seed in (1, 2, 3):
            match = signal_match(
                {"case": guess, "record": with_noise(clean, force, velocity, seed)}, processes=processes
            )
            found = match["parameters"]
            offs = [(found[p]["value"] - truth) / found[p]["standard_error"] for p, truth in TRUTH.items()]
            capacity = match["capacity"]
            offs.append((capacity["value"] - 1.5e6) / capacity["standard_error"])
            lines.append(f"| {label} | {seed} | " + " | ".join(f"{off:+.2f}" for off in offs) + " |")
    return "\n".join(lines)


if __name__ == "__main__":
    main()
