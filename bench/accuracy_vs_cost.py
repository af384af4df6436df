"""The speed/accuracy trade of each scheme, measured: a ladder of grids on three presets against a
converged reference from an independent method.

    .venv/bin/python bench/accuracy_vs_cost.py [--write]

For each preset (Fig. 3: uniform tool and medium; Fig. 5: short hard contact, 20 ms of repeated
impacts; Fig. 9: conical tool, abs-sine force, repeated contacts) the case's own numerics are
replaced by each scheme in turn (the paper's γ = 0.5, σ = 1/4, and the explicit scheme whose ends
integrate their own equations, all at Courant number 1) on cells 2^(k/4)·10, 10 … 640. A run's
error is its largest relative error over every headline quantity the reference has (the
characteristics solver converged, as in `bench/matrix.py`, whose cache it shares); its cost the
least CPU time of one `simulate_rod` call over repeats, after compilation: the run alone, without
the companion runs that estimate a fixed grid's error. A grid meets an accuracy when it and every
finer grid of its ladder do; a grid the scheme refuses (a contact too stiff for its ends on so few
cells) meets none.

`--write` writes `docs/accuracy_vs_cost.md`, `docs/accuracy_vs_cost.png` and the table quoted in
README.md (between its `accuracy_vs_cost` markers).
"""

from __future__ import annotations

import argparse
import importlib.util
import math
import time
from pathlib import Path

from marked import write_marked

from percussim.solver.accuracy import estimated_values
from percussim.solver.case import CaseError, parse_case
from percussim.solver.controller import simulate_rod, warm_up
from percussim.solver.grid import resolve_numerics, wave_speed
from percussim.testing import at_default_accuracy

ROOT = Path(__file__).resolve().parents[1]

_spec = importlib.util.spec_from_file_location("matrix_bench", ROOT / "bench" / "matrix.py")
matrix_bench = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(matrix_bench)

PRESETS = ("fig3", "fig5", "fig9")
SCHEMES = ("paper", "sigma", "explicit")
LADDER = [round(10 * 2 ** (k / 4)) for k in range(25)]  # 10 … 640 cells
TARGETS = (1e-2, 1e-3, 1e-4)


def timed(case, numerics, budget: float = 0.05) -> tuple[dict, float]:
    """The summary and the least CPU time of at least 3 runs, repeated until they took `budget`."""
    best, spent, runs, summary = math.inf, 0.0, 0, None
    while runs < 3 or spent < budget:
        start = time.process_time()
        summary = simulate_rod(case, numerics=numerics).summary
        took = time.process_time() - start
        best, spent, runs = min(best, took), spent + took, runs + 1
    return summary, best


def measure(name: str) -> dict:
    data = at_default_accuracy(name)
    case = parse_case(data)
    ref = matrix_bench.reference(data)
    ladder = {}
    for scheme in SCHEMES:
        rows = []
        for cells in LADDER:
            tau = case.tool.length / cells / wave_speed(case.tool)
            try:
                numerics = resolve_numerics(case, model="rod", scheme=scheme, cells=cells, time_step=tau)
            except CaseError:  # a contact too stiff for this scheme's ends on so few cells
                rows.append((cells, math.nan, math.inf))
                continue
            summary, cpu = timed(case, numerics)
            errors = matrix_bench.true_errors(estimated_values(summary), ref)
            rows.append((cells, cpu, max(errors.values())))
        ladder[scheme] = rows
        print(name, scheme, " ".join(f"{c}:{e:.1e}/{t * 1e3:.2f}ms" for c, t, e in rows), flush=True)
    return {"reference": ref, "ladder": ladder}


def cheapest(rows, target: float) -> tuple[float, int] | None:
    """(CPU time, cells) of the coarsest grid from which every finer one meets `target`."""
    found = None
    for cells, cpu, error in reversed(rows):
        if error > target:
            break
        found = (cpu, cells)
    return found


def table(results: dict) -> str:
    lines = [
        f"| preset | scheme | error ≤ 1e-2 | error ≤ 1e-3 | error ≤ 1e-4 | error at {LADDER[-1]} cells |",
        "|---|---|---|---|---|---|",
    ]
    for name, r in results.items():
        for scheme, rows in r["ladder"].items():
            cells = []
            for target in TARGETS:
                hit = cheapest(rows, target)
                cells.append(f"{hit[0] * 1e3:.2f} ms ({hit[1]})" if hit else "—")
            lines.append(f"| {name} | {scheme} | " + " | ".join(cells) + f" | {rows[-1][2]:.1e} |")
    return "\n".join(lines)


def plot(results: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(results), figsize=(4.2 * len(results), 3.8), sharey=True)
    for ax, (name, r) in zip(axes, results.items()):
        for scheme, marker in zip(SCHEMES, "osD"):
            cells, cpu, error = zip(*(row for row in r["ladder"][scheme] if math.isfinite(row[2])))
            ax.loglog([1e3 * t for t in cpu], error, marker + "-", ms=3.5, label=scheme)
        ax.set_title(name)
        ax.set_xlabel("CPU time of one run (ms)")
        ax.grid(True, which="both", alpha=0.3)
    axes[0].set_ylabel("largest relative error")
    axes[0].legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--write", action="store_true")
    args = parser.parse_args()
    warm_up()
    results = {name: measure(name) for name in PRESETS}
    found = table(results)
    print(found)
    if not args.write:
        return
    text = [
        "# Speed against accuracy",
        "",
        "Written by `bench/accuracy_vs_cost.py --write` (rerun it to check). Error: the largest "
        "relative error over the headline quantities against the converged reference of an "
        "independent method (the characteristics solver). Cost: CPU time of one run on one core, "
        "the least over repeats, after compilation, without the companion runs that estimate a "
        "fixed grid's error. All schemes at Courant number 1, on ladders of cells 2^(k/4)·10. A "
        "grid meets an accuracy when it and every finer grid of its ladder do.",
        "",
        "## Cheapest run that reaches an accuracy (CPU time, and cells)",
        "",
        found,
        "",
        "![largest relative error against CPU time](accuracy_vs_cost.png)",
        "",
    ]
    (ROOT / "docs" / "accuracy_vs_cost.md").write_text("\n".join(text))
    plot(results, ROOT / "docs" / "accuracy_vs_cost.png")
    write_marked(ROOT / "README.md", "accuracy_vs_cost", found)


if __name__ == "__main__":
    main()
