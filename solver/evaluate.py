"""Many runs of one case with a few fields changed: what fits and optimisations are made of.

`Space` is the fields varied (dotted paths) and their bounds, mapped onto the unit cube: a field
whose bounds are both positive on a logarithmic scale, so that six decades of a stiffness are as
well posed as one, any other linearly. Its cases are validated at every corner before anything
runs, each refusal naming the path and bound it came from.

Every run of a study's stage is on one grid: the runs' answers are then smooth functions of the
fields, which finite differences and least squares need (a grid chosen anew for each run would
jump with it). An optimisation's is chosen by the tolerance machinery for the base case
(`study_grid`) and its answer checked under the tolerance; a fit starts on the tolerance ladder's
first grid (`first_study_grid`) and doubles it until its values settle.

A batch of runs is plain JSON (`Batch`: cases, the grid, what to read from each), so that it runs
in this process, in a pool over every core (`LocalEvaluator`) or on the service's workers alike:
an evaluator maps `evaluate_batch` over batches. A batch without a grid is of variants each solved
as a case is, to its own accuracy, driven until its set settles (`settle.settled_run`): the pile
studies' bearing graphs and drivability.
"""

from __future__ import annotations

import copy
import itertools
import math
import os
import time
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import ProcessPoolExecutor, as_completed
from contextlib import contextmanager
from dataclasses import asdict, dataclass
from typing import Any, NotRequired, Protocol, TypedDict

import numpy as np

from .case import Case, CaseError, FieldError, parse_case
from .errors import NumericalFailure
from .grid import DEFAULT_TOLERANCE, explicit_numerics, fewest_cells, first_cells
from .limits import Limits, excesses
from .paths import quantity, set_field, value_at
from .record import series
from .sweep import Sweep, variants


class Batch(TypedDict):
    """Runs to make: `cases` (case JSON), each on `cells` cells (explicit, Courant 1) over
    `duration` s, read for `series` ({quantity, times}: at `times`, or with times None at the
    run's own instants, which come back as `time`) or `quantities` (summary paths). With `cells`
    None each case is solved to its own accuracy over its own duration, driven until its set
    settles, within `limits` (`Limits` as JSON): its answer then also gives the `blows` it took
    and its summary's `warnings`."""

    cases: list[dict]
    cells: int | None
    duration: float | None
    series: dict | None
    quantities: list[str] | None
    limits: NotRequired[dict]


def settled_batch(cases: list[dict], quantities: list[str], limits: Limits) -> Batch:
    """A batch of variants each solved to its own accuracy, driven until its set settles."""
    return Batch(cases=cases, cells=None, duration=None, series=None, quantities=quantities, limits=asdict(limits))


# Told how many of a batch's cases are answered, as they are; raising stops the batch (a cancel).
Answered = Callable[[int], None]


class Evaluator(Protocol):
    """Runs a batch and returns per case {"series": [...]}, {"quantities": {...}} or {"error":
    why}, in order. It may split the batch and run its parts anywhere (`parts_of`), and calls
    `answered`, when given, as its cases are answered."""

    def __call__(self, batch: Batch, answered: Answered | None = None) -> list[dict]: ...


def evaluate_batch(batch: Batch, answered: Answered | None = None) -> list[dict]:
    """Run every case of `batch` on its grid; per case what it asks, or why the run failed."""
    answers = []
    for tree in batch["cases"]:
        answers.append(_evaluate(tree, batch))
        if answered is not None:
            answered(len(answers))
    return answers


def parts_of(batch: Batch, pieces: int) -> list[Batch]:
    """`batch` cut to be spread: into `pieces` runs of consecutive cases, or a case a part for
    variants each solved to its own accuracy, whose costs are their ladders' finest grids, which
    no case tells of the next (one can cost a thousand times its neighbour: parts taken one by one
    as processes come free keep them all busy)."""
    cases = batch["cases"]
    return [Batch(batch, cases=part) for part in split(cases, len(cases) if batch["cells"] is None else pieces)]


def _evaluate(tree: dict, batch: Batch) -> dict:
    from .controller import simulate_rod  # the kernel, loaded when a run needs it

    if batch["cells"] is None:
        return _settled(tree, batch)
    try:
        case = parse_case(tree)
        case = case.model_copy(update={"numerics": case.numerics.model_copy(update={"duration": batch["duration"]})})
        result = simulate_rod(case, numerics=explicit_numerics(case, batch["cells"]))
    except (CaseError, NumericalFailure) as error:
        return {"error": str(error)}
    if batch["series"] is not None:
        wanted = batch["series"]
        if wanted["times"] is None:
            times = result.history["time"]
            values = series(wanted["quantity"], result.history, result.probe_stress, times)
            return {"time": times.tolist(), "series": values.tolist()}
        values = series(wanted["quantity"], result.history, result.probe_stress, np.asarray(wanted["times"]))
        return {"series": values.tolist()}
    return {"quantities": {path: quantity(result.summary, path) for path in batch["quantities"]}}


def _settled(tree: dict, batch: Batch) -> dict:
    from .settle import settled_run

    try:
        summary = settled_run(parse_case(tree), Limits(**batch["limits"]))
    except (CaseError, NumericalFailure) as error:
        return {"error": str(error)}
    return {
        "quantities": {path: quantity(summary, path) for path in batch["quantities"]},
        "blows": len(summary["blows"]),
        "warnings": summary["warnings"],
    }


class LocalEvaluator:
    """Batches over `processes` processes on this machine (default: one a core), as a context
    manager that closes its pool. A batch of a few milliseconds costs less here than the pipe to
    a pool: one runs in this process unless its runs, at the longest run seen, would take
    `SPREAD_SECONDS` or more."""

    SPREAD_SECONDS = 0.1

    def __init__(self, processes: int | None = None):
        self.processes = processes or os.cpu_count() or 1
        self.pool: ProcessPoolExecutor | None = None
        self.run_seconds = 0.0

    def __enter__(self) -> LocalEvaluator:
        return self

    def __exit__(self, *exc) -> None:
        if self.pool is not None:
            self.pool.shutdown(cancel_futures=True)

    def worth_spreading(self, batch: Batch) -> bool:
        """Whether `batch` is long enough to spread: runs that would take `SPREAD_SECONDS` here
        (the first batch runs here, to learn what a run costs). Variants solved to their own
        accuracy always are: each is a ladder of runs, whose cost no run on one grid tells."""
        if len(batch["cases"]) < 2:
            return False
        return batch["cells"] is None or len(batch["cases"]) * self.run_seconds >= self.SPREAD_SECONDS

    def __call__(self, batch: Batch, answered: Answered | None = None) -> list[dict]:
        if self.processes == 1 or not self.worth_spreading(batch):
            started = time.perf_counter()
            answers = evaluate_batch(batch, answered)
            per_run = (time.perf_counter() - started) / max(len(answers), 1)
            self.run_seconds = max(self.run_seconds, per_run)
            return answers
        if self.pool is None:
            self.pool = ProcessPoolExecutor(self.processes)
        futures = {self.pool.submit(evaluate_batch, part): k for k, part in enumerate(parts_of(batch, self.processes))}
        answers: dict[int, list[dict]] = {}
        for future in as_completed(futures):
            answers[futures[future]] = future.result()
            if answered is not None:
                answered(sum(map(len, answers.values())))
        return [answer for k in range(len(futures)) for answer in answers[k]]


@contextmanager
def evaluator_for(evaluator: Evaluator | None, processes: int | None) -> Iterator[Evaluator]:
    """`evaluator`, or else a `LocalEvaluator` over `processes`, closed afterwards."""
    if evaluator is not None:
        yield evaluator
        return
    with LocalEvaluator(processes) as local:
        yield local


def split(cases: list[dict], pieces: int) -> list[list[dict]]:
    """`cases` in at most `pieces` runs of consecutive cases, as even as can be."""
    if not cases:
        return []
    pieces = max(1, min(pieces, len(cases)))
    size = math.ceil(len(cases) / pieces)
    return [cases[i : i + size] for i in range(0, len(cases), size)]


@dataclass(frozen=True)
class Space:
    """The fields varied (`paths`) between `low` and `high`, and the unit cube they map onto."""

    paths: tuple[str, ...]
    low: np.ndarray
    high: np.ndarray
    logarithmic: np.ndarray  # per field: both bounds > 0

    @classmethod
    def of(cls, bounds: dict[str, Any], field: str) -> Space:
        """The space of `bounds` ({path: [low, high]}); `CaseError` names a bad pair as
        `field[path]`."""
        errors = []
        for path, pair in bounds.items():
            if (
                not isinstance(pair, (list, tuple))
                or len(pair) != 2
                or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in pair)
                or not all(math.isfinite(v) for v in pair)
            ):
                errors.append(FieldError(field=f"{field}[{path!r}]", message="must be [low, high]: two finite numbers"))
            elif not pair[0] < pair[1]:
                errors.append(
                    FieldError(
                        field=f"{field}[{path!r}]", message=f"must have low < high, not [{pair[0]:g}, {pair[1]:g}]"
                    )
                )
        if not bounds:
            errors.append(FieldError(field=field, message="give at least one field and its bounds"))
        if errors:
            raise CaseError(errors)
        low = np.array([float(p[0]) for p in bounds.values()])
        high = np.array([float(p[1]) for p in bounds.values()])
        return cls(tuple(bounds), low, high, low > 0.0)

    @property
    def log_span(self) -> np.ndarray:
        """ln(high/low) of a logarithmic field (its cube's unit length on the log scale); 1 for a
        linear one, where it is not used."""
        return np.log(np.where(self.logarithmic, self.high / np.where(self.logarithmic, self.low, 1.0), np.e))

    def values(self, unit: np.ndarray) -> np.ndarray:
        """The fields' values at a point of the unit cube."""
        u = np.clip(unit, 0.0, 1.0)
        return np.where(self.logarithmic, self.low * np.exp(self.log_span * u), self.low + (self.high - self.low) * u)

    def unit(self, values: np.ndarray) -> np.ndarray:
        """The point of the unit cube of the fields' values."""
        low = np.where(self.logarithmic, self.low, 1.0)
        log = np.log(np.maximum(values, 1e-300) / low) / self.log_span
        return np.where(self.logarithmic, log, (values - self.low) / (self.high - self.low))

    def slope(self, unit: np.ndarray) -> np.ndarray:
        """d(value)/d(unit) per field: the chain rule from the cube to the fields."""
        return np.where(self.logarithmic, self.values(unit) * self.log_span, self.high - self.low)

    def own(self, case: Case) -> np.ndarray:
        """The point of the unit cube of the case's own values (clipped to the bounds; the
        bounds' middle, on their scale, for a field the case leaves out)."""
        tree = case.model_dump(mode="json")
        found = [value_at(tree, path) for path in self.paths]
        middle = self.values(np.full(len(self.paths), 0.5))
        values = np.array([v if isinstance(v, float) else m for v, m in zip(found, middle)])
        return self.unit(np.clip(values, self.low, self.high))

    def without(self, path: str) -> Space:
        """The space of the other fields."""
        keep = [k for k, p in enumerate(self.paths) if p != path]
        return Space(tuple(self.paths[k] for k in keep), self.low[keep], self.high[keep], self.logarithmic[keep])

    def corners(self, case: Case) -> list[Case]:
        """The case at every corner of the bounds (validated: `check` refuses a corner first)."""
        base = case.model_dump(mode="json", exclude_none=True)
        return [
            Case.model_validate(self.tree(base, self.values(np.array(corner, dtype=float))))
            for corner in itertools.product((0.0, 1.0), repeat=len(self.paths))
        ]

    def fewest_cells(self, case: Case) -> int:
        """The fewest cells every point within the bounds takes (`grid.fewest_cells`, the most of
        any corner: a striker's transit grows with its length and falls with its wave speed, and
        the tool's the same way)."""
        return max(fewest_cells(corner) for corner in self.corners(case))

    def tree(self, base: dict, values: Iterable[float]) -> dict:
        """The case JSON `base` with the fields set to `values`."""
        tree = copy.deepcopy(base)
        for path, value in zip(self.paths, values):
            set_field(tree, path, float(value))
        return tree

    def check(self, case: Case, field: str) -> None:
        """Refuse a corner of the bounds the case cannot take (naming `field[path][0 or 1]`), and
        a field that is not a continuous number of the case, before any run. The limits are the
        study's grid's to check (`check_grid`): a corner's own grid is never run."""
        corners = Sweep(
            case=case, parameters={p: [float(lo), float(hi)] for p, lo, hi in zip(self.paths, self.low, self.high)}
        )
        _, corner = variants(corners, limits=None, field=field)[0]
        tree = corner.model_dump(mode="json", exclude_none=True)
        errors = [
            FieldError(
                field=f"{field}[{path!r}]",
                message=(
                    f"is {value_at(tree, path)!r} in the case, not a continuous number: only such fields can vary"
                ),
            )
            for path in self.paths
            if not isinstance(value_at(tree, path), float)
        ]
        if errors:
            raise CaseError(errors)


def study_grid(case: Case, space: Space, tolerance: float | None, limits: Limits) -> int:
    """The cells the tolerance machinery chooses for `case` (its own tolerance, else `tolerance`,
    else the default), and no fewer than every point of `space` takes: the one grid every run of
    a study uses."""
    from .adaptive import solve_to_tolerance  # the kernel, loaded when a run needs it

    tol = case.numerics.tolerance or tolerance or DEFAULT_TOLERANCE
    plain = case.summary_only()
    result, _ = solve_to_tolerance(plain, tol, limits=limits)
    return max(result.numerics.cells, space.fewest_cells(case))


def first_study_grid(case: Case, space: Space) -> int:
    """The tolerance ladder's first grid for `case` (`grid.first_cells` at its own tolerance, else
    the default), and no fewer cells than every point of `space` takes: where a fit, which judges
    its grid by how far a finer one moves its values, starts."""
    tol = case.numerics.tolerance or DEFAULT_TOLERANCE
    return max(first_cells(case, tol), space.fewest_cells(case))


def check_grid(case: Case, cells: int, duration: float, limits: Limits, field: str, remedy: str) -> None:
    """Refuse, naming `field`, a study whose runs would exceed the limits; `remedy` says what in
    the request to change (the study chooses its grid: the case's numerics are not the cause)."""
    short = case.model_copy(update={"numerics": case.numerics.model_copy(update={"duration": duration})})
    found = excesses(short, explicit_numerics(short, cells), limits)
    if found:
        raise CaseError(
            [
                FieldError(
                    field=field,
                    message=(
                        f"a run on the study's grid of {cells} cells over {duration:.4g} s is beyond the limits: "
                        + "; ".join(e.what for e in found)
                        + f": {remedy}"
                    ),
                )
            ]
        )
