"""The accuracy guarantee, measured: a seeded random matrix of cases over the whole valid parameter
space (`solver.matrix`), each against a converged reference from an independent method (the
characteristics solver, `solver.characteristics`), at tolerances 1e-2 and 1e-3.

    .venv/bin/python bench/matrix.py [--seed 1] [--count 72] [--processes 2] [--prepare] [--write]

For every case:

- the reference: the characteristics solution on grids doubled until the Richardson
  extrapolations of successive triplets agree (`solver.matrix.converged_reference`);
- the cheapest fixed grid that meets each tolerance, found in hindsight: the explicit scheme at
  Courant number 1 on grids 2^(1/4) apart, the coarsest from which every finer one is within the
  tolerance on every quantity the reference has (a grid that meets it by luck between two that
  do not is not counted);
- a run under each tolerance (`numerics.tolerance`, the limits raised): its true error on every
  quantity it estimates, its own estimate, and its work (node-steps over all its grids) against
  that grid's; a silent miss is a run whose estimate is below its true error while that is beyond
  the tolerance;
- the cheapest fixed grid as accurate as each run's answer turned out to be, from the same search:
  the run's work against it separates what the ladder's grids cost from how far within the
  tolerance its estimate's margins land it.

Then, for each of the paper's presets, the time to a 1%-accurate answer (the default accuracy)
after compilation, least of several runs, and its true error.

`--write` writes `docs/matrix.md` and the figures quoted in README.md and docs/numerics.md (between
their `matrix` markers). References are cached in `bench/.cache/` by case, and so are the
fixed-grid searches, keyed also by the solver's whole source and the reference: any change of the
solver searches again (about a minute on two processes).
"""

from __future__ import annotations

import argparse
import functools
import hashlib
import inspect
import json
import math
import statistics
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

from marked import write_marked

from percussim.solver import adaptive, characteristics, matrix
from percussim.solver.accuracy import estimated_values
from percussim.solver.adaptive import explicit_numerics
from percussim.solver.case import parse_case
from percussim.solver.controller import simulate_rod, warm_up
from percussim.solver.grid import wave_speed
from percussim.solver.limits import Limits
from percussim.solver.matrix import converged_reference, draw_cases, reference_cells
from percussim.solver.presets import preset_names
from percussim.solver.simulate import simulate
from percussim.testing import at_default_accuracy

ROOT = Path(__file__).resolve().parents[1]

TOLERANCES = (1e-2, 1e-3)
CACHE = ROOT / "bench" / ".cache"
REFERENCE_TARGET = 5e-5  # the references' aim: 20× below the tightest tolerance
REFERENCE_CELLS = 110_000
# Node-steps on a reference's finest grid (about 100 s of the characteristics solver): a case
# whose reference would need four grids beyond it is left out, saying so, and one whose reference
# is not 10× tighter than a tolerance is not counted at that tolerance.
REFERENCE_WORK = 3e10
FIXED_WORK_CAP = 5e8  # node-steps: the fixed-grid search stops there
PRESET_REPEATS = 20
COUNT = 72  # cases a matrix draws
# The runs under a tolerance: the service's limits raised tenfold, so that a ladder stops on its own
# account (met, or saying why not), not on a limit (one that does is counted apart); a run on the
# largest grid they allow takes minutes (a ladder_trade setting that never converges meets them).
RAISED = Limits(max_cells=10**6, max_steps=2 * 10**8, max_node_steps=2e11, max_output_values=2e9)


def _cached(kind: str, case: dict, depends_on: str) -> Path:
    """Where a result for `case` is cached, keyed by the case and what it depends on."""
    text = json.dumps(case, sort_keys=True) + depends_on
    return CACHE / f"{kind}-{hashlib.sha256(text.encode()).hexdigest()[:16]}.json"


@functools.cache
def solver_source() -> str:
    """The solver's whole source: what a cached fixed-grid run depends on besides its case. A
    version raised by hand was missed once, and the matrix then counted grids searched against an
    earlier reference and an earlier reading of the stresses (seed 1's matrix-10: 6 cells taken to
    meet 1e-2, 11% off on its tension)."""
    package = Path(characteristics.__file__).parent
    return "".join(path.read_text() for path in sorted(package.rglob("*.py")))


def reference(case: dict) -> dict:
    """The case's converged reference, from the cache when the solver has not changed."""
    path = _cached("reference", case, inspect.getsource(characteristics) + inspect.getsource(matrix))
    if path.exists():
        return json.loads(path.read_text())
    start = time.perf_counter()
    parsed = parse_case(case)
    steps_per_cell = parsed.numerics.duration * wave_speed(parsed.tool) / parsed.tool.length
    max_cells = min(REFERENCE_CELLS, int(math.sqrt(REFERENCE_WORK / steps_per_cell)))
    first = reference_cells(parsed)
    if 8 * first > max_cells:  # four grids, the least an uncertainty is found from
        found = {
            "skipped": f"its reference would take {steps_per_cell * (8 * first) ** 2:.1e} "
            f"node-steps on its finest grid, over {REFERENCE_WORK:.0e}"
        }
    else:
        ref = converged_reference(parsed, target=REFERENCE_TARGET, max_cells=max_cells)
        found = {
            "values": ref.values,
            "uncertainty": ref.uncertainty,
            "left_out": ref.left_out,
            "cells": ref.cells,
            "contacts": ref.finest.contacts,
            "seconds": time.perf_counter() - start,
        }
    CACHE.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(found))
    return found


def true_errors(values: dict, ref: dict) -> dict[str, float]:
    """Relative errors of `values` on the quantities the reference has (inf where a run lacks one)."""
    errors = {}
    for name, truth in ref["values"].items():
        found = values.get(name)
        errors[name] = math.inf if found is None else abs(found / truth - 1.0) if truth else 0.0
    return errors


def work(numerics) -> float:
    return float((numerics.cells + 1) * (numerics.steps + 1))


def fixed_grids(case_json: dict, ref: dict) -> list[dict]:
    """The worst true error of the explicit scheme at Courant number 1 on grids 2^(1/4) apart,
    from the cache when neither the solver nor the reference has changed."""
    path = _cached("fixed", case_json, solver_source() + json.dumps(ref["values"], sort_keys=True))
    if path.exists():
        return json.loads(path.read_text())
    case = parse_case(case_json)
    rows = []
    for k in range(80):
        cells = max(2, round(2 * 2 ** (k / 4)))
        if rows and cells == rows[-1]["cells"]:
            continue
        numerics = explicit_numerics(case, cells)
        if work(numerics) > FIXED_WORK_CAP:
            break
        summary = simulate_rod(case, numerics=numerics).summary
        worst = max(true_errors(estimated_values(summary), ref).values(), default=0.0)
        rows.append({"cells": cells, "work": work(numerics), "worst": worst})
        if len(rows) >= 4 and all(r["worst"] <= min(TOLERANCES) / 20 for r in rows[-4:]):
            break
    CACHE.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(rows))
    return rows


def cheapest_within(rows: list[dict], target: float) -> dict | None:
    """The least work of a fixed grid from which every finer one is within `target` (None: not
    within FIXED_WORK_CAP)."""
    best = None
    for row in reversed(rows):
        if row["worst"] > target:
            break
        best = row
    # a grid counts only if the search went finer than it while still within the target
    return best if best is not None and best is not rows[-1] else None


# The least true error a fixed grid is sought for: the searches stop once four grids in a row are
# within it, and a reference 10× tighter than the tightest tolerance vouches for no less
OWN_ACCURACY_FLOOR = min(TOLERANCES) / 20


def tolerance_run(case, tol: float, ref: dict) -> dict:
    run_case = case.model_copy(update={"numerics": case.numerics.model_copy(update={"tolerance": tol})})
    start = time.process_time()
    summary = simulate(run_case, limits=RAISED).summary
    seconds = time.process_time() - start
    estimate = summary["error_estimate"]
    errors = {name: e for name, e in true_errors(estimated_values(summary), ref).items() if name in estimate}
    return {
        "errors": errors,
        "estimate": {k: v for k, v in estimate.items() if k != "worst"},
        "worst": max(errors.values(), default=0.0),
        "estimated": estimate["worst"],
        "work": sum((r["cells"] + 1) * (r["steps"] + 1) for r in summary["runs"]),
        "final_work": (summary["runs"][-1]["cells"] + 1) * (summary["runs"][-1]["steps"] + 1),
        "cells": [r["cells"] for r in summary["runs"]],
        "on_fewest_grids": len(summary["runs"]) == adaptive.MIN_RUNS,
        "seconds": seconds,
        "warnings": summary["warnings"],
        "missed": [name for name in ref["values"] if name not in estimate],
    }


def prepare(case_json: dict) -> dict:
    """The case's reference and fixed grids, into the cache."""
    ref = reference(case_json)
    if "skipped" in ref:
        return {"name": case_json["name"], "skipped": ref["skipped"]}
    rows = fixed_grids(case_json, ref)
    return {"name": case_json["name"], "reference_seconds": ref["seconds"], "fixed_grids": len(rows)}


def counted(ref: dict, tol: float) -> bool:
    """Whether a case's reference is tight enough to hold a run to `tol`."""
    return "skipped" not in ref and max(ref["uncertainty"].values(), default=0.0) <= tol / 10


def measure(case_json: dict) -> dict:
    case = parse_case(case_json)
    ref = reference(case_json)
    if "skipped" in ref:
        return {"name": case_json["name"], "case": case_json, "reference": ref, "runs": {}}
    rows = fixed_grids(case_json, ref)
    runs = {}
    for tol in TOLERANCES:
        if not counted(ref, tol):
            continue
        run = tolerance_run(case, tol, ref)
        best = cheapest_within(rows, tol)
        run["cheapest_cells"] = best["cells"] if best else None
        run["ratio"] = run["work"] / best["work"] if best else None
        run["final_ratio"] = run["final_work"] / best["work"] if best else None
        # against a fixed grid as accurate as the answer turned out to be: what the ladder's work
        # costs beside what its answer is worth, apart from how far below the tolerance it lands
        as_accurate = cheapest_within(
            rows, max(run["worst"], OWN_ACCURACY_FLOOR, 10 * max(ref["uncertainty"].values(), default=0.0))
        )
        run["own_cells"] = as_accurate["cells"] if as_accurate else None
        run["own_ratio"] = run["work"] / as_accurate["work"] if as_accurate else None
        runs[str(tol)] = run
    return {"name": case_json["name"], "case": case_json, "reference": ref, "runs": runs}


def describe(case: dict) -> str:
    """A case in a few words: tool shape, contact exponent and damping ratio ζ, medium, force."""
    tool = case["tool"]
    shape = (
        "uniform"
        if "area" in tool
        else (
            "tapered" if len(tool["profile"]["x"]) == 2 else "stepped" if len(tool["profile"]["x"]) == 4 else "conical"
        )
    )
    medium = "no medium" if "medium" not in case else f"c2 {case['medium']['stiffness']:.0e}"
    force = case.get("force", {}).get("kind", "no force")
    return (
        f"{case['striker']['mass']:.3g} kg at {case['striker']['velocity']:.3g} m/s, {shape} "
        f"{tool['length']:.2g} m, α {case['contact']['exponent']:.2g}, c1 "
        f"{case['contact']['stiffness']:.1e}, {medium}, {force}"
    )


def presets() -> list[dict]:
    """Time to a 1%-accurate answer on each preset (the default accuracy), and its true error."""
    rows = []
    for name in preset_names():
        data = at_default_accuracy(name)
        case = parse_case(data)
        if case.beyond_paper:  # the characteristics reference solves the paper's model only
            continue
        ref = reference(data)
        simulate(case)
        best = math.inf
        for _ in range(PRESET_REPEATS):
            start = time.perf_counter()
            summary = simulate(case).summary
            best = min(best, time.perf_counter() - start)
        errors = true_errors(estimated_values(summary), ref)
        rows.append(
            {
                "name": name,
                "ms": 1e3 * best,
                "worst": max(errors.values()),
                "estimated": summary["error_estimate"]["worst"],
                "cells": [r["cells"] for r in summary["runs"]],
                "not_met": any("not met" in w for w in summary["warnings"]),
            }
        )
    return rows


def summarise(results: list[dict]) -> dict:
    out = {}
    for tol in TOLERANCES:
        runs = [r["runs"][str(tol)] for r in results if str(tol) in r["runs"]]
        ratios = [r["ratio"] for r in runs if r["ratio"] is not None]
        own = [r["own_ratio"] for r in runs if r["own_ratio"] is not None]
        worst = [r["worst"] / tol for r in runs]
        out[str(tol)] = {
            "cases": len(runs),
            "worst_ratio_to_tol": max(worst),
            "beyond_tol": sum(w > 1.0 for w in worst),
            "beyond_1_5_tol": sum(w > 1.5 for w in worst),
            "estimate_below_truth": sum(r["estimated"] < r["worst"] for r in runs),
            # the estimate below a truth beyond the tolerance: a miss the answer does not show
            "silent_misses": sum(r["estimated"] < r["worst"] and r["worst"] > tol for r in runs),
            "said_not_met": sum(any("not met" in w for w in r["warnings"]) for r in runs),
            "stopped_by_a_limit": sum(any("beyond the limits" in w for w in r["warnings"]) for r in runs),
            "cost_median": statistics.median(ratios) if ratios else None,
            "cost_worst": max(ratios) if ratios else None,
            "cost_counted": len(ratios),
            "own_accuracy_median": statistics.median(own) if own else None,
            "own_accuracy_counted": len(own),
            # where the answer lands within the tolerance: its estimate above its true error, and
            # the tolerance above its estimate
            "estimate_over_truth_median": statistics.median(
                r["estimated"] / r["worst"] for r in runs if r["worst"] > 0
            ),
            "tolerance_over_estimate_median": statistics.median(
                tol / r["estimated"] for r in runs if r["estimated"] > 0
            ),
            # ladders that met it on their fewest grids: their first grid, not the estimate, set their work
            "on_fewest_grids": sum(r["on_fewest_grids"] for r in runs),
            # the least any start could cost on the grid the ladder ended on: that grid alone
            "final_grid_median": statistics.median(r["final_ratio"] for r in runs if r["ratio"] is not None)
            if ratios
            else None,
            "seconds_median": statistics.median(r["seconds"] for r in runs),
        }
    return out


def overview(stats: dict, preset_rows: list[dict], count: int, seed: int) -> str:
    """The figures quoted in README.md and docs/numerics.md."""
    lines = [
        f"{count} cases drawn (`bench/matrix.py --seed {seed} --count {count} --write`; every case "
        "in [matrix.md](matrix.md)); a case counts at a tolerance where its reference is 10× tighter. "
        "True error: a run's largest relative error over every quantity it estimates, against the "
        "reference. Cost: its work (node-steps over all its grids) against the cheapest fixed grid "
        "that meets the same tolerance, found in hindsight; its final grid alone against the same "
        "grid is the least a start nearer the answer (from a neighbour in a study) could cost where "
        "the ladder ends as it does. As accurate: its work against the cheapest fixed grid whose "
        f"true error is no larger than its own (or than {OWN_ACCURACY_FLOOR:g} and 10× the reference's uncertainty, "
        "if larger), found in hindsight the same way: what the answer costs beside what it turned "
        "out to be worth, apart from how far within the tolerance it lands. Each run has the "
        "service's limits raised "
        "tenfold, so that its ladder stops on its own account.",
        "",
        "| tolerance | cases | worst true error / tolerance | beyond it | beyond 1.5× | estimate below the truth | silent misses (that and beyond it) | say 'not met' | stopped by a limit | cost: median | worst | its final grid alone: median | cases with a cheapest grid | as accurate: median | cases |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for tol in TOLERANCES:
        s = stats[str(tol)]
        lines.append(
            f"| {tol:g} | {s['cases']} | {s['worst_ratio_to_tol']:.2f} | {s['beyond_tol']} | "
            f"{s['beyond_1_5_tol']} | {s['estimate_below_truth']} | {s['silent_misses']} | {s['said_not_met']} | "
            f"{s['stopped_by_a_limit']} | {s['cost_median']:.2f}× | {s['cost_worst']:.2f}× | "
            f"{s['final_grid_median']:.2f}× | {s['cost_counted']} | {s['own_accuracy_median']:.2f}× | "
            f"{s['own_accuracy_counted']} |"
        )
    lines += [
        "",
        "Where the answers land, medians: "
        + "; ".join(
            f"at {tol:g} the estimate {stats[str(tol)]['estimate_over_truth_median']:.1f}× the true error "
            f"and the tolerance {stats[str(tol)]['tolerance_over_estimate_median']:.1f}× the estimate, "
            f"{stats[str(tol)]['on_fewest_grids']} of {stats[str(tol)]['cases']} ladders ending on their "
            f"fewest grids ({adaptive.MIN_RUNS})"
            for tol in TOLERANCES
        )
        + ".",
        "",
        f"Each of the paper's presets at the default accuracy (1%), after compilation, least of "
        f"{PRESET_REPEATS} runs (the reference solves the paper's model only; `bench/device_presets.py` "
        "times the others):",
        "",
        "| preset | time | true error | estimate | grids (cells) |",
        "|---|---|---|---|---|",
    ]
    for p in preset_rows:
        lines.append(
            f"| {p['name']} | {p['ms']:.2f} ms | {p['worst']:.1e} | {p['estimated']:.1e} | "
            f"{', '.join(map(str, p['cells']))}{', says not met' if p.get('not_met') else ''} |"
        )
    return "\n".join(lines)


def table(results: list[dict], stats: dict, preset_rows: list[dict], seed: int) -> str:
    lines = [
        "# The accuracy guarantee on a random matrix of cases",
        "",
        "Written by `bench/matrix.py --write`: the cases are `solver/matrix.py`'s, the references "
        "the characteristics solver's (`solver/characteristics.py`), an independent method.",
        "",
        overview(stats, preset_rows, len(results), seed).replace("[matrix.md](matrix.md)", "the table below"),
    ]
    lines += [
        "",
        "Every case (true error and estimate, worst over the quantities; cost against "
        "the cheapest fixed grid, and against the cheapest as accurate as the answer, whose cells are given):",
        "",
        "| case | reference contacts | 1e-2: true | estimate | cost (cells) | as accurate (cells) "
        "| 1e-3: true | estimate | cost (cells) | as accurate (cells) |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in results:
        if "skipped" in r["reference"]:
            lines.append(
                f"| {r['name']}: {describe(r['case'])} | left out: {r['reference']['skipped']} | | | | | | | | |"
            )
            continue
        cells = []
        for tol in TOLERANCES:
            run = r["runs"].get(str(tol))
            if run is None:
                uncertainty = max(r["reference"]["uncertainty"].values())
                cells.append(f"not counted: the reference's uncertainty is {uncertainty:.1e} | | |")
                continue
            ratio = f"{run['ratio']:.2f}× ({run['cheapest_cells']})" if run["ratio"] else "no fixed grid"
            own = f"{run['own_ratio']:.2f}× ({run['own_cells']})" if run["own_ratio"] else "no fixed grid"
            cells.append(f"{run['worst']:.1e} | {run['estimated']:.1e} | {ratio} | {own}")
        lines.append(
            f"| {r['name']}: {describe(r['case'])} | {r['reference']['contacts']} | " + " | ".join(cells) + " |"
        )
    return "\n".join(lines) + "\n"


def matrix_parser(description: str) -> argparse.ArgumentParser:
    """The options of a bench over the matrix: which cases, on how many processes, and --write."""
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--count", type=int, default=COUNT)
    parser.add_argument("--processes", type=int, default=2)
    parser.add_argument("--write", action="store_true")
    return parser


def main() -> None:
    parser = matrix_parser(__doc__.split("\n\n")[0])
    parser.add_argument(
        "--prepare", action="store_true", help="only compute the references and fixed grids into the cache"
    )
    args = parser.parse_args()
    warm_up()
    cases = draw_cases(args.seed, args.count)
    if args.prepare:
        with ProcessPoolExecutor(args.processes) as pool:
            for done in pool.map(prepare, cases):
                print(done, flush=True)
        return
    with ProcessPoolExecutor(args.processes) as pool:
        results = []
        for result in pool.map(measure, cases):
            runs = result["runs"]
            print(
                result["name"],
                " ".join(
                    f"{tol}: true {runs[tol]['worst']:.1e} est {runs[tol]['estimated']:.1e} "
                    f"cost {runs[tol]['ratio'] or float('nan'):.2f} as accurate "
                    f"{runs[tol]['own_ratio'] or float('nan'):.2f} cells {runs[tol]['cells']}"
                    for tol in runs
                ),
                flush=True,
            )
            results.append(result)
    stats = summarise(results)
    preset_rows = presets()
    print(json.dumps(stats, indent=2, default=float))
    for p in preset_rows:
        print(p)
    if args.write:
        (ROOT / "docs" / "matrix.md").write_text(table(results, stats, preset_rows, args.seed))
        quoted = overview(stats, preset_rows, len(results), args.seed)
        write_marked(ROOT / "README.md", "matrix", quoted.replace("(matrix.md)", "(docs/matrix.md)"))
        write_marked(ROOT / "docs" / "numerics.md", "matrix", quoted)


if __name__ == "__main__":
    main()
