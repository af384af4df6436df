"""Calibration and optimisation: wall time, model runs, and how near the answers come to values
known beforehand.

    .venv/bin/python bench/inverse.py [--repeats 3] [--quick] [--write]

a. Two parameters (contact.stiffness, medium.stiffness) of a Fig. 5-like case (Fig. 5's striker,
   tool and contact on a medium of 2e9 N/m with a damper of 1e5 N·s/m, over 1.5 ms) fitted to the
   stress at a gauge at x = 0.3 m, from a start 8× and 4× off, on 2 processes and on 1.
b. Three parameters (medium.damping in [0, 1e6] too, its start 4× off) from the contact force.
   Each record is made by another setting than any fit's (the sigma scheme on 1200 cells at
   τ = 0.1 µs, where a fit runs the explicit scheme on its own grid), sampled at 1 MHz, with
   Gaussian noise of 2% of its peak (seed 1): the tests' records (tests/test_calibrate.py).
c. An optimisation of 1,000 runs: the rock_drill preset's piston (striker.length in [0.1, 0.6] m,
   striker.velocity in [5, 20] m/s) maximising energy.to_medium with max_compressive_stress at
   most 250 MPa, on 2 processes; on the preset's 3.66-m rod and, as a check, on the 1.5-m rod of
   tests/test_optimize.py. Skipped by `--quick`.
d. Lundberg's optimal piston: energy.transfer_efficiency maximised over striker.length in
   [0.1, 0.6] m on the 1.5-m rod (a budget of 200 runs, 2 processes), against his closed form.
e. The striker–tool impedance ratio: an elastic striker (0.2 m) on a 1-m tool whose far end is a
   matched dashpot; energy.transfer_efficiency over the striker's first pulse maximised over
   striker.area in [A/4, 4A] (A the tool's), against the rod–rod transmission 4r/(1 + r)², whose
   maximum is r = 1 (a budget of 200 runs, 2 processes).
f. A split Hopkinson bar's incident pulse as a recorder writes it (percussim/testing/closed_forms.py,
   `Hopkinson`: made by d'Alembert's solution, not the kernel): 12.5 MHz from the trigger at 10% of
   the plateau, times of 3 significant digits, 1% noise. The striker's velocity and length, the
   contact's stiffness and the record's time_offset fitted (2 processes), against the truth and
   the wave theory's reading. `--write` also writes the record and the starting case
   (docs/inverse/shpb.csv, shpb.json) and the fit's plot (docs/images/shpb-fit.png).

Times are wall clock around `calibrate` or `optimize` (given a `LocalEvaluator` of the processes,
as `processes=` makes, to see whether its pool started), the kernel compiled beforehand: the
median of `--repeats` runs for a and b, one run for c and d. Runs: the model runs the answer counts
(`evaluations`). `--write` writes docs/inverse.md.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import sys
import time
from pathlib import Path

import numpy as np

from percussim.solver.calibrate import calibrate
from percussim.solver.case import parse_case
from percussim.solver.controller import simulate_rod, warm_up
from percussim.solver.evaluate import LocalEvaluator
from percussim.solver.optimize import optimize
from percussim.solver.presets import preset_json
from percussim.solver.record import record_from_csv
from percussim.solver.study import OFFSET, fitted_bounds, parse_calibration
from percussim.solver.study_plots import fit_figure
from percussim.testing import closed_forms as CF

ROOT = Path(__file__).resolve().parents[1]

TRUE = {"contact.stiffness": 8e11, "medium.stiffness": 2e9, "medium.damping": 1e5}
START = {"contact.stiffness": 1e11, "medium.stiffness": 5e8, "medium.damping": 4e5}
BOUNDS = {"contact.stiffness": [1e9, 1e15], "medium.stiffness": [1e7, 1e11], "medium.damping": [0.0, 1e6]}
DURATION = 1.5e-3  # s
GAUGE = 0.3  # m
NOISE = 0.02  # of the record's peak
SEED = 1
MAX_PISTON = 0.6  # m
ALLOWABLE = 250e6  # Pa
LUNDBERG_BUDGET = 200


# The records and the cases


def fig5_like() -> dict:
    """Fig. 5's striker, tool and contact on a stiffer medium with a damper, over 1.5 ms."""
    case = preset_json("fig5")
    case.pop("description")
    case["medium"] = {"stiffness": TRUE["medium.stiffness"], "damping": TRUE["medium.damping"]}
    case["numerics"] = {"duration": DURATION}
    return case


def measured(quantity: str) -> dict:
    """The true case's `quantity` by the sigma scheme on 1200 cells, sampled at 1 MHz, with noise."""
    case = fig5_like()
    case["numerics"] = {"duration": DURATION, "scheme": "sigma", "cells": 1200, "time_step": 1e-7}
    case["outputs"] = {"probes": [GAUGE]}
    run = simulate_rod(parse_case(case))
    t = np.arange(0.0, DURATION, 1e-6)
    samples = {"contact_force": run.history["contact/force"], "stress": run.probe_stress[:, 0]}[quantity]
    values = np.interp(t, run.history["time"], samples)
    values += NOISE * np.abs(values).max() * np.random.default_rng(SEED).standard_normal(len(t))
    return {
        "quantity": quantity,
        "time": t.tolist(),
        "values": values.tolist(),
        **({"x": GAUGE} if quantity == "stress" else {}),
    }


def start_case(names: list[str]) -> dict:
    case = fig5_like()
    for name in names:
        part, field = name.split(".")
        case[part][field] = START[name]
    return case


def rock_drill(short: bool) -> dict:
    """The rock_drill preset (a 3.66-m rod over 1.3 ms), or with `short` the 1.5-m rod over
    0.55 ms of tests/test_optimize.py."""
    case = preset_json("rock_drill")
    case.pop("description")
    if short:
        case["tool"]["length"] = 1.5
        case["numerics"] = {"duration": 0.55e-3}
    return case


def single_pass(case: dict) -> str:
    """Whether a run of `case` holds one pass of the wave through the rod, Lundberg's, for every
    piston up to `MAX_PISTON`: the longest piston's pulse has reached the bit when the run ends,
    and the bit's reflection is not yet back at the struck end."""
    speed = math.sqrt(case["tool"]["youngs_modulus"] / case["tool"]["density"])
    length, duration = case["tool"]["length"], case["numerics"]["duration"]
    reached, returned = (length + 2.0 * MAX_PISTON) / speed, 2.0 * length / speed
    verdict = "one pass, Lundberg's" if reached <= duration < returned else "NOT a single pass"
    return (
        f"the longest piston's pulse is at the bit by {reached * 1e3:.3f} ms, the run ends at "
        f"{duration * 1e3:g} ms, the bit's reflection is back at the struck end at "
        f"{returned * 1e3:.3f} ms: {verdict}"
    )


def lundberg(case: dict) -> tuple[float, float]:
    """Lundberg's optimal piston length x*·Z·a/(2k), the stationary point x* of (1 − e^−x)²/x,
    and his efficiency there, 2(1 − e^−x*)²/x*·(1 − k/k_u)."""
    x, _ = CF.lundberg_optimum()
    tool, rock = case["tool"], case["medium"]
    speed = math.sqrt(tool["youngs_modulus"] / tool["density"])
    impedance = tool["density"] * speed * tool["area"]
    efficiency = CF.lundberg(x, unloading=rock["unloading_stiffness"] / rock["stiffness"])
    return x * impedance * speed / (2.0 * rock["stiffness"]), efficiency


# Running and timing


def timed(study, request: dict, processes: int) -> tuple[dict, float, LocalEvaluator]:
    """The answer of `study` on `processes` processes, its wall time, and the evaluator (which says
    whether its pool started: a batch of quick runs stays in this process)."""
    with LocalEvaluator(processes) as evaluator:
        start = time.perf_counter()
        answer = study(request, evaluator=evaluator)
        return answer, time.perf_counter() - start, evaluator


def pool_note(evaluator: LocalEvaluator) -> str:
    run = f"runs up to {evaluator.run_seconds * 1e3:.1f} ms"
    if evaluator.processes == 1:
        return run
    return run + (", pool started" if evaluator.pool is not None else ", pool not started")


class Table:
    """A titled table, shown as aligned text and written as markdown, with notes below it."""

    def __init__(self, title: str, header: list[str]):
        self.title, self.header, self.rows, self.notes = title, header, [], []

    def text(self) -> str:
        cells = [self.header] + self.rows
        widths = [max(len(row[k]) for row in cells) for k in range(len(self.header))]
        lines = [self.title] + ["  " + "  ".join(c.ljust(w) for c, w in zip(row, widths)).rstrip() for row in cells]
        lines.insert(2, "  " + "  ".join("-" * w for w in widths))
        return "\n".join(lines + [f"  {note}" for note in self.notes])

    def markdown(self) -> str:
        lines = [f"**{self.title}**", "", "| " + " | ".join(self.header) + " |", "|" + "---|" * len(self.header)]
        lines += ["| " + " | ".join(row) + " |" for row in self.rows]
        return "\n".join(lines + [""] + [f"{note}\n" for note in self.notes])


def calibration_tables(label: str, quantity: str, names: list[str], repeats: int) -> list[Table]:
    request = {
        "case": start_case(names),
        "record": measured(quantity),
        "parameters": {name: BOUNDS[name] for name in names},
    }
    runs = Table(
        f"{label}: time and runs",
        ["processes", "wall time (median)", "range", "runs", "nrmse", "noise", "grid (cells)", "note"],
    )
    fits = []
    for processes in (2, 1):
        trials = [timed(calibrate, request, processes) for _ in range(repeats)]
        fit, _, evaluator = trials[0]
        seconds = [s for _, s, _ in trials]
        fits += [t[0] for t in trials]
        runs.rows.append(
            [
                str(processes),
                f"{statistics.median(seconds):.2f} s",
                f"{min(seconds):.2f}–{max(seconds):.2f} s",
                str(fit["evaluations"]),
                f"{fit['nrmse']:.4f}",
                f"{fit['noise']:.4f}",
                f"{fit['grid']['cells']} ({fit['grid']['refinements']} refinement"
                f"{'s' if fit['grid']['refinements'] != 1 else ''})",
                pool_note(evaluator),
            ]
        )
    fit = fits[0]
    values = Table(
        f"{label}: recovered values",
        ["parameter", "start", "true", "found", "error", "standard error", "error in s.e.", "95% bounds hold true"],
    )
    for name in names:
        found = fit["parameters"][name]
        se = found["standard_error"]
        error = found["value"] / TRUE[name] - 1.0
        held = found["low"] is not None and found["low"] < TRUE[name] < found["high"]
        values.rows.append(
            [
                name,
                f"{START[name]:.3g}",
                f"{TRUE[name]:.3g}",
                f"{found['value']:.5g}",
                f"{error:+.2%}",
                "—" if se is None else f"{se:.3g} ({se / found['value']:.2%})",
                "—" if se is None else f"{abs(found['value'] - TRUE[name]) / se:.2f}",
                "yes" if held else "no",
            ]
        )
    same = all(f["parameters"] == fit["parameters"] for f in fits)
    values.notes.append(
        "The same values in every run, on 1 and on 2 processes."
        if same
        else "The values differ between runs (1 and 2 processes, repeats): those of the first on 2 processes are shown."
    )
    values.notes.append("Warnings: " + ("; ".join(fit["warnings"]) if fit["warnings"] else "none."))
    return [runs, values]


def rock_drill_table() -> Table:
    table = Table(
        f"c. Rock drill: maximise energy.to_medium, max_compressive_stress ≤ {ALLOWABLE / 1e6:g} "
        "MPa, a budget of 1000 runs, 2 processes",
        [
            "rod",
            "wall time",
            "runs",
            "striker.length",
            "striker.velocity",
            "energy.to_medium",
            "max_compressive_stress (checked)",
            "designs checked",
            "grid (cells)",
            "note",
        ],
    )
    for short in (False, True):
        case = rock_drill(short)
        answer, seconds, evaluator = timed(
            optimize,
            {
                "case": case,
                "variables": {"striker.length": [0.1, MAX_PISTON], "striker.velocity": [5.0, 20.0]},
                "objective": {"maximize": "energy.to_medium"},
                "limits": {"max_compressive_stress": {"max": ALLOWABLE}},
                "max_evaluations": 1000,
            },
            2,
        )
        rod = f"{case['tool']['length']:g} m over {case['numerics']['duration'] * 1e3:g} ms"
        rod += " (tests/test_optimize.py)" if short else " (the preset)"
        if answer["values"] is None:
            found = ["—"] * 4
        else:
            found = [
                f"{answer['values']['striker.length']:.4f} m",
                f"{answer['values']['striker.velocity']:.3f} m/s",
                f"{answer['quantities']['energy.to_medium']:.2f} J",
                f"{answer['summary']['max_compressive_stress']['value'] / 1e6:.1f} MPa",
            ]
        table.rows.append(
            [
                rod,
                f"{seconds:.1f} s",
                str(answer["evaluations"]),
                *found,
                str(len(answer["checked"])),
                str(answer["grid"]["cells"]),
                pool_note(evaluator),
            ]
        )
        table.notes.append(
            f"{rod}: {single_pass(case)}. Stopped: {answer['stopped']}. "
            f"Warnings: {'; '.join(answer['warnings']) or 'none'}."
        )
    return table


def lundberg_table() -> Table:
    case = rock_drill(short=True)
    answer, seconds, evaluator = timed(
        optimize,
        {
            "case": case,
            "variables": {"striker.length": [0.1, MAX_PISTON]},
            "objective": {"maximize": "energy.transfer_efficiency"},
            "max_evaluations": LUNDBERG_BUDGET,
        },
        2,
    )
    expected, efficiency = lundberg(case)
    found = answer["values"]["striker.length"]
    table = Table(
        f"d. Lundberg's optimal piston: maximise energy.transfer_efficiency over striker.length "
        f"in [0.1, {MAX_PISTON:g}] m, 1.5-m rod, budget {LUNDBERG_BUDGET} runs, 2 processes",
        ["", "piston length", "efficiency"],
    )
    found_efficiency = answer["quantities"]["energy.transfer_efficiency"]
    table.rows.append(["found", f"{found:.4f} m", f"{found_efficiency:.4f}"])
    table.rows.append(["Lundberg", f"{expected:.4f} m", f"{efficiency:.4f}"])
    table.rows.append(["difference", f"{found / expected - 1.0:+.2%}", f"{found_efficiency / efficiency - 1.0:+.2%}"])
    table.notes.append(
        f"{answer['evaluations']} runs in {seconds:.1f} s ({pool_note(evaluator)}). Lundberg: L* = x*·Z·a/(2k) "
        "with x* = 1.2564 the stationary point of (1 − e^−x)²/x, Z = ρ·a·A, a = √(E/ρ) and k the rock's "
        "loading stiffness; his efficiency there 2(1 − e^−x*)²/x*·(1 − k/k_u). "
        f"Stopped: {answer['stopped']}. Warnings: {'; '.join(answer['warnings']) or 'none'}."
    )
    return table


def impedance_table() -> Table:
    answer, seconds, evaluator = timed(
        optimize,
        {
            "case": CF.matched_tool_case(1.7),
            "variables": {"striker.area": [CF.AREA / 4, 4 * CF.AREA]},
            "objective": {"maximize": "energy.transfer_efficiency"},
            "max_evaluations": LUNDBERG_BUDGET,
        },
        2,
    )
    ratio = answer["values"]["striker.area"] / CF.AREA
    efficiency = answer["quantities"]["energy.transfer_efficiency"]
    table = Table(
        f"e. The striker–tool impedance ratio r = A1/A2 that passes the most energy, budget "
        f"{LUNDBERG_BUDGET} runs, 2 processes",
        ["", "r", "efficiency"],
    )
    table.rows.append(["found", f"{ratio:.4f}", f"{efficiency:.4f}"])
    table.rows.append(["closed form", "1", "1"])
    table.rows.append(["difference", f"{ratio - 1.0:+.2%}", f"{efficiency - 1.0:+.2%}"])
    worst = max(
        abs(
            run["quantities"]["energy.transfer_efficiency"] / CF.passed_share(run["values"]["striker.area"] / CF.AREA)
            - 1.0
        )
        for run in answer["history"]
    )
    table.notes.append(
        f"{answer['evaluations']} runs in {seconds:.1f} s ({pool_note(evaluator)}) on {answer['grid']['cells']} cells; "
        f"every run's efficiency within {worst:.2%} of 4r/(1 + r)² (the contact's finite stiffness and the "
        f"grid of the 1% tolerance). Stopped: {answer['stopped']}. "
        f"Warnings: {'; '.join(answer['warnings']) or 'none'}."
    )
    return table


SHPB_START = {"velocity": 7.0, "length": 0.8, "stiffness": 2e9}
SHPB_BOUNDS = {"striker.velocity": [2.0, 10.0], "striker.length": [0.3, 1.0], "contact.stiffness": [1e8, 1e10]}


def shpb_table(write: bool) -> Table:
    H = CF.Hopkinson
    text, offset = H.triggered_record()
    record = record_from_csv(text)
    case = H.case(**SHPB_START)
    answer, seconds, evaluator = timed(calibrate, {"case": case, "record": record, "parameters": SHPB_BOUNDS}, 2)
    reading = H.reading(record.instants, record.values)
    excess = H.C * H.half_width_excess() / 2.0
    truth = {
        "striker.velocity": H.VELOCITY,
        "striker.length": H.STRIKER,
        "contact.stiffness": H.STIFFNESS,
        "record.time_offset": offset,
    }
    theory = {
        "striker.velocity": f"{reading['velocity']:.4f}",
        "striker.length": f"{reading['half_width_length']:.4f} ({reading['half_width_length'] - excess:.4f})",
    }
    table = Table(
        "f. A split Hopkinson bar's incident pulse, triggered at its gauge, 3-digit times, 1% noise, 2 processes",
        ["parameter", "truth", "wave theory", "fitted", "standard error", "(fitted − truth)/SE", "fitted/truth − 1"],
    )
    for name, value in truth.items():
        found = answer["parameters"][name]
        table.rows.append(
            [
                name,
                f"{value:.6g}",
                theory.get(name, ""),
                f"{found['value']:.6g}",
                f"{found['standard_error']:.2g}",
                f"{(found['value'] - value) / found['standard_error']:+.2f}",
                f"{found['value'] / value - 1.0:+.2e}",
            ]
        )
    table.notes.append(
        f"{answer['evaluations']} runs in {seconds:.2f} s ({pool_note(evaluator)}), grid {answer['grid']['cells']} "
        f"cells after {answer['grid']['refinements']} refinements; nrmse {answer['nrmse']:.4f} against the "
        f"record's noise {answer['noise']:.4f}. Wave theory: v = 2|σ|/(ρc) from the plateau; L_s = c·T/2 from "
        f"the half-amplitude width T, and in brackets that less the contact spring's unloading, "
        f"c·τ·(1.678 − ln 2)/2 = {excess * 1e3:.1f} mm, which the record does not show. "
        f"Warnings: {'; '.join(answer['warnings']) or 'none'}."
    )
    if write:
        folder = ROOT / "docs" / "inverse"
        folder.mkdir(exist_ok=True)
        (folder / "shpb.csv").write_text(text)
        (folder / "shpb.json").write_text(json.dumps(case, indent=2) + "\n")
        fit_figure(answer, "shpb").savefig(ROOT / "docs" / "images" / "shpb-fit.png")
    return table


def shpb_facts() -> dict:
    """What the worked example quotes of the record: its first lines, and where its time_offset is
    sought (µs)."""
    text, _ = CF.Hopkinson.triggered_record()
    request = parse_calibration(
        {
            "case": CF.Hopkinson.case(**SHPB_START),
            "record": record_from_csv(text).model_dump(exclude_none=True),
            "parameters": SHPB_BOUNDS,
        }
    )
    low, high = fitted_bounds(request)[OFFSET]
    return {
        "shpb_head": "\n".join("    " + line for line in text.splitlines()[:4]),
        "shpb_low": low * 1e6,
        "shpb_high": high * 1e6,
    }


PAGE = """# Calibration and optimisation

Two studies run the solver many times over: a **calibration** finds the values of a case's
fields that make a run reproduce a measured record, and an **optimisation** finds the values,
within bounds, that make a summary quantity as large or as small as it can be while others stay
within limits. Both are in the solver (`percussim.calibrate`, `percussim.optimize`), on the command
line (`percussim calibrate`, `percussim optimize`, here or with `--url` on a service), in the
HTTP API (`POST /v1/calibrations`, `/v1/optimizations`, see [api.md](api.md)) and its Python
client (`Client.calibrate`, `Client.optimize`), and on the job page, which reads a CSV record
from disk and shows the fit, its uncertainty and warnings, or an optimisation's progress and
best design.

Both vary fields named by dotted paths (`contact.stiffness`, `striker.length`) between bounds.
A field whose bounds are both positive is searched on a logarithmic scale, so that six decades of
a stiffness are as easy as one. Every run of a study's stage is on one grid, so that the answers
change smoothly with the fields: the explicit scheme at Courant number 1, on no fewer cells than
any point within the bounds takes (an elastic striker's wave transit must span two time steps, so
a piston a twelfth of its rod's length needs 24 cells, and one whose length is fitted, as many as
its shortest bound asks). An optimisation's grid is the one the tolerance machinery chooses for
the starting case (`numerics.tolerance`, 1% when not given); a fit climbs its own, from the
tolerance ladder's first grid, doubling it until its values settle (step 5 below). A fixed grid the case gives (`numerics.cells`, `time_step`, `scheme`) is
set aside, and the answer's warnings say so. The batch of runs of each step goes to a pool of
processes (one a core by default), or to the service's workers. Runs of a few milliseconds, as in most fits, cost less in the calling process than the
pipe to a pool: a batch goes to the pool only when its runs would take long enough to be worth
it, so a fit of such runs gains little from more processes (see a and b below).

## Calibration

The record is a time series of one quantity a run also gives: the contact force, the force on
the medium, the stress at a gauge (`stress@X`, X in metres from the struck end, tension
positive), or the velocity of the struck or the working end, in SI units.

**Its clock.** The times are a column (`time`), or, for an evenly sampled record, a start and a
rate (`time_start`, `sample_rate`; in a CSV, comment lines `# sample_rate = 12.5e6` and
`# time_start = 0` above a header with the quantity alone, or `--sample-rate` on the command
line). A time column printed with few digits repeats its times (at 12.5 MHz, times of three
significant digits repeat each one about 12 times past 100 µs): a column whose repeats are only
such rounding of an even sampling is read as that sampling, a line fitted through the middles of
its distinct times (within 2 ns at 12.5 MHz, from two significant digits on), and the answer's
warnings say so; any other column that does not increase is refused, naming the first sample.

**The trigger.** The model's time 0 is the impact. A recorder triggered by the pulse starts its
clock where the pulse reaches the gauge, and a wave needs x/c to run from the struck end to a
gauge x metres along a tool of wave speed c = √(E/ρ) (5.17 km/s in steel: 209 µs to a gauge at
1.082 m), plus part of the pulse's rise before it crosses the trigger's level. `record.time_offset`
(s) is the model's time at the record's time 0. Give it when it is known; leave it out and it is 0
for a record that starts at rest (its first sample within four noise deviations, or 2% of the
peak, of zero: a recorder started before the impact, or with a lead-in), and fitted otherwise,
between x/c less and x/c plus the record's own rise (its first sample to the first at 90% of its
peak), or between the bounds given as `parameters["record.time_offset"]`. The fit reports it
with the others, with its standard error; a sample before the impact is compared with the tool
at rest.

1. **Checks first.** The record against the case (a gauge on the tool, a record no longer than
   the run), the fields and their bounds, and the record's units: a record whose peak is 30 times
   or more above or below the model's at every corner of the bounds is refused (a unit off by a
   prefix gives 1000).
2. **A global look.** The case at its own values and at a scrambled Sobol sample of the bounds
   (8 points a parameter), in one batch; more rounds with a sample as large again while the
   misfit stays above the record's noise.
3. **Least squares** (bounded, trust-region reflective) on the difference between the model and
   the record, from the three best points of the global look, with the sensitivities by finite
   differences run as one batch.
4. **The uncertainty.** At the optimum, the sensitivities by central differences, the residual's
   variance and from them the covariance: a standard error for each parameter, the correlation
   between them, and 95% confidence bounds (on the logarithmic scale for a positive parameter,
   so they stay positive).
5. **The grid.** Steps 2–4 run on the tolerance ladder's first grid, coarse: a global look needs
   no more. The fit is then repeated on a grid twice as fine, from its optimum, until the values
   move by less than a third of their standard errors: the grid's error is then a small part of
   the answer's uncertainty. A fit is judged by its values, not by a summary's tolerance: a
   record of a few hundred samples settles on far fewer cells than a summary's largest stress
   asks of its grid.

The answer holds, for each parameter, its value, standard error and 95% bounds; the correlation
matrix; the misfit (`nrmse`, the RMS difference over the record's range) beside the record's own
noise (estimated from its sample-to-sample scatter); the number of model runs; the fitted case,
ready to run; the record against the model; and `warnings`, which say when the fit should not be
trusted as unique: two parameters strongly correlated (|r| ≥ 0.95: the record cannot tell them
apart), a parameter at a bound (the best fit may lie beyond it), a parameter the record does not
or hardly determines, starts that ended at different values with the same misfit, a misfit well
above the noise (the model does not reproduce the record: a parameter not fitted, or something
the model lacks), and a grid not fine enough. The standard errors are those of the record's
noise, on the assumption that the model is right; they do not cover what the model leaves out.

## Optimisation

The objective is one summary quantity to maximise or minimise (such as
`energy.transfer_efficiency` or `energy.to_medium`); limits bound others (such as
`max_compressive_stress` ≤ 250 MPa).

1. **A global search** by differential evolution over the bounds, ten designs a variable in its
   population, each generation one batch of runs; each limit is a constraint tightened by the
   tolerance (1% by default) toward its safe side. It stops when the population agrees or its
   share of the budget of runs is spent.
2. **A local polish** (SLSQP) from its best design, the gradients by finite differences, within
   the rest of the budget. The budget, `max_evaluations` (1000 by default), is checked after each
   generation and each step, so the runs may pass it by a generation's worth.
3. **The check.** The best feasible design is solved again under the tolerance, by the adaptive
   solver, and its summary, with its error estimate, is the answer's. A design that breaks a
   limit there is not the answer: the next best is checked instead (up to three).

The answer holds the design's values, its case and checked summary, the objective and limits'
values, every run made (`history`), the designs checked, why each stage stopped (`stopped`), and
`warnings`: a variable at a bound (the optimum may lie beyond it), or no design found that keeps
every limit.

## A worked example: a split Hopkinson bar

The incident bar of a split Hopkinson bar: steel (E = 210 GPa, ρ = 7850 kg/m³), Ø20 mm, 2.1 m
long, a strain gauge 1.082 m from the struck end, recorded at 12.5 MHz from the moment the pulse
crosses 10% of its plateau, for 340 µs, with the time column printed to three significant digits
and 1% noise. The pulse of about 100 MPa lasting 236 µs comes from a striker of the bar's own
section through a contact whose spring makes a front rising over 20 µs. The record
([docs/inverse/shpb.csv](inverse/shpb.csv)) is made by d'Alembert's solution of two uniform rods
through a contact spring, not by percussim's solver. Its first lines:

{shpb_head}

The fit, from a start at 7 m/s, 0.8 m and 2e9 N/m ([docs/inverse/shpb.json](inverse/shpb.json)),
the striker as a rod of the bar's section:

    percussim calibrate docs/inverse/shpb.json --record docs/inverse/shpb.csv \\
        --fit striker.velocity=2:10 --fit striker.length=0.3:1 --fit contact.stiffness=1e8:1e10 \\
        --plot shpb-fit.png

The record does not start at rest, so its time_offset is fitted too (between {shpb_low:.1f} and
{shpb_high:.1f} µs here),
and the answer's first warning says the time column was read as an even sampling at 12.5 MHz.
The figures are in table f below; the plot:

![the SHPB record against the fitted model, and the residual](images/shpb-fit.png)

The wave theory reads the same record as v = 2|σ|/(ρc) from the plateau, and L_s = c·T/2 from
the half-amplitude width T. The velocity agrees; the width does not give the length to better
than a few percent when a contact spring shapes the front: the spring loads as 1 − e^(−t/τ) but,
once the striker's unloading wave is back, unloads as (1 + t/τ)·e^(−t/τ) (τ = Z/(2k), 9.1 µs
here), which is slower, so the half-amplitude width is 2·L_s/c + τ·(1.678 − ln 2), 23 mm of
length long (3.8%). The fit models the spring, and finds the length within 0.02%.

## Measured

{measured}
Measured on a machine with {cores} cores, Python {python} (the 1-minute load average {load}:
other work on the machine lengthens the times), by

    .venv/bin/python bench/inverse.py --write{options}

(`--quick` skips c).

"""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeats", type=int, default=3, help="runs of each fit, the median time shown (default 3)")
    parser.add_argument("--quick", action="store_true", help="skip c, the 1000-run optimisation")
    parser.add_argument("--write", action="store_true", help="write docs/inverse.md")
    args = parser.parse_args()
    load = [os.getloadavg()[0]]
    warm_up()
    parts = [
        lambda: calibration_tables(
            f"a. Two parameters from the stress at x = {GAUGE:g} m, {NOISE:.0%} noise",
            "stress",
            ["contact.stiffness", "medium.stiffness"],
            args.repeats,
        ),
        lambda: calibration_tables(
            f"b. Three parameters from the contact force, {NOISE:.0%} noise",
            "contact_force",
            list(BOUNDS),
            args.repeats,
        ),
        *([] if args.quick else [lambda: [rock_drill_table()]]),
        lambda: [lundberg_table()],
        lambda: [impedance_table()],
        lambda: [shpb_table(args.write)],
    ]
    tables = []
    for part in parts:
        for table in part():
            print(table.text() + "\n", flush=True)
            tables.append(table)
    load.append(os.getloadavg()[0])
    load_text = f"{load[0]:.2f} at the start, {load[1]:.2f} at the end"
    print(f"{os.cpu_count()} cores; the 1-minute load average {load_text}")
    if args.write:
        measured = "\n".join(t.markdown() for t in tables)
        if args.quick:
            measured += "\nc. (the 1000-run optimisation) was skipped: `--quick`.\n"
        options = (" --quick" if args.quick else "") + (f" --repeats {args.repeats}" if args.repeats != 3 else "")
        (ROOT / "docs" / "inverse.md").write_text(
            PAGE.format(
                measured=measured,
                cores=os.cpu_count(),
                python=sys.version.split()[0],
                load=load_text,
                options=options,
                **shpb_facts(),
            )
        )
        print("wrote docs/inverse.md")


if __name__ == "__main__":
    main()
