"""A hammer at work, designed: the `rock_drill_cycle` preset, a sweep of its valve's stroke, and the
classic design question, the piston's length and the stroke that give the most impact power
while the rod's largest compressive stress stays under a limit.

    .venv/bin/python bench/cycle_design.py [--write]

The study runs 6 of the preset's 10 cycles a variant, to keep its runs short, on 2 processes:
the sweep under the default accuracy (1%) each, the optimisation on one grid chosen by the
tolerance machinery with its best design checked under it (`percussim.optimize`: differential
evolution, then SLSQP). `--write` puts the figures in README.md between its `cycle design`
markers.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from marked import write_marked

from percussim.solver.case import parse_case
from percussim.solver.optimize import optimize
from percussim.solver.presets import preset_json
from percussim.solver.simulate import run_sweep, simulate

ROOT = Path(__file__).resolve().parents[1]
CYCLES = 6
STROKES = [0.02, 0.03, 0.04, 0.05, 0.06]
PISTON = [0.15, 0.6]  # m, striker.length
STROKE = [0.02, 0.08]  # m, drive.stroke
STRESS = 4.5e8  # Pa: the limit on the rod's largest compressive stress
BUDGET = 300  # model runs of the optimisation


def case() -> dict:
    return preset_json("rock_drill_cycle") | {"cycles": {"count": CYCLES}}


def report() -> str:
    lines = []
    started = time.perf_counter()
    summary = simulate(parse_case(case())).summary
    c = summary["cycle"]
    lines += [
        f"The preset, {CYCLES} cycles at the default accuracy ({time.perf_counter() - started:.1f} s): "
        f"{c['frequency']:.3g} blows a second of {c['impact_energy']:.4g} J, {c['impact_power'] / 1e3:.3g} kW of "
        f"impact power from {c['hydraulic_power'] / 1e3:.3g} kW, largest compressive stress "
        f"{summary['max_compressive_stress']['value'] / 1e6:.0f} MPa, estimated error {summary['error_estimate']['worst']:.1e}.",
        "",
        "| stroke (mm) | blows a second | impact energy (J) | impact power (kW) | largest compression (MPa) |",
        "|---|---|---|---|---|",
    ]
    started = time.perf_counter()
    rows = run_sweep({"case": case(), "parameters": {"drive.stroke": STROKES}}, processes=2)
    for row in rows:
        lines.append(
            f"| {1e3 * row['drive.stroke']:.0f} | {row['frequency']:.3g} | {row['impact_power'] / row['frequency']:.4g} | "
            f"{row['impact_power'] / 1e3:.3g} | {row['max_compressive_stress'] / 1e6:.0f} |"
        )
    lines += ["", f"The sweep took {time.perf_counter() - started:.1f} s on 2 processes.", ""]
    request = {
        "case": case(),
        "variables": {"striker.length": PISTON, "drive.stroke": STROKE},
        "objective": {"maximize": "cycle.impact_power"},
        "limits": {"max_compressive_stress": {"max": STRESS}},
        "max_evaluations": BUDGET,
    }
    answer = optimize(request, processes=2)
    best, found = answer["values"], answer["quantities"]
    if best is None:
        lines.append(
            f"Not optimised ({answer['seconds']:.0f} s, {answer['stopped']}): {'; '.join(answer['warnings'])}."
        )
        return "\n".join(lines)
    lines += [
        f"Optimised ({answer['seconds']:.0f} s, {len(answer['history'])} runs on {answer['grid']['cells']} cells, "
        f"2 processes; {answer['stopped']}): a piston of {best['striker.length']:.3f} m and a stroke of "
        f"{1e3 * best['drive.stroke']:.1f} mm give {found['cycle.impact_power'] / 1e3:.3g} kW at "
        f"{found['max_compressive_stress'] / 1e6:.0f} MPa (limit {STRESS / 1e6:.0f} MPa), checked under the "
        f"tolerance; {'; '.join(answer['warnings']) or 'no warning'}.",
    ]
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--write", action="store_true", help="write the figures into README.md")
    args = parser.parse_args()
    text = report()
    print(text)
    if args.write:
        write_marked(ROOT / "README.md", "cycle design", text)


if __name__ == "__main__":
    main()
