"""Make a measured-like record and the case a calibration starts from, for the README's worked fit.

    .venv/bin/python examples/make_record.py --out-dir demo
    percussim calibrate demo/case.json --record demo/record.csv \\
        --fit contact.stiffness=1e9:1e15 --fit medium.stiffness=1e7:1e11 \\
        --output demo/fit.json --plot demo/fit.png

The "true" device is Fig. 5's striker, tool and contact on a stiffer medium with a damper
(medium.stiffness 2e9 N/m, medium.damping 1e5 N·s/m) over 1.5 ms. It is solved with another
setting than any fit uses (the sigma scheme on 1200 cells at a time step of 0.1 µs; a fit runs
the explicit scheme on its own grid), the stress at a gauge is sampled at 1 MHz, and Gaussian
noise of a share of the peak is added, so the record is not something the fit can reproduce
exactly. Writes:

    record.csv  time,stress@X: s from the impact and Pa (tension positive)
    case.json   the true case with contact.stiffness 1e11 (8× too soft) and
                medium.stiffness 5e8 (4× too soft): where the fit starts
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from percussim.solver.case import parse_case
from percussim.solver.controller import simulate_rod
from percussim.solver.presets import preset_json
from percussim.solver.record import Record, record_to_csv

TRUE = {"contact.stiffness": 8e11, "medium.stiffness": 2e9}
START = {"contact.stiffness": 1e11, "medium.stiffness": 5e8}
DURATION = 1.5e-3  # s
SAMPLING = 1e-6  # s: 1 MHz


def true_case() -> dict:
    """Fig. 5's striker, tool and contact (contact.stiffness 8e11) on a stiffer, damped medium."""
    case = preset_json("fig5")
    case.pop("description")
    case["name"] = "fig5-like"
    case["medium"] = {"stiffness": TRUE["medium.stiffness"], "damping": 1e5}
    case["numerics"] = {"duration": DURATION}
    return case


def measured(case: dict, gauge: float, noise: float, seed: int) -> Record:
    """The stress at `gauge` (m from the struck end) by another solver setting than a fit's,
    sampled at 1 MHz, with Gaussian noise of `noise` × its peak."""
    fine = {
        **case,
        "numerics": {"duration": DURATION, "scheme": "sigma", "cells": 1200, "time_step": 1e-7},
        "outputs": {"probes": [gauge]},
    }
    run = simulate_rod(parse_case(fine))
    t = np.arange(0.0, DURATION, SAMPLING)
    stress = np.interp(t, run.history["time"], run.probe_stress[:, 0])
    stress += noise * np.abs(stress).max() * np.random.default_rng(seed).standard_normal(len(t))
    return Record(quantity="stress", x=gauge, time=t.tolist(), values=stress.tolist())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out-dir", default="demo", help="where to write record.csv and case.json (default demo)")
    parser.add_argument("--noise", type=float, default=0.02, help="noise as a share of the peak (default 0.02)")
    parser.add_argument("--seed", type=int, default=1, help="of the noise (default 1)")
    parser.add_argument(
        "--gauge", type=float, default=0.3, help="the gauge's station, m from the struck end (default 0.3)"
    )
    args = parser.parse_args()

    out = Path(args.out_dir)
    out.mkdir(parents=True, exist_ok=True)
    case = true_case()
    record = measured(case, args.gauge, args.noise, args.seed)
    (out / "record.csv").write_text(record_to_csv(record))

    start = json.loads(json.dumps(case))
    start["contact"]["stiffness"] = START["contact.stiffness"]
    start["medium"]["stiffness"] = START["medium.stiffness"]
    (out / "case.json").write_text(json.dumps(start, indent=2) + "\n")

    peak = max(abs(v) for v in record.values)
    print(
        f"{out / 'record.csv'}: {record.label} (Pa), {len(record.time)} samples at 1 MHz over "
        f"{DURATION * 1e3:g} ms, peak {peak / 1e6:.1f} MPa, noise {args.noise:.0%} of the peak (seed {args.seed})"
    )
    print(f"{out / 'case.json'}: the fit's start")
    for name, true in TRUE.items():
        print(f"  {name:18s} start {START[name]:.3g}, true {true:.3g} ({true / START[name]:g}× the start)")


if __name__ == "__main__":
    main()
