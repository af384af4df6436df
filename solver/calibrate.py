"""Calibration: the case's parameters that make a run reproduce a measured record.

The method, in order:

0. Checks (`check_calibration`, also the service's before it queues a fit): the record against
   the case, the parameters' paths and bounds, and the record's units: its peak must come within
   `UNITS_FACTOR` of the model's at some corner of the bounds (a prefix off gives 1000).
1. A global stage: the case at its own values and at a scrambled Sobol sample of the bounds
   (8 points a parameter, rounded up to a power of 2), in one batch; further rounds, each with a
   sample as large again and fresh starts, while the misfit stays above the record's noise.
2. Bounded least squares (`scipy.optimize.least_squares`, trust-region reflective) on the record's
   residual, from the `STARTS` best points of the global stage, over the unit cube of `Space`
   (logarithmic for positive bounds). The Jacobian's columns are forward differences run as one
   batch, so they spread over the evaluator's processes or workers.
3. The uncertainty at the optimum: the Jacobian by central differences, the residual's variance
   s² = Σr²/(m − n), covariance s²(JᵀJ)⁻¹ mapped from the cube to the parameters, standard errors,
   the correlation matrix and 95% confidence bounds (Student's t; on the logarithmic scale for a
   logarithmic parameter, so they stay positive).
4. The grid: the fit climbs a ladder of its own. Steps 1–3 run on the tolerance ladder's first
   grid (`evaluate.first_study_grid`: coarse, as a global look needs no more); the fit is then
   repeated on a grid twice as fine, from its optimum, until the values move by less than
   `GRID_SHARE` of their standard errors, so that the grid's error is a small part of the
   answer's uncertainty. A fit is judged by its values, not by a summary's tolerance: a record of
   a few hundred samples settles on far fewer cells than the summary's largest stress asks.

The answer says, in `warnings`, when the fit is not unique: parameters strongly correlated, one at
a bound, one the record does not determine, or starts that ended apart at the same misfit.
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

from .case import Case, CaseError, FieldError
from .errors import Cancelled
from .evaluate import Batch, Evaluator, Space, check_grid, evaluator_for, first_study_grid
from .limits import Limits
from .record import Record, record_noise
from .result import CancelCheck, ProgressCallback
from .study import (
    GRID_REMEDY,
    OFFSET,
    Calibration,
    check_calibration,
    parse_calibration,
    run_span,
    set_aside,
    study_case,
)

POINTS_PER_PARAMETER = 8
STARTS = 3  # least-squares starts a round, from the global stage's best points not yet tried
ROUNDS = 3  # each with a global sample twice as large, until the misfit is the record's noise
MISFIT_RATIO = 1.25  # a misfit within this × the record's noise: the model reproduces the record
INPUT_TOO = " and its driving input's"
MAX_RUNS_PER_START = 60  # model runs a start may use (its Jacobians' included)
STEP = 1e-4  # finite-difference step on the unit cube
CONFIDENCE = 0.95
GRID_SHARE = 1.0 / 3.0  # of a standard error: how far a finer grid may move the values
MAX_REFINEMENTS = 10  # doublings from the first grid: 1024× its cells, the limits permitting
CORRELATED = 0.95  # |correlation| above which two parameters are not told apart
UNDETERMINED = 0.5  # a 95% interval wider than this share of the bounds (on the unit cube)
AT_BOUND = 1e-3  # on the unit cube
SAME_MISFIT = 4.0  # residual variances: starts whose sums of squares differ less fit as well


class _Problem:
    """The fit's residual on one grid, each run counted and cancellable. The record's
    time_offset, when fitted, moves the instants the model is read at, not the run: points that
    differ in it alone share one run. `cells` is the grid of every run, once chosen."""

    def __init__(
        self,
        base: dict,
        space: Space,
        record: Record,
        evaluator: Evaluator,
        cancelled: CancelCheck | None,
        cells: int = 0,
    ):
        self.base, self.space, self.record, self.cells = base, space, record, cells
        self.evaluator, self.cancelled = evaluator, cancelled
        self.case_space = space.without(OFFSET)
        self.offset_at = space.paths.index(OFFSET) if OFFSET in space.paths else None
        self.times = record.instants
        self.values = np.asarray(record.values)
        self.scale = float(np.ptp(self.values))
        self.duration = run_span(record, space)
        self.runs = 0
        self._runs: dict[bytes, Any] = {}

    def split(self, u: np.ndarray) -> tuple[np.ndarray, float]:
        """The case's fields' values and the time_offset at a point of the unit cube."""
        values = self.space.values(u)
        if self.offset_at is None:
            return values, self.record.time_offset or 0.0
        return np.delete(values, self.offset_at), float(values[self.offset_at])

    def case_at(self, u: np.ndarray) -> Case:
        """The case at a point of the unit cube."""
        return Case.model_validate(self.case_space.tree(self.base, self.split(u)[0]))

    def model(self, units: list[np.ndarray]) -> list[np.ndarray]:
        """The model's series at the record's instants, per point of the unit cube."""
        if self.cancelled is not None and self.cancelled():
            raise Cancelled
        points = [self.split(u) for u in units]
        keys = [fields.tobytes() for fields, _ in points]
        wanted = {key: fields for key, (fields, _) in zip(keys, points) if key not in self._runs}
        fitted = self.offset_at is not None
        if wanted:
            answers = self.evaluator(
                Batch(
                    cases=[self.case_space.tree(self.base, fields) for fields in wanted.values()],
                    cells=self.cells,
                    duration=self.duration,
                    series={
                        "quantity": self.record.quantity,
                        "times": None if fitted else (self.times + points[0][1]).tolist(),
                    },
                    quantities=None,
                )
            )
            self.runs += len(answers)
            for (key, fields), answer in zip(wanted.items(), answers):
                if "error" in answer:
                    raise CaseError(
                        [
                            FieldError(
                                field="parameters",
                                message=(
                                    f"the model fails at {self.describe(fields, self.case_space)}: {answer['error']}"
                                ),
                            )
                        ]
                    )
                self._runs[key] = (
                    (np.asarray(answer["time"]), np.asarray(answer["series"]))
                    if fitted
                    else np.asarray(answer["series"])
                )
        if not fitted:
            return [self._runs[key] for key in keys]
        # before the impact (a record's lead-in) the model is at rest: its first sample
        return [np.interp(self.times + offset, *self._runs[key]) for key, (_, offset) in zip(keys, points)]

    def describe(self, values: np.ndarray, space: Space | None = None) -> str:
        """The fields' `values` (of `space`, by default the fit's) in words."""
        return ", ".join(f"{p} = {v:.6g}" for p, v in zip((space or self.space).paths, values))

    def misfit(self, series: np.ndarray) -> np.ndarray:
        """(model − record) over the record's range, at each sample."""
        return (series - self.values) / self.scale

    def residual(self, u: np.ndarray) -> np.ndarray:
        return self.misfit(self.model([u])[0])

    def jacobian(self, u: np.ndarray) -> np.ndarray:
        """Forward differences, stepping inward at an upper bound, one batch of runs."""
        steps = np.where(u + STEP > 1.0, -STEP, STEP)
        points = [u + np.eye(len(u))[k] * steps[k] for k in range(len(u))]
        base = self.model([u])[0]
        return np.column_stack([(m - base) / self.scale / s for m, s in zip(self.model(points), steps)])

    def central_jacobian(self, u: np.ndarray) -> np.ndarray:
        """Central differences (one-sided at a bound), one batch of runs: for the covariance."""
        eye = np.eye(len(u))
        ahead = [np.minimum(u + STEP * eye[k], 1.0) for k in range(len(u))]
        behind = [np.maximum(u - STEP * eye[k], 0.0) for k in range(len(u))]
        series = self.model(ahead + behind)
        n = len(u)
        return np.column_stack(
            [(series[k] - series[n + k]) / self.scale / (ahead[k][k] - behind[k][k]) for k in range(n)]
        )

    def solve(self, start: np.ndarray) -> Any:
        # scipy's optimize and stats are imported where a fit runs: not by the API, which reads
        # the requests' models in this module (0.7 s and about 40 MB of each API process)
        from scipy.optimize import least_squares

        return least_squares(
            self.residual,
            start,
            jac=self.jacobian,
            bounds=(0.0, 1.0),
            method="trf",
            x_scale="jac",
            ftol=1e-10,
            xtol=1e-7,
            gtol=1e-10,
            max_nfev=MAX_RUNS_PER_START // (len(start) + 1),
        )


def calibrate(
    calibration: Calibration | dict,
    evaluator: Evaluator | None = None,
    processes: int | None = None,
    progress: ProgressCallback | None = None,
    cancelled: CancelCheck | None = None,
    limits: Limits = Limits(),
    input_noise: float = 0.0,
) -> dict:
    """Fit `calibration.parameters` so that the case reproduces the record (see the module's
    docstring). `evaluator` runs the batches (default: a pool over `processes`, one a core).
    `input_noise` is the misfit the model's own measured input adds, over the record's range (a
    head driven by a measured velocity: its noise times the impedance): the least misfit is then
    both noises together. Returns the fit as JSON: parameters with standard errors and confidence
    bounds, correlation, nrmse, evaluations, warnings, the fitted case and the record against the
    model."""
    if not isinstance(calibration, Calibration):
        calibration = parse_calibration(calibration)
    with evaluator_for(evaluator, processes) as run:
        return _calibrate(calibration, run, progress, cancelled, limits, input_noise)


def _calibrate(
    calibration: Calibration,
    evaluator: Evaluator,
    progress: ProgressCallback | None,
    cancelled: CancelCheck | None,
    limits: Limits,
    input_noise: float = 0.0,
) -> dict:
    started = time.monotonic()
    case, record = study_case(calibration.case), calibration.record
    space = check_calibration(calibration, limits)
    report = progress or (lambda fraction: None)

    own = space.own(case)
    base = case.model_dump(mode="json", exclude_none=True)
    base["outputs"] = record.outputs()
    problem = _Problem(base, space, record, evaluator, cancelled)
    own_case = problem.case_at(own)
    problem.cells = first_study_grid(own_case, problem.case_space)
    check_grid(own_case, problem.cells, problem.duration, limits, field="record.time", remedy=GRID_REMEDY)

    n = len(space.paths)
    noise = math.hypot(record_noise(record), input_noise)
    from scipy.stats import qmc

    sobol = qmc.Sobol(n, scramble=True, seed=20261125)
    points = [own] + list(sobol.random_base2(math.ceil(math.log2(POINTS_PER_PARAMETER * n))))
    costs: list[float] = []
    solutions, tried = [], set()
    for round_ in range(ROUNDS):
        models = problem.model(points[len(costs) :])
        costs += [float(np.sum(problem.misfit(m) ** 2)) for m in models]
        fresh = [k for k in np.argsort(costs) if k not in tried][:STARTS]
        for k in fresh:
            solutions.append(problem.solve(points[k]))
            report(0.7 * (1.0 - 0.5 ** (round_ + len(solutions) / (len(fresh) * ROUNDS))))
        tried.update(fresh)
        if _nrmse(min(s.cost for s in solutions), record) <= MISFIT_RATIO * noise:
            break
        points += list(sobol.random(len(points) - 1))  # as many again: a Sobol sample stays balanced
    best = min(solutions, key=lambda s: s.cost)
    fit = _uncertainty(problem, best.x)

    refinements, moved = 0, 0.0
    while True:
        finer = _Problem(base, space, record, evaluator, cancelled, cells=2 * problem.cells)
        try:
            check_grid(own_case, finer.cells, finer.duration, limits, field="record.time", remedy=GRID_REMEDY)
        except CaseError:
            break
        finer.runs = problem.runs
        refined = finer.solve(fit["unit"])
        refined_fit = _uncertainty(finer, refined.x)
        moved = float(np.max(np.abs(refined.x - fit["unit"]) / np.maximum(refined_fit["unit_error"], 1e-300)))
        problem, fit, refinements = finer, refined_fit, refinements + 1
        report(0.7 + 0.3 * (1.0 - 0.5**refinements))
        if moved <= GRID_SHARE or refinements >= MAX_REFINEMENTS:
            break

    warnings = set_aside(calibration.case) + record.notes + _warnings(space, fit, solutions, problem)
    if fit["nrmse"] > MISFIT_RATIO * noise:
        warnings.append(
            f"the misfit (nrmse {fit['nrmse']:.3g}) is {fit['nrmse'] / max(noise, 1e-300):.3g}× the "
            f"record's noise ({noise:.3g}, from its sample-to-sample scatter{INPUT_TOO if input_noise else ''}) "
            f"after {len(solutions)} "
            "starts: the model does not reproduce the record within its noise (a parameter not "
            "fitted, something the model lacks, or an optimum the starts did not find)"
        )
    if moved > GRID_SHARE:
        warnings.append(
            f"the grid is not fine enough for this record: on {problem.cells} cells, twice as fine "
            f"as the last, the values moved by {moved:.2g} of their standard errors (more than "
            f"{GRID_SHARE:.2g}); the uncertainty does not include the grid's error"
        )
    values = space.values(fit["unit"])
    fields, offset = problem.split(fit["unit"])
    fitted = problem.case_space.tree(calibration.case.model_dump(mode="json", exclude_none=True), fields)
    model = problem.model([fit["unit"]])[0]
    report(1.0)
    return {
        "parameters": {
            path: {"value": float(v), "standard_error": _finite(se), "low": _finite(lo), "high": _finite(hi)}
            for path, v, se, lo, hi in zip(space.paths, values, fit["standard_error"], fit["low"], fit["high"])
        },
        "correlation": fit["correlation"],
        "nrmse": fit["nrmse"],
        "evaluations": problem.runs,
        "warnings": warnings,
        "confidence": CONFIDENCE,
        "noise": noise,
        "case": fitted,
        "record": {"quantity": record.quantity, "x": record.x, "unit": record.unit, "time_offset": offset},
        "series": {"time": problem.times.tolist(), "record": record.values, "model": model.tolist()},
        "grid": {"cells": problem.cells, "refinements": refinements, "moved": moved},
        "starts": [
            {
                "values": dict(zip(space.paths, space.values(s.x).tolist())),
                "nrmse": _nrmse(s.cost, record),
                "stopped": s.message,
            }
            for s in solutions
        ],
        "seconds": time.monotonic() - started,
    }


def _finite(value: float) -> float | None:
    """A number for JSON; None for an infinite one (a parameter the record does not determine)."""
    return float(value) if math.isfinite(value) else None


def _nrmse(cost: float, record: Record) -> float:
    """The normalised RMS misfit of a least-squares cost (half the sum of squared residuals)."""
    return math.sqrt(2.0 * cost / len(record.values))


def _uncertainty(problem: _Problem, u: np.ndarray) -> dict:
    """Standard errors, correlation and confidence bounds at the optimum `u` of the cube."""
    from scipy.stats import t as student

    space = problem.space
    residual = problem.residual(u)
    jac = problem.central_jacobian(u)
    m, n = jac.shape
    dof = max(m - n, 1)
    variance = float(residual @ residual) / dof
    # On the Jacobian's range only: a parameter with a part in its null space does not change the
    # model at the record's instants, and its error is infinite, not the pseudo-inverse's 0.
    _, singular_values, vt = np.linalg.svd(jac, full_matrices=False)
    rank = int(np.sum(singular_values > 1e-8 * max(singular_values[0], 1e-300)))
    null = vt[rank:]
    undetermined = np.linalg.norm(null, axis=0) > 1e-3 if rank < n else np.zeros(n, bool)
    inverse = (vt[:rank].T / singular_values[:rank] ** 2) @ vt[:rank]
    cov_unit = variance * inverse
    unit_error = np.where(undetermined, np.inf, np.sqrt(np.maximum(np.diag(cov_unit), 0.0)))
    slope = space.slope(u)
    standard_error = unit_error * np.abs(slope)
    with np.errstate(divide="ignore", invalid="ignore"):
        correlation = cov_unit / np.outer(unit_error, unit_error)
    correlation = np.where(np.isfinite(correlation), np.clip(correlation, -1.0, 1.0), 0.0)
    np.fill_diagonal(correlation, 1.0)
    spread = student.ppf(0.5 + CONFIDENCE / 2.0, dof) * unit_error
    values = space.values(u)
    # On the cube (logarithmic for a positive parameter), then back: bounds that can leave [low,
    # high], since they say what the record allows, not what the fit was allowed.
    reach = space.log_span * spread
    with np.errstate(over="ignore"):
        low = np.where(space.logarithmic, values * np.exp(-reach), values - spread * (space.high - space.low))
        high = np.where(space.logarithmic, values * np.exp(reach), values + spread * (space.high - space.low))
    low, high = np.where(undetermined, -np.inf, low), np.where(undetermined, np.inf, high)
    return {
        "unit": u,
        "unit_error": unit_error,
        "standard_error": standard_error,
        "low": low,
        "high": high,
        "correlation": correlation.tolist(),
        "nrmse": math.sqrt(float(residual @ residual) / m),
        "spread": spread,
        "variance": variance,
        "undetermined": undetermined,
    }


def _warnings(space: Space, fit: dict, solutions: list, problem: _Problem) -> list[str]:
    """Why the fit may not be unique, in words, naming the parameters."""
    warnings = []
    paths, u = space.paths, fit["unit"]
    corr = np.asarray(fit["correlation"])
    for i in range(len(paths)):
        for j in range(i + 1, len(paths)):
            if abs(corr[i, j]) >= CORRELATED:
                warnings.append(
                    f"{paths[i]} and {paths[j]} are strongly correlated ({corr[i, j]:+.3f}): the "
                    "record does not tell them apart, and other pairs of values fit it as well; the "
                    "fit is not unique"
                )
    values = space.values(u)
    for k, path in enumerate(paths):
        if u[k] <= AT_BOUND or u[k] >= 1.0 - AT_BOUND:
            side, bound = ("lower", space.low[k]) if u[k] <= AT_BOUND else ("upper", space.high[k])
            warnings.append(
                f"{path} ended at its {side} bound ({bound:.6g}): the best fit may lie "
                "beyond it; widen the bounds or fix the parameter"
            )
        elif fit["undetermined"][k]:
            warnings.append(
                f"{path} is not determined by the record: changing it does not change the "
                "model at the record's instants; the fit is not unique"
            )
        elif 2.0 * fit["spread"][k] >= UNDETERMINED:
            warnings.append(
                f"{path} is poorly determined by the record: its {CONFIDENCE:.0%} interval "
                f"[{fit['low'][k]:.4g}, {fit['high'][k]:.4g}] around {values[k]:.4g} spans more than "
                f"{UNDETERMINED:.0%} of the bounds' range (on their scale); the fit is not unique"
            )
    # Another start as good within the noise (its sum of squares within `SAME_MISFIT` residual
    # variances of the best), yet over three standard errors away: no single basin has both.
    # The starts ran on the first grid: they are compared with the best of them, not with the fit.
    best = min(solutions, key=lambda s: s.cost)
    error = np.maximum(fit["unit_error"], 1e-12)
    apart = [
        s
        for s in solutions
        if 2.0 * (s.cost - best.cost) <= SAME_MISFIT * fit["variance"] and np.any(np.abs(s.x - best.x) > 3.0 * error)
    ]
    if apart:
        warnings.append(
            "starts ended at different values with the same misfit ("
            + problem.describe(space.values(apart[0].x))
            + " against "
            + problem.describe(space.values(best.x))
            + "): the record has more than one best fit; the fit is not unique"
        )
    return warnings
