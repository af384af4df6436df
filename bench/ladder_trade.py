"""What the ladder's margins buy: the matrix of `bench/matrix.py` run under other settings of the
estimator and the ladder, each changing one margin of the shipped one (then all of them at once),
with the worst true error and the cost of each.

    .venv/bin/python bench/ladder_trade.py [--count 72] [--processes 2] [--write]

A setting changes the named constants of `solver.accuracy` and `solver.adaptive` in the processes
that run the cases. The references and the cheapest fixed grids are `bench/matrix.py`'s, from its
cache (run `bench/matrix.py --prepare` first on a fresh clone). `--write` writes
`docs/ladder_trade.md`.
"""

from __future__ import annotations

from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import matrix as bench_matrix

from percussim.solver import accuracy, adaptive, grid
from percussim.solver.controller import warm_up
from percussim.solver.matrix import draw_cases

ROOT = Path(__file__).resolve().parents[1]

LOOSE = {"MIN_RUNS": 3, "SAFETY_FACTOR": 1.0, "UNCONFIRMED_ORDER": 2.0, "LOWEST_ORDER": 1.0}
SETTINGS = [
    ("shipped", {}),
    ("three grids, the order not confirmed by a fourth", {"MIN_RUNS": 3}),
    ("no safety factor (1.25 → 1)", {"SAFETY_FACTOR": 1.0}),
    ("an unconfirmed order trusted up to 2 (not 1)", {"UNCONFIRMED_ORDER": 2.0}),
    (
        "grids observed under order 1 (not 0.5) taken as out of their asymptotic range, and read at order 1",
        {"LOWEST_ORDER": 1.0},
    ),
    ("predicted grids aim at the tolerance (not 0.75×)", {"AIM": 1.0}),
    ("no predicted grid less than 2× finer (not 1.2×)", {"MIN_STEP": 2.0}),
    ("a first grid of 2 steps over the contact (not 4)", {"FIRST_POINTS": 2.0}),
    ("all four estimator margins loosened", LOOSE),
]


def apply(overrides: dict) -> None:
    """Set the constants in the modules that hold them (each, where one module imported another's)."""
    for name, value in overrides.items():
        for module in (accuracy, adaptive, grid):
            if hasattr(module, name):
                setattr(module, name, value)


def run_setting(overrides: dict, cases: list[dict], processes: int) -> dict:
    with ProcessPoolExecutor(processes, initializer=apply, initargs=(overrides,)) as pool:
        results = list(pool.map(bench_matrix.measure, cases))
    return bench_matrix.summarise(results)


def table(rows: list[tuple[str, dict]]) -> str:
    lines = [
        "| setting | "
        + " | ".join(
            f"{tol:g}: worst true / tol | beyond tol | beyond 1.5× | silent misses | cost median | final grid alone "
            "| as accurate"
            for tol in bench_matrix.TOLERANCES
        )
        + " |",
        "|---|" + "---|---|---|---|---|---|---|" * len(bench_matrix.TOLERANCES),
    ]
    for name, stats in rows:
        cells = []
        for tol in bench_matrix.TOLERANCES:
            s = stats[str(tol)]
            cells.append(
                f"{s['worst_ratio_to_tol']:.2f} | {s['beyond_tol']} | {s['beyond_1_5_tol']} | {s['silent_misses']} | "
                f"{s['cost_median']:.2f}× | {s['final_grid_median']:.2f}× | {s['own_accuracy_median']:.2f}×"
            )
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def main() -> None:
    args = bench_matrix.matrix_parser(__doc__.split("\n\n")[0]).parse_args()
    warm_up()
    cases = draw_cases(args.seed, args.count)
    rows = []
    for name, overrides in SETTINGS:
        rows.append((name, run_setting(overrides, cases, args.processes)))
        print(table(rows[-1:]).splitlines()[-1], flush=True)
    text = table(rows)
    print(text)
    if args.write:
        (ROOT / "docs" / "ladder_trade.md").write_text(
            "# What the ladder's margins buy\n\n"
            f"Written by `bench/ladder_trade.py --write` on the matrix of `bench/matrix.py` "
            f"(seed {args.seed}, {args.count} cases; the cases counted at each tolerance, and the "
            "limits raised tenfold, as there). "
            "Each row changes the named margin of the shipped ladder; the last changes all four of "
            "the estimator's. True error: a run's worst relative error against the reference; cost: "
            "its work against the cheapest fixed grid that meets the same tolerance, found in "
            "hindsight; the final grid alone: the median of the grid each ladder ended on against "
            "the same, the least a start nearer the answer could cost; as accurate: the median of "
            "its work against the cheapest fixed grid whose true error is no larger than its own "
            "(`bench/matrix.py`), what its answer costs beside what it turned out to be worth. A "
            "silent miss: an estimate below a true error beyond the tolerance.\n\n" + text
        )


if __name__ == "__main__":
    main()
