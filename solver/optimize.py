"""Design optimisation: the case's fields, within bounds, that maximise or minimise one summary
quantity while others stay within limits.

The method, in order:

1. Every run on one grid, chosen by the tolerance machinery for the case (`evaluate.study_grid`),
   so that the quantities are smooth functions of the fields.
2. A global stage: `scipy.optimize.differential_evolution` over the unit cube of `Space`, its
   population evaluated as one batch a generation (spread over the evaluator's processes or
   workers), each limit a `NonlinearConstraint` tightened by the tolerance toward its safe side,
   until the population agrees or the evaluation budget is spent.
3. A local stage from its best point: `scipy.optimize.minimize` (SLSQP) with the gradients of the
   objective and of the limits by forward differences, run as one batch.
4. The check: the best design solved under the tolerance (`adaptive`); its summary, with its error
   estimate, is the answer's. A design whose checked summary breaks a limit is not the answer: the
   next best feasible one is checked instead.
"""

from __future__ import annotations

import math
import time

import numpy as np

from .case import SUMMARY_ONLY, Case, CaseError, FieldError
from .errors import Cancelled
from .evaluate import Batch, Evaluator, Space, check_grid, evaluator_for, study_grid
from .grid import DEFAULT_TOLERANCE
from .limits import Limits
from .paths import quantity
from .result import CancelCheck, ProgressCallback
from .simulate import simulate
from .study import (
    DURATION_REMEDY,
    Optimization,
    check_optimization,
    parse_optimization,
    quantity_fields,
    set_aside,
    study_case,
)

POPULATION = 10  # per variable: differential evolution's population
MIN_POPULATION = 8
GLOBAL_SHARE = 0.8  # of the budget of runs: the global stage's; the local stage has the rest
STEP = 1e-5  # finite-difference step on the unit cube, for the local stage
CHECKED = 3  # designs checked under the tolerance before giving up on the limits


class _Study:
    """The design space on one grid: every run counted, cached and kept in the history."""

    def __init__(
        self,
        request: Optimization,
        space: Space,
        cells: int,
        tolerance: float,
        evaluator: Evaluator,
        cancelled: CancelCheck | None,
    ):
        self.request, self.space, self.cells, self.tolerance = request, space, cells, tolerance
        self.evaluator, self.cancelled = evaluator, cancelled
        self.base = study_case(request.case).model_dump(mode="json", exclude_none=True)
        self.base["outputs"] = SUMMARY_ONLY.model_dump(mode="json")  # the summary is all a design needs
        self.names = [request.objective.quantity, *request.limits]
        self.history: list[dict] = []
        self._cache: dict[bytes, dict] = {}

    def quantities(self, units: list[np.ndarray]) -> list[dict]:
        """The summary quantities at points of the unit cube (None where a run failed or has none)."""
        if self.cancelled is not None and self.cancelled():
            raise Cancelled
        wanted = list({u.tobytes(): u for u in units if u.tobytes() not in self._cache}.values())
        if wanted:
            trees = [self.space.tree(self.base, self.space.values(u)) for u in wanted]
            answers = self.evaluator(
                Batch(
                    cases=trees,
                    cells=self.cells,
                    duration=self.request.case.numerics.duration,
                    series=None,
                    quantities=self.names,
                )
            )
            for u, answer in zip(wanted, answers):
                found = answer.get("quantities", {name: None for name in self.names})
                entry = {
                    "values": dict(zip(self.space.paths, self.space.values(u).tolist())),
                    "quantities": found,
                    "feasible": self.feasible(found),
                    **({"error": answer["error"]} if "error" in answer else {}),
                }
                self.history.append(entry)
                self._cache[u.tobytes()] = found
        return [self._cache[u.tobytes()] for u in units]

    def objective(self, found: dict) -> float:
        value = found.get(self.request.objective.quantity)
        return math.inf if value is None else self.request.objective.sign * value

    def margins(self, found: dict, tightened: bool) -> list[float]:
        """Per limit side, how far inside it the design is (≥ 0 inside), scaled by the limit;
        `tightened`: inside by the tolerance too."""
        out = []
        for name, bound in self.request.limits.items():
            value = found.get(name)
            for side, limit in ((1.0, bound.max), (-1.0, bound.min)):
                if limit is None:
                    continue
                scale = max(abs(limit), 1e-300)
                if value is None:
                    out.append(-1.0)
                    continue
                margin = side * (limit - value) / scale
                out.append(margin - (self.tolerance if tightened else 0.0))
        return out

    def feasible(self, found: dict, tightened: bool = False) -> bool:
        return all(m >= 0.0 for m in self.margins(found, tightened))

    def objective_many(self, units: np.ndarray) -> np.ndarray:
        """Differential evolution's vectorised objective: units of shape (n, S) → (S,)."""
        columns = [np.asarray(c, dtype=float) for c in np.atleast_2d(units.T)]
        return np.array([self.objective(f) for f in self.quantities(columns)])

    def margins_many(self, units: np.ndarray) -> np.ndarray:
        columns = [np.asarray(c, dtype=float) for c in np.atleast_2d(units.T)]
        return np.array([self.margins(f, tightened=True) for f in self.quantities(columns)]).T

    def gradients(self, u: np.ndarray) -> tuple[float, np.ndarray, np.ndarray, np.ndarray]:
        """The objective and the tightened margins at u, with their gradients (forward
        differences, stepping inward at an upper bound), as one batch."""
        steps = np.where(u + STEP > 1.0, -STEP, STEP)
        points = [u] + [u + np.eye(len(u))[k] * steps[k] for k in range(len(u))]
        found = self.quantities(points)
        f = np.array([self.objective(x) for x in found])
        g = np.array([self.margins(x, tightened=True) for x in found]).reshape(len(found), -1)
        return f[0], (f[1:] - f[0]) / steps, g[0], ((g[1:] - g[0]) / steps[:, None]).T


def optimize(
    optimization: Optimization | dict,
    evaluator: Evaluator | None = None,
    processes: int | None = None,
    progress: ProgressCallback | None = None,
    cancelled: CancelCheck | None = None,
    limits: Limits = Limits(),
) -> dict:
    """Find the best design (see the module's docstring). `evaluator` runs the batches (default:
    a pool over `processes`, one a core). Returns as JSON: the best case and its summary (checked
    under the tolerance), its variables and quantities, every evaluation, and why it stopped."""
    if not isinstance(optimization, Optimization):
        optimization = parse_optimization(optimization)
    with evaluator_for(evaluator, processes) as run:
        return _optimize(optimization, run, progress, cancelled, limits)


def _optimize(
    request: Optimization,
    evaluator: Evaluator,
    progress: ProgressCallback | None,
    cancelled: CancelCheck | None,
    limits: Limits,
) -> dict:
    from scipy.optimize import NonlinearConstraint, differential_evolution  # where a search runs, as in calibrate

    started = time.monotonic()
    case = study_case(request.case)
    space = check_optimization(request, limits)
    report = progress or (lambda fraction: None)
    tol = case.numerics.tolerance or DEFAULT_TOLERANCE
    own = space.own(case)
    own_case = Case.model_validate(space.tree(case.model_dump(mode="json", exclude_none=True), space.values(own)))
    cells = study_grid(own_case, space, tol, limits)
    check_grid(own_case, cells, case.numerics.duration, limits, field="case.numerics.duration", remedy=DURATION_REMEDY)
    study = _Study(request, space, cells, tol, evaluator, cancelled)
    _check_quantities(study, own)

    n = len(space.paths)
    population = max(MIN_POPULATION, POPULATION * n)

    def generation(intermediate_result) -> bool:
        """Report progress; stop once the budget of runs is spent."""
        report(0.8 * min(1.0, len(study.history) / request.max_evaluations))
        return len(study.history) >= GLOBAL_SHARE * request.max_evaluations

    constraints = [NonlinearConstraint(study.margins_many, 0.0, np.inf)] if request.limits else []
    found = differential_evolution(
        study.objective_many,
        [(0.0, 1.0)] * n,
        popsize=max(1, population // n),
        maxiter=request.max_evaluations,
        init="sobol",
        seed=request.seed,
        tol=1e-6,
        atol=0.0,
        polish=False,
        vectorized=True,
        updating="deferred",
        constraints=constraints,
        callback=generation,
    )
    global_runs = len(study.history)
    local = _local_stage(study, found.x, request.max_evaluations)
    report(0.9)
    best, checked = _check(study, case, tol, limits)
    report(1.0)
    spent = "its share of the budget of runs was spent"
    stopped = (
        f"global stage: {spent if global_runs >= GLOBAL_SHARE * request.max_evaluations else found.message} "
        f"({global_runs} runs, {found.nit} generations)"
    )
    if local is not None:
        local_spent = len(study.history) >= request.max_evaluations
        stopped += f"; local stage: {'the budget of runs was spent' if local_spent else local.message}"
    answer = {
        "objective": {request.objective.goal: request.objective.quantity},
        "variables": {
            path: [low, high] for path, low, high in zip(space.paths, space.low.tolist(), space.high.tolist())
        },
        "limits": {name: bound.model_dump(exclude_none=True) for name, bound in request.limits.items()},
        "stopped": stopped,
        "evaluations": len(study.history),
        "grid": {"cells": cells, "tolerance": tol},
        "history": study.history,
        "checked": checked,
        "seconds": time.monotonic() - started,
    }
    if best is None:
        answer |= {
            "case": None,
            "summary": None,
            "values": None,
            "quantities": None,
            "warnings": [
                "no design within the bounds was found that keeps every limit under "
                "the tolerance: loosen a limit or widen the bounds"
            ],
        }
        return answer
    values, result = best
    answer |= {
        "values": values,
        "case": result.case.model_dump(mode="json", exclude_none=True),
        "summary": result.summary,
        "quantities": {name: quantity(result.summary, name) for name in study.names},
        "warnings": set_aside(request.case) + _warnings(study, values),
    }
    return answer


def _check_quantities(study: _Study, own: np.ndarray) -> None:
    """Refuse an objective or a limit that is not a number of the summary, from a run of the case."""
    found = study.quantities([own])[0]
    request, errors = study.request, []
    entry = study.history[-1]
    if "error" in entry:
        raise CaseError([FieldError(field="case", message=f"the case itself fails: {entry['error']}")])
    for name, field in quantity_fields(request).items():
        if found.get(name) is None:
            errors.append(
                FieldError(
                    field=field,
                    message=(
                        f"{name!r} has no value for this case (a medium's penetration with no medium, the "
                        "blows of a single blow)"
                    ),
                )
            )
    if errors:
        raise CaseError(errors)


def _local_stage(study: _Study, start: np.ndarray, budget: int):
    """SLSQP from the global stage's best point, its gradients from batched differences, until
    it converges or the runs reach `budget`."""
    from scipy.optimize import minimize

    memo: dict[bytes, tuple] = {}

    def at(u: np.ndarray) -> tuple:
        key = np.asarray(u, dtype=float).tobytes()
        if key not in memo:
            memo[key] = study.gradients(np.clip(np.asarray(u, dtype=float), 0.0, 1.0))
        return memo[key]

    if not math.isfinite(at(start)[0]):
        return None
    constraints = (
        [{"type": "ineq", "fun": lambda u: at(u)[2], "jac": lambda u: at(u)[3]}] if study.request.limits else []
    )
    return minimize(
        lambda u: at(u)[0],
        start,
        jac=lambda u: at(u)[1],
        method="SLSQP",
        bounds=[(0.0, 1.0)] * len(start),
        constraints=constraints,
        options={"maxiter": 30, "ftol": 1e-10},
        callback=lambda u: _spent(study, budget),
    )


def _spent(study: _Study, budget: int) -> None:
    """Stop the local stage once the runs reach the budget (SciPy ends on StopIteration)."""
    if len(study.history) >= budget:
        raise StopIteration


def _check(study: _Study, case: Case, tol: float, limits: Limits) -> tuple[tuple | None, list[dict]]:
    """The best feasible designs of the history, best first, solved under the tolerance until one
    keeps every limit there: (its values, its result), and what each check found."""
    ranked = sorted(
        (e for e in study.history if e["feasible"] and "error" not in e), key=lambda e: study.objective(e["quantities"])
    )
    checked = []
    for entry in ranked[:CHECKED]:
        tree = study.space.tree(case.model_dump(mode="json", exclude_none=True), list(entry["values"].values()))
        accurate = study_case(case.model_validate(tree), tol)
        result = simulate(accurate, limits=limits)
        found = {name: quantity(result.summary, name) for name in study.names}
        ok = study.feasible(found)
        checked.append({"values": entry["values"], "quantities": found, "feasible": ok})
        if ok:
            return (entry["values"], result), checked
    return None, checked


def _warnings(study: _Study, values: dict) -> list[str]:
    """What the answer cannot promise: a variable at a bound."""
    warnings = []
    for path, value, low, high in zip(study.space.paths, values.values(), study.space.low, study.space.high):
        span = high - low
        if value - low <= 1e-3 * span or high - value <= 1e-3 * span:
            side = "lower" if value - low <= 1e-3 * span else "upper"
            warnings.append(f"{path} is at its {side} bound ({value:.6g}): the optimum may lie beyond it")
    return warnings
