"""The speed/accuracy trade, measured: each scheme over a ladder of grids on three presets, against
a converged reference, and the tolerance-driven runs against the cheapest fixed grid.

    .venv/bin/python bench/accuracy_vs_cost.py [--write]

For each preset (Fig. 3: uniform tool and medium; Fig. 5: short hard contact; Fig. 9: conical tool,
abs-sine force, repeated contacts) the case's own numerics are replaced by:

- a reference: the explicit scheme at Courant number 1 on two very fine grids, Richardson-
  extrapolated at order 2 (its uncertainty, a third of their difference, is printed);
- a ladder for each scheme (paper γ = 0.5, sigma σ = 1/4, explicit; all at Courant number 1) of
  cells 2^(k/4)·10; the error of a run is the largest relative error of co-impact time, peak
  contact force and maximum stress; its cost the least CPU time of `simulate` over repeats;
- `numerics.tolerance` = 1e-2, 1e-3, 1e-4: true error, estimate, cost, and the ratio of that cost
  to the cheapest fixed grid (any scheme) that meets the tolerance. A grid meets it when it and
  every finer grid of its scheme's ladder do: where the error still jumps about with the grid
  (Fig. 5 below about 90 cells, where the sequence of repeated impacts changes from grid to grid)
  a coarse grid can hit the tolerance by luck, which no one choosing a grid could rely on. Those
  lucky grids are listed too.

Then the same tolerances on three linear impacts with a closed form (`solver.reference`), in work
(node-steps) against the cheapest fixed grid of any scheme; and tolerances 1e-2 and 1e-3 on Fig. 5 variants
with many repeated impacts, against a fine reference.

`--write` writes `docs/accuracy_vs_cost.md`, `docs/accuracy_vs_cost.png` and the tables quoted in
README.md (between its `accuracy_vs_cost` markers).
"""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path

import numpy as np

from solver import parse_case
from solver.adaptive import QUANTITIES, quantities
from solver.controller import warm_up
from solver.grid import wave_speed
from solver.reference import LinearImpact, cheapest_fixed_grid, true_errors, work
from solver.simulate import simulate

ROOT = Path(__file__).resolve().parents[1]
PRESETS = {"fig3": 1600, "fig5": 800, "fig9": 800}  # reference grids: N and 2N cells
SCHEMES = ("paper", "sigma", "explicit")
LADDER = [round(10 * 2 ** (k / 4)) for k in range(25)]  # 10 … 640 cells
TOLERANCES = (1e-2, 1e-3, 1e-4)
TARGETS = (1e-2, 1e-3, 1e-4)
VARIANT_TOLERANCES = (1e-2, 1e-3)
CLOSED_FORMS = ((0.3, 20.0), (0.1, 5.0), (0.6, 50.0))  # contact damping ratio ζ, striker mass m1
# Fig. 5 variants: points (k, j) of bench/sweep.py's 20 × 20 grid, striker velocity 2 + 8k/19 m/s
# and contact stiffness 1e11·16^(j/19). The first two have many repeated impacts with irregular
# convergence; the rest were drawn at random.
FIG5_VARIANTS = tuple((2.0 + 8.0 * k / 19, 1e11 * 16 ** (j / 19)) for k, j in (
    (0, 18), (4, 18), (2, 8), (3, 15), (14, 15), (12, 6), (0, 12), (13, 19), (0, 14), (8, 7),
    (18, 3), (10, 0), (0, 0), (17, 0)))


def preset(name: str) -> dict:
    case = json.loads((ROOT / "examples" / f"{name}.json").read_text())
    case["numerics"] = {"duration": case["numerics"]["duration"]}
    case["outputs"] = {}
    return case


def fig5_variant(velocity: float, stiffness: float) -> dict:
    """The Fig. 5 preset with another striker velocity and contact stiffness (`FIG5_VARIANTS`)."""
    case = preset("fig5")
    case["striker"]["velocity"], case["contact"]["stiffness"] = velocity, stiffness
    return case


def closed_form_case(reference: LinearImpact, tol: float) -> dict:
    """The closed form's case under `numerics.tolerance` = `tol`, no grid given."""
    case = reference.case(10)
    case["numerics"].update(cells=None, time_step=None, tolerance=tol)
    return case


def with_numerics(case: dict, **numerics) -> dict:
    return {**case, "numerics": {"duration": case["numerics"]["duration"], **numerics}}


def courant_one(case: dict, cells: int) -> float:
    tool = parse_case(case).tool
    return (1.0 - 1e-9) * tool.length / cells / wave_speed(tool)


def timed(case: dict, repeat: int = 3, budget: float = 0.05) -> tuple[dict, float]:
    """The summary and the least CPU time of at least `repeat` runs of the validated case, repeated
    until they took `budget` seconds (sub-millisecond runs need many to time)."""
    parsed = parse_case(case)
    best, summary, spent, runs = math.inf, None, 0.0, 0
    while runs < repeat or spent < budget:
        start = time.process_time()
        summary = simulate(parsed).summary
        took = time.process_time() - start
        best, spent, runs = min(best, took), spent + took, runs + 1
    return summary, best


def reference(case: dict, cells: int) -> tuple[dict[str, float], float]:
    runs = [quantities(simulate(parse_case(with_numerics(
        case, scheme="explicit", cells=n, time_step=courant_one(case, n)))).summary)
        for n in (cells, 2 * cells)]
    ref, uncertainty = {}, 0.0
    for q in QUANTITIES:
        if runs[1][q] is None:
            continue
        ref[q] = runs[1][q] + (runs[1][q] - runs[0][q]) / 3.0
        uncertainty = max(uncertainty, abs(runs[1][q] - runs[0][q]) / 3.0 / abs(ref[q]))
    return ref, uncertainty


def error(summary: dict, ref: dict[str, float]) -> float:
    return max(true_errors(summary, ref).values())


def measure(name: str) -> dict:
    case = preset(name)
    ref, uncertainty = reference(case, PRESETS[name])
    print(f"\n{name}: reference {ref} (uncertainty {uncertainty:.1e})")
    ladder = {}
    for scheme in SCHEMES:
        rows = []
        for cells in LADDER:
            summary, cpu = timed(with_numerics(case, scheme=scheme, cells=cells,
                                               time_step=courant_one(case, cells)))
            rows.append((cells, summary["numerics"]["steps"], cpu, error(summary, ref)))
            print(f"  {scheme:8s} {cells:5d} cells {rows[-1][1]:7d} steps {cpu * 1e3:9.2f} ms  "
                  f"error {rows[-1][3]:.2e}")
        ladder[scheme] = rows
    tolerance = []
    for tol in TOLERANCES:
        summary, cpu = timed(with_numerics(case, tolerance=tol))
        cheapest = min(meeting(ladder, tol), default=(math.nan, "none", 0))
        lucky = [f"{scheme} {cells}" for cpu_, scheme, cells in lucky_hits(ladder, tol)
                 if cpu_ < cheapest[0]]
        cheapest_work = (cheapest[2] + 1) * (ladder_steps(ladder, cheapest) + 1)
        row = {"tol": tol, "error": error(summary, ref), "estimate": summary["error_estimate"]["worst"],
               "cpu": cpu, "model": summary["model"], "scheme": summary["scheme"],
               "cells": summary["runs"][-1]["cells"], "runs": len(summary["runs"]),
               "cheapest": cheapest, "ratio": cpu / cheapest[0],
               "work_ratio": work(summary["runs"]) / cheapest_work, "lucky": lucky}
        tolerance.append(row)
        print(f"  tolerance {tol:g}: error {row['error']:.2e} (estimate {row['estimate']:.2e}), "
              f"{cpu * 1e3:.2f} ms in {row['runs']} runs; cheapest fixed grid meeting it: "
              f"{cheapest[1]} {cheapest[2]} cells, {cheapest[0] * 1e3:.2f} ms → {row['ratio']:.2f}× "
              f"(work {row['work_ratio']:.2f}×)"
              + (f"; coarser grids meeting it by luck: {', '.join(lucky)}" if lucky else ""))
    return {"ref": ref, "uncertainty": uncertainty, "ladder": ladder, "tolerance": tolerance}


def meeting(ladder: dict, tol: float) -> list[tuple[float, str, int]]:
    """(cost, scheme, cells) of each scheme's coarsest grid from which every finer grid meets `tol`,
    the cost a row's third column (CPU time here, work in bench/ladder_settings.py)."""
    found = []
    for scheme, rows in ladder.items():
        settled = None
        for cells, _, cost, err in reversed(rows):
            if err > tol:
                break
            settled = (cost, scheme, cells)
        if settled:
            found.append(settled)
    return found


def ladder_steps(ladder: dict, grid: tuple[float, str, int]) -> int:
    """The time steps of a grid of the ladder (`meeting`'s CPU, scheme, cells)."""
    _, scheme, cells = grid
    return next(steps for c, steps, _, _ in ladder[scheme] if c == cells)


def closed_forms() -> list[dict]:
    """Tolerance runs on linear impacts with a closed form (`solver.reference`), three striker
    and contact pairs: true error, and work (node-steps) against the cheapest fixed grid of any
    scheme at Courant number 1 or ½."""
    rows = []
    for zeta, m1 in CLOSED_FORMS:
        ref = LinearImpact(zeta=zeta, m1=m1)
        for tol in TOLERANCES:
            summary = simulate(parse_case(closed_form_case(ref, tol))).summary
            cheapest, grid = cheapest_fixed_grid(ref, tol)
            rows.append({"zeta": zeta, "m1": m1, "tol": tol,
                         "error": error(summary, ref.truth()),
                         "estimate": summary["error_estimate"]["worst"],
                         "cells": [r["cells"] for r in summary["runs"]], "grid": grid,
                         "work_ratio": work(summary["runs"]) / cheapest})
            r = rows[-1]
            print(f"  closed form ζ = {zeta:g}, m1 = {m1:g} kg, tolerance {tol:g}: error {r['error']:.2e} "
                  f"(estimate {r['estimate']:.2e}), grids {r['cells']}; cheapest fixed grid "
                  f"{grid[0]} at Courant {grid[1]:g} on {grid[2]} cells → work {r['work_ratio']:.2f}×")
    return rows


def fig5_variants() -> tuple[list[dict], list[tuple[int, float]]]:
    """Tolerances `VARIANT_TOLERANCES` on Fig. 5 variants (`FIG5_VARIANTS`: striker velocity,
    contact stiffness, points of bench/sweep.py's grid) against the explicit scheme on 800 and
    1600 cells; and the maximum stress of the first variant over a ladder of grids."""
    rows = []
    for velocity, stiffness in FIG5_VARIANTS:
        case = fig5_variant(velocity, stiffness)
        ref, uncertainty = reference(case, 800)
        for tol in VARIANT_TOLERANCES:
            summary = simulate(parse_case(with_numerics(case, tolerance=tol))).summary
            rows.append({"velocity": velocity, "stiffness": stiffness, "tol": tol,
                         "error": error(summary, ref), "estimate": summary["error_estimate"]["worst"],
                         "uncertainty": uncertainty, "cells": [r["cells"] for r in summary["runs"]]})
            r = rows[-1]
            print(f"  Fig. 5 at {velocity:.2f} m/s, c1 = {stiffness:.3g}, tolerance {tol:g}: error "
                  f"{r['error']:.2e} (estimate {r['estimate']:.2e}, reference uncertainty "
                  f"{uncertainty:.0e}), grids {r['cells']}")
    case = fig5_variant(*FIG5_VARIANTS[0])
    ladder = [(cells, quantities(simulate(parse_case(with_numerics(
        case, scheme="explicit", cells=cells, time_step=courant_one(case, cells)))).summary)["max_stress"])
        for cells in (100, 130, 200, 400, 800, 1600)]
    print("  its maximum stress: " + ", ".join(f"{v / 1e6:.2f} MPa on {c}" for c, v in ladder))
    return rows, ladder


def lucky_hits(ladder: dict, tol: float) -> list[tuple[float, str, int]]:
    """Grids meeting `tol` although a finer grid of the same scheme does not."""
    settled = {scheme: cells for _, scheme, cells in meeting(ladder, tol)}
    return [(cpu, scheme, cells) for scheme, rows in ladder.items() for cells, _, cpu, err in rows
            if err <= tol and cells < settled.get(scheme, math.inf)]


def cheapest_for(scheme: str, rows, target) -> str:
    hits = meeting({scheme: rows}, target)
    if not hits:
        return "—"
    cpu, _, cells = hits[0]
    return f"{cpu * 1e3:.2f} ms ({cells})"


def write(results: dict, closed: list[dict], variants: tuple) -> None:
    lines = [
        "# Speed against accuracy",
        "",
        "Written by `bench/accuracy_vs_cost.py --write` (rerun it to check). Error: the largest "
        "relative error of co-impact time, peak contact force and maximum stress against a "
        "reference (the explicit scheme at Courant number 1 on two fine grids, Richardson-"
        "extrapolated). Cost: CPU time of one `simulate` call on one core, the least over repeats, "
        "after compilation. All schemes at Courant number 1, on ladders of cells 2^(k/4)·10. A grid "
        "meets an accuracy when it and every finer grid of its ladder do.",
        "",
        "## Cheapest run that reaches an accuracy (CPU time, and cells)",
        "",
        f"| preset | scheme | error ≤ 1e-2 | error ≤ 1e-3 | error ≤ 1e-4 | error at {LADDER[-1]} cells |",
        "|---|---|---|---|---|---|",
    ]
    for name, r in results.items():
        for scheme, rows in r["ladder"].items():
            lines.append(f"| {name} | {scheme} | " + " | ".join(cheapest_for(scheme, rows, t) for t in TARGETS)
                         + f" | {rows[-1][3]:.1e} |")
    lines += [
        "",
        "## Tolerance-driven runs (`numerics.tolerance`)",
        "",
        "| preset | tolerance | true error | estimate | chosen | runs | CPU | cheapest fixed grid meeting it | ratio (CPU) | ratio (work) | coarser grids meeting it by luck |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for name, r in results.items():
        for t in r["tolerance"]:
            cpu, scheme, cells = t["cheapest"]
            lines.append(
                f"| {name} | {t['tol']:g} | {t['error']:.1e} | {t['estimate']:.1e} | {t['model']}, "
                f"{t['scheme']}, {t['cells']} cells | {t['runs']} | {t['cpu'] * 1e3:.2f} ms | "
                f"{scheme} {cells} cells, {cpu * 1e3:.2f} ms | {t['ratio']:.2f}× | "
                f"{t['work_ratio']:.2f}× | {', '.join(t['lucky']) or '—'} |")
    lines += [
        "",
        "Work: node-steps ((cells + 1) × steps) summed over the grids a run tried, against the "
        "cheapest fixed grid's. Reference uncertainty: "
        + ", ".join(f"{n} {r['uncertainty']:.0e}" for n, r in results.items())
        + ". Errors far below it are not meaningful.",
        "",
        "## Tolerance-driven runs on closed forms",
        "",
        "Linear impacts on a long rod (`solver.reference.LinearImpact`), whose co-impact time, "
        "peak force and peak stress are known exactly; the cheapest fixed grid is searched over "
        "every scheme at Courant number 1 and ½.",
        "",
        "| contact damping ratio ζ | striker | tolerance | true error | estimate | grids | cheapest fixed grid | ratio (work) |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for c in closed:
        scheme, courant, cells = c["grid"]
        lines.append(f"| {c['zeta']:g} | {c['m1']:g} kg | {c['tol']:g} | {c['error']:.1e} | "
                     f"{c['estimate']:.1e} | {', '.join(map(str, c['cells']))} | {scheme}, Courant "
                     f"{courant:g}, {cells} cells | {c['work_ratio']:.2f}× |")
    rows, ladder = variants
    lines += [
        "",
        "## Tolerances 1e-2 and 1e-3 on Fig. 5 variants",
        "",
        "Points of `bench/sweep.py`'s grid, against the explicit scheme on 800 and 1600 cells "
        "(Richardson); a true error below about the reference uncertainty is not meaningful. "
        "Repeated impacts make the maximum stress converge irregularly; on the first variant: "
        + ", ".join(f"{v / 1e6:.2f} MPa on {c}" for c, v in ladder) + " cells.",
        "",
        "| striker | contact stiffness | tolerance | true error | estimate | reference uncertainty | grids |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(f"| {r['velocity']:.2f} m/s | {r['stiffness']:.3g} | {r['tol']:g} | {r['error']:.1e} | "
                     f"{r['estimate']:.1e} | {r['uncertainty']:.0e} | "
                     f"{', '.join(map(str, r['cells']))} |")
    lines += [
        "",
        "![error against CPU time](accuracy_vs_cost.png)",
        "",
    ]
    (ROOT / "docs" / "accuracy_vs_cost.md").write_text("\n".join(lines))
    quote_in_readme(lines)
    plot(results)


def quote_in_readme(lines: list[str]) -> None:
    """Replace what stands between the README's markers with the tables."""
    tables = "\n".join(("##" + line) if line.startswith("## ") else line for line in lines
                       if not line.startswith(("# ", "Written by", "![")))
    readme = ROOT / "README.md"
    text = readme.read_text()
    start = text.index("<!-- accuracy_vs_cost")
    start = text.index("\n", start) + 1
    end = text.index("<!-- /accuracy_vs_cost -->")
    readme.write_text(text[:start] + tables.strip() + "\n" + text[end:])


def plot(results: dict) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(results), figsize=(5 * len(results), 4.2), sharey=True)
    for ax, (name, r) in zip(axes, results.items()):
        for scheme, rows in r["ladder"].items():
            rows = np.array(rows)
            ax.loglog(rows[:, 2] * 1e3, rows[:, 3], "o-", ms=3, label=scheme)
        t = r["tolerance"]
        ax.loglog([x["cpu"] * 1e3 for x in t], [x["error"] for x in t], "k*", ms=10,
                  label="numerics.tolerance")
        for x in t:
            ax.axhline(x["tol"], color="0.85", lw=0.8, zorder=0)
        ax.set_title(name)
        ax.set_xlabel("CPU time per run (ms)")
        ax.grid(True, which="major", alpha=0.3)
    axes[0].set_ylabel("largest relative error")
    axes[0].legend()
    fig.tight_layout()
    fig.savefig(ROOT / "docs" / "accuracy_vs_cost.png", dpi=120)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--write", action="store_true", help="write docs/accuracy_vs_cost.{md,png}")
    args = parser.parse_args()
    warm_up()
    results = {name: measure(name) for name in PRESETS}
    print("\nclosed forms:")
    closed = closed_forms()
    print("\nFig. 5 variants:")
    variants = fig5_variants()
    if args.write:
        write(results, closed, variants)


if __name__ == "__main__":
    main()
