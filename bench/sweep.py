"""Sweeps of the Fig. 5 preset: variants per second on one core, on every core, and through the
service (Redis and 2 workers), side by side.

    .venv/bin/python bench/sweep.py [--variants 400] [--spread [PRESET] [--rung 4]]

The sweep is striker velocity × contact stiffness over the Fig. 5 preset (20 ms of repeated
impacts), run twice: with the preset's own numerics (the paper's 5 cells and τ = 2e-5 s: about
0.1 ms a variant, where the per-variant cost is all overhead) and with `numerics.tolerance` =
1e-2 (the solver's own ladder to 1% accuracy: tens of milliseconds a variant). Times are wall
clock from the call to the last row; the service's from the POST to the GET that shows the sweep
finished (polled every 20 ms), with every variant a job that writes its HDF5 result. Last, the
ratio of the two sweeps' times, each way of running them, from this run, and how far apart the
two sweeps' answers are: what the cheap sweep's speed is bought with.

`--spread` instead solves each variant of the tolerance's sweep alone, in this process, and prints
how its time is spread over the variants: the median and the 90th percentile, the share of the
costliest twentieth, the share of the work on each variant's final grid and on the grids its own
estimate needs (what no start from a neighbour can save), and the costliest variants with their
grids and what their estimate says. Then it solves them again, in turn, each ladder reaching its
first estimate on the final grid of its nearest neighbour solved before it, and once more with
only the variants whose two neighbours' final grids agree started so, and prints those times
against the first. `--spread fig3` does the same over another preset (the same two parameters);
`--rung K` puts the neighbour's final grid at the ladder's K-th grid instead (K > 4: a start
further below it). `--truth` adds each way's true errors against the variants' references, as
`bench/matrix.py` finds and counts them (the first time, minutes for each hundred Fig. 3 variants).
"""

from __future__ import annotations

import argparse
import math
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import NamedTuple
from unittest import mock

from matrix import counted, reference, true_errors

from percussim.solver import adaptive
from percussim.solver.accuracy import Accuracy, estimated_values
from percussim.solver.adaptive import CLIMB, MIN_RUNS, solve
from percussim.solver.controller import warm_up
from percussim.solver.presets import preset_json
from percussim.solver.simulate import run_sweep
from percussim.solver.sweep import Sweep, variants
from percussim.testing import merge
from percussim.testing.live_stack import Stack, redis_server, wait_for


def at_tolerance(preset: str) -> dict:
    """The preset with its numerics replaced by a tolerance of 1e-2."""
    return merge(
        preset_json(preset), {"numerics": {"cells": None, "time_step": None, "gamma": None, "tolerance": 1e-2}}
    )


AGREE = 1.5  # --spread: neighbours' final grids this close agree

CASES = {"preset numerics": preset_json("fig5"), "tolerance 1e-2": at_tolerance("fig5")}


def parameters(variants: int) -> dict[str, list[float]]:
    side = round(math.sqrt(variants))
    return {
        "striker.velocity": [2.0 + 8.0 * k / (side - 1) for k in range(side)],
        "contact.stiffness": [1e11 * 16 ** (k / (side - 1)) for k in range(side)],
    }


def through_service(stack: Stack, case: dict, grid: dict) -> tuple[list[dict], float]:
    start = time.perf_counter()
    answer = stack.client.post("/v1/sweeps", json={"case": case, "parameters": grid})
    assert answer.status_code == 202, answer.text
    url = f"/v1/sweeps/{answer.json()['id']}"
    sweep = wait_for(lambda: (v := stack.client.get(url).json())["finished"] and v, 600, "the sweep", interval=0.02)
    return sweep["rows"], time.perf_counter() - start


class Solved(NamedTuple):
    seconds: float
    accuracy: Accuracy
    values: dict[str, float | None]  # what its error is estimated for (`estimated_values`)


def alone(cases: list, first: Callable[[int, list[Solved]], int | None] | None = None) -> list[Solved]:
    """Each case solved alone in this process, in turn. `first(k, solved)`, given the cases solved
    before the k-th, is that case's coarsest grid, or None for the ladder's own a-priori one
    (`first_cells`); the larger of the two is taken."""
    solved: list[Solved] = []
    for k, case in enumerate(cases):
        start_on = first(k, solved) if first else None
        own = adaptive.first_cells
        chosen = own if start_on is None else (lambda of, tol: max(own(of, tol), start_on))
        with mock.patch.object(adaptive, "first_cells", chosen):
            start = time.perf_counter()
            result, accuracy = solve(case)
        solved.append(Solved(time.perf_counter() - start, accuracy, estimated_values(result.summary)))
    return solved


def true_error_line(solved: list[Solved], references: list[dict], tolerance: float) -> str:
    """How the answers' true errors (over the quantities each estimates) stand against the
    references where they are 10× tighter than `tolerance`: as `bench/matrix.py` counts them."""
    worst, beyond, silent, held = 0.0, 0, 0, 0
    for one, ref in zip(solved, references, strict=True):
        if not counted(ref, tolerance):
            continue
        held += 1
        estimate = one.accuracy.estimate
        errors = [e for name, e in true_errors(one.values, ref).items() if name in estimate.errors]
        error = max(errors, default=0.0)
        worst = max(worst, error)
        beyond += error > tolerance
        silent += error > tolerance and estimate.worst < error
    return (
        f"true error against {held} references: worst {worst / tolerance:.2f}× the tolerance, {beyond} beyond it, "
        f"{silent} silent"
    )


def work(accuracy: Accuracy) -> list[int]:
    """The node-steps of each grid a ladder ran."""
    return [(n.cells + 1) * (n.steps + 1) for n in accuracy.runs]


def spread(grid: dict[str, list[float]], preset: str, rung: int, truth: bool) -> None:
    """Each variant of the preset's sweep at the tolerance alone: how the sweep's time is spread
    over them, and what a start with a neighbour's final grid as its `rung`-th grid does to it;
    with `truth`, each way's true errors against the variants' references."""
    tolerance = 1e-2
    sweep = Sweep(case=at_tolerance(preset), parameters=grid)
    found = list(variants(sweep.model_copy(update={"case": sweep.case.summary_only()})))
    cases = [case for _, case in found]
    references = [reference(case.model_dump(mode="json", exclude_none=True)) for case in cases] if truth else []
    cold = alone(cases)
    runs = sorted(((one.seconds, values, one.accuracy) for (values, _), one in zip(found, cold)), key=lambda r: r[0])
    seconds = [run[0] for run in runs]
    total, count = sum(seconds), len(seconds)
    costly = max(1, count // 20)
    print(f"\n{preset} at tolerance 1e-2, {count} variants each alone, {total:.3g} s in all:")
    print(f"  median {1e3 * seconds[count // 2]:.1f} ms, 90th percentile {1e3 * seconds[int(0.9 * count)]:.1f} ms")
    print(
        f"  the costliest {costly} ({100 * costly / count:.0f}%) take {100 * sum(seconds[-costly:]) / total:.0f}% of it:"
    )
    # What any start could save: each variant must still run its final grid, for its own answer,
    # and the coarser grids its own estimate needs: `MIN_RUNS` in all, each `CLIMB` times finer.
    works = [work(one.accuracy) for one in cold]
    ladders, finals = sum(map(sum, works)), sum(w[-1] for w in works)
    least = sum(w[-1] * CLIMB ** (-2 * k) for w in works for k in range(MIN_RUNS))
    print(
        f"  node-steps: {ladders:.3g} on the variants' ladders; {100 * finals / ladders:.0f}% of them on their final "
        f"grids; ladders that took their first estimate on each variant's final grid (it and {MIN_RUNS - 1} grids "
        f"below it, each 2× coarser) would do {100 * least / ladders:.0f}% of that work"
    )
    for took, values, accuracy in reversed(runs[-5:]):
        met = "not met" if any("not met" in w for w in accuracy.warnings) else "met"
        worst = accuracy.estimate.worst if accuracy.estimate else float("nan")
        grids = ", ".join(str(n.cells) for n in accuracy.runs)
        print(f"    {took:8.4f} s {values}: estimate {worst:.1e} ({met}), grids {grids}")
    if truth:
        print(f"  {true_error_line(cold, references, tolerance)}")
    # The starts a study could take: a variant's `rung`-th grid (the fourth is its first with an
    # estimate) on the final grid of a neighbour solved before it (the one before it along either
    # parameter), its ladder and its own estimate as they are from there. Either the nearer to it
    # of the two, the coarser; or only where both are there and agree within `AGREE`.
    side = len(next(reversed(grid.values())))

    def neighbour_grids(k: int, solved: list[Solved]) -> list[int]:
        return [solved[q].accuracy.runs[-1].cells for q in (k - 1, k - side) if q >= 0 and (q != k - 1 or k % side)]

    apart = [min(neighbour_grids(k, cold)) / one.accuracy.runs[-1].cells for k, one in enumerate(cold) if k]
    print(
        f"  a variant's final grid against its nearest neighbour's: within {AGREE}× in "
        f"{sum(1 / AGREE <= r <= AGREE for r in apart)} of {len(apart)}, the neighbour's 2× finer or more in "
        f"{sum(r >= 2 for r in apart)}, 2× coarser or more in {sum(r <= 0.5 for r in apart)}"
    )

    def nearest(k: int, solved: list[Solved]) -> int | None:
        near = neighbour_grids(k, solved)
        return math.ceil(min(near) / CLIMB ** (rung - 1)) if near else None

    def agreeing(k: int, solved: list[Solved]) -> int | None:
        near = neighbour_grids(k, solved)
        return nearest(k, solved) if len(near) == 2 and max(near) <= AGREE * min(near) else None

    starts = {
        "its nearest neighbour's final grid": nearest,
        f"its two neighbours' final grid where they agree within {AGREE}× (else as alone)": agreeing,
    }
    for how, first in starts.items():
        started = alone(cases, first)
        moved = sum(a.accuracy.runs[-1].cells != c.accuracy.runs[-1].cells for a, c in zip(started, cold))
        again = sum(one.seconds for one in started)
        print(
            f"  started with {how} as grid {rung}: {again:.3g} s in all ({again / total:.2f}× alone), "
            f"node-steps {sum(sum(work(one.accuracy)) for one in started):.3g}; {moved} of {count} end on another grid"
        )
        if truth:
            print(f"    {true_error_line(started, references, tolerance)}")


# The sweep table's columns that the tolerance's answers are trusted to 1% on.
COMPARED = (
    "co_impact_time",
    "peak_contact_force",
    "max_compressive_stress",
    "max_tensile_stress",
    "energy_to_medium",
    "striker_rebound_velocity",
)


def answers_apart(fixed: list[dict], tolerant: list[dict], tolerance: float) -> None:
    """What the cheap sweep answers, against the sweep whose every variant is within the tolerance
    by its own estimate: each quantity's relative difference over the variants both answered."""
    pairs = [
        (f, t)
        for f, t in zip(fixed, tolerant, strict=True)
        if not f.get("error") and not t.get("error") and (t.get("estimated_error") or 0.0) <= tolerance
    ]
    print(f"\nThe preset numerics' answers against the tolerance's, {len(pairs)} variants both answered within it:")
    print(f"  {'quantity':28s} {'median':>8s} {'90th pct':>9s} {'largest':>8s}  beyond {tolerance:g}")
    for column in COMPARED:
        apart = sorted(
            abs(f[column] / t[column] - 1.0) for f, t in pairs if f[column] is not None and t[column] not in (None, 0.0)
        )
        beyond = sum(d > tolerance for d in apart)
        print(
            f"  {column:28s} {apart[len(apart) // 2]:8.1%} {apart[int(0.9 * len(apart))]:9.1%} {apart[-1]:8.1%}"
            f"  {beyond} of {len(apart)}"
        )
    counts = sum(f["contacts"] != t["contacts"] for f, t in pairs)
    print(f"  a different number of contacts in {counts} of {len(pairs)}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--variants", type=int, default=400, help="about this many (a square grid)")
    parser.add_argument(
        "--spread", nargs="?", const="fig5", metavar="PRESET", help="each variant alone: how the time is spread"
    )
    parser.add_argument("--rung", type=int, default=MIN_RUNS, help="--spread: the neighbour's grid as which grid")
    parser.add_argument("--truth", action="store_true", help="--spread: true errors against references")
    args = parser.parse_args()
    warm_up()
    grid = parameters(args.variants)
    if args.spread:
        spread(grid, args.spread, args.rung, args.truth)
        return
    with tempfile.TemporaryDirectory() as tmp, redis_server(Path(tmp) / "redis") as url:
        stack = Stack(Path(tmp), url, workers=2)
        try:
            seconds_by, rows_by = {}, {}  # (case, how) → seconds and rows, for the same run's ratios
            for label, case in CASES.items():
                sweep = Sweep(case=case, parameters=grid)
                figures = {}
                for processes in (1, 2):
                    start = time.perf_counter()
                    rows = run_sweep(sweep, processes=processes)
                    figures[f"run_sweep, {processes} process{'es' if processes > 1 else ''}"] = (
                        rows,
                        time.perf_counter() - start,
                    )
                figures["service, Redis, 2 workers"] = through_service(stack, case, grid)
                print(f"\nFig. 5, {label}:")
                tolerance = case["numerics"].get("tolerance")
                for how, (rows, seconds) in figures.items():
                    seconds_by[label, how], rows_by[label, how] = seconds, rows
                    failed = [r for r in rows if r.get("error")]
                    unmet = [r for r in rows if tolerance and (r.get("estimated_error") or 0.0) > tolerance]
                    print(
                        f"  {how:28s} {len(rows):5d} variants in {seconds:7.2f} s: "
                        f"{len(rows) / seconds:8.1f} variants/s, {len(failed)} failed"
                        + (f", {len(unmet)} saying the tolerance is not met" if tolerance else "")
                    )
                    for row in failed[:3]:
                        values = row.get("values") or {k: row[k] for k in grid}
                        print(f"    {values}: {row['error']}")
            fixed, tolerant = CASES
            print(f"\nThe sweep's cost at {tolerant} against {fixed}, this run's times:")
            for how in figures:
                print(f"  {how:28s} {seconds_by[tolerant, how] / seconds_by[fixed, how]:8.0f}×")
            one = "run_sweep, 1 process"
            answers_apart(rows_by[fixed, one], rows_by[tolerant, one], CASES[tolerant]["numerics"]["tolerance"])
        finally:
            stack.stop()


if __name__ == "__main__":
    main()
