"""The data behind the job page's interactive plots: the curves of one result file, or its stress
field σ(x, t), downsampled for a screen as JSON (`series`, `dumps`) or every sample as CSV
(`csv_chunks`).

Each series is the data of one of `plots.PLOTS` (`_CHARTS`, `FIELDS`): its title, the curves it
draws, and whether this result can make it (`plots.problem`, with the same reasons). Every value is
SI; the page converts for display.

A curve is downsampled by min–max decimation: the samples are cut into buckets of consecutive
ones, and each bucket keeps its least and its greatest, so every peak survives (the curve's max and
min are the full resolution's, exactly); the first and the last sample are always kept. The energy
terms are stacked, so they must share one x: they are read by a plain stride, the last sample
kept, as the energy plot reads them. Histories are read a block of rows at a time, so that a
long run is never held whole.
"""

from __future__ import annotations

import csv
import io
import itertools
import json
import math
import re
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .plots import (
    INPUT,
    NUMERICAL,
    PLOTS,
    NotAvailable,
    Source,
    displacements,
    energy_budget,
    energy_terms,
    forces,
    open_result,
    penetration_path,
    probe_label,
    problem,
    strides,
    take,
)

DEFAULT_POINTS = 2000  # samples a curve, about: a screen's width, twice over
MAX_POINTS = 2_000_000  # samples a curve at the most, every sample (`points=0`) included
DEFAULT_TIMES = 300  # frames of the stress field
DEFAULT_STATIONS = 400  # stations along the tool of the stress field
MAX_FIELD_SIDE = 2000  # frames, and stations, of the stress field at the most
BLOCK_ROWS = 1 << 16  # rows of a history read at once to decimate it
CSV_VALUES = 1 << 18  # numbers a chunk of CSV, about 5 MB of text
SIGNIFICANT = 6  # digits of a JSON value: a screen shows fewer, and Python's 17 make it 1.6× larger
FIELDS = "fields"


class UnknownSeries(ValueError):
    """No series has this name."""


@dataclass(frozen=True)
class Column:
    key: str
    label: str
    unit: str


TIME = Column("time", "time t", "s")


@dataclass(frozen=True)
class _Table:
    """A chart's columns over a result, time first, and how to read them."""

    columns: list[Column]
    read: Callable[[slice], list[np.ndarray]]  # each column's values at rows
    x: int = 0  # the column the curves are drawn against (0: time)

    @property
    def curves(self) -> list[int]:
        return [k for k in range(1, len(self.columns)) if k != self.x]


def _datasets(src: Source, columns: list[tuple[Column, str, int | None]], x: int = 0) -> _Table:
    """Columns read from datasets: (column, dataset, its column in a 2-D dataset or None)."""
    paths = list(dict.fromkeys(path for _, path, _ in columns))

    def read(rows: slice) -> list[np.ndarray]:
        data = {path: src.h5[path][rows] for path in paths}
        return [data[path] if k is None else data[path][:, k] for _, path, k in columns]

    return _Table([column for column, _, _ in columns], read, x)


def _histories(src: Source, shown: list[tuple[str, str, str]], unit: str) -> _Table:
    """Time, then the histories `shown` as (key, dataset, label), all in `unit`."""
    return _datasets(
        src, [(TIME, "time", None)] + [(Column(key, label, unit), path, None) for key, path, label in shown]
    )


def _force(src: Source) -> _Table:
    return _histories(src, forces(src.case), "N")


def _displacements(src: Source) -> _Table:
    return _histories(src, displacements(src.case), "m")


def _probes(src: Source) -> _Table:
    return _datasets(
        src,
        [(TIME, "time", None)]
        + [
            (Column(f"probe_{k}", probe_label(x), "Pa"), "probes/stress", k)
            for k, x in enumerate(src.h5["probes/x"][()])
        ],
    )


def _force_penetration(src: Source) -> _Table:
    return _datasets(
        src,
        [
            (TIME, "time", None),
            (Column("penetration", "penetration of the working end u_N", "m"), penetration_path(src.h5), None),
            (Column("medium_force", "medium force", "N"), "medium/force", None),
        ],
        x=1,
    )


def _energy(src: Source) -> _Table:
    columns = [
        TIME,
        *(Column(name, label, "J") for name, label in energy_terms(src.h5).items()),
        Column("input", INPUT, "J"),
        Column("numerical", NUMERICAL, "J"),
    ]

    def read(rows: slice) -> list[np.ndarray]:
        budget = energy_budget(src, lambda path: src.h5[path][rows])
        return [src.h5["time"][rows], *budget.terms, budget.supplied, budget.numerical]

    return _Table(columns, read)


def _pressures(src: Source) -> _Table:
    return _histories(
        src,
        [("rear", "drive/rear_pressure", "rear chamber p_r"), ("supply", "drive/supply_pressure", "supply p_s")],
        "Pa",
    )


def _striker_velocity(src: Source) -> _Table:
    return _histories(src, [("striker", "striker/velocity", "striker velocity, toward the tool > 0")], "m/s")


@dataclass(frozen=True)
class _Chart:
    plot: str  # the plot it is the data of: what it needs of a result, and its title unless `title`
    y: tuple[str, str]  # the axis' label and unit
    table: Callable[[Source], _Table]
    stacked: bool = False  # its curves share one x (read by a stride), to be stacked
    title: str | None = None  # where the plot draws more than this chart


_CHARTS = {
    "force": _Chart("force", ("force", "N"), _force),
    "displacements": _Chart("displacements", ("displacement", "m"), _displacements),
    "probes": _Chart("probes", ("stress σ", "Pa"), _probes),
    "energy": _Chart("energy", ("energy", "J"), _energy, stacked=True),
    "force_penetration": _Chart("force_penetration", ("medium force", "N"), _force_penetration),
    # a hammer at work's: the plot's other panels are the summary's, blow by blow
    "pressures": _Chart("cycle", ("pressure", "Pa"), _pressures, title="The drive's pressures"),
    "striker_velocity": _Chart("cycle", ("velocity", "m/s"), _striker_velocity, title="The striker's velocity"),
}
_FIELDS_PLOT = "spacetime"
SERIES = {name: chart.title or PLOTS[chart.plot] for name, chart in _CHARTS.items()} | {FIELDS: PLOTS[_FIELDS_PLOT]}


def _plot_of(name: str) -> str:
    if name not in SERIES:
        raise UnknownSeries(f"unknown series {name!r}; the series are: {', '.join(SERIES)}")
    return _FIELDS_PLOT if name == FIELDS else _CHARTS[name].plot


def problems(path: str | Path) -> dict[str, str | None]:
    """Why the result at `path` cannot give each series, saying what to change; None if it can."""
    with open_result(path) as src:
        return {name: problem(src.h5, _plot_of(name)) for name in SERIES}


def _check(src: Source, name: str) -> None:
    """Refuse a series this result cannot give."""
    reason = problem(src.h5, _plot_of(name))
    if reason:
        raise NotAvailable(reason)


def _at_most(asked: int, cap: int) -> int:
    """`asked` values, or every one (0), never more than `cap`."""
    return min(asked or cap, cap)


def _spread(rows: int, most: int) -> list[slice]:
    """`strides` that keep at most `most` of `rows` rows, the first and the last among them (both,
    even for `most` = 1)."""
    # The last comes on top of the stride's.
    return strides(rows, rows if rows <= most else max(1, most - 1))


def _extremes(values: np.ndarray, size: int) -> np.ndarray:
    """The indices of the least and the greatest of each `size` consecutive `values`."""
    buckets = -(-len(values) // size)
    # The padding repeats the last value, which argmin and argmax find first where it really is.
    grid = np.pad(values, (0, buckets * size - len(values)), mode="edge").reshape(buckets, size)
    start = np.arange(buckets) * size
    return np.concatenate([grid.argmin(axis=1) + start, grid.argmax(axis=1) + start])


def _min_max(table: _Table, rows: int, most: int) -> dict[int, tuple[np.ndarray, np.ndarray]]:
    """Each curve's (x, y), every sample if it has `most` or fewer, else decimated to about `most`.

    A curve against time keeps the extremes of its y; one against another column (the medium's
    force against the penetration) those of its x too, in half as many buckets.
    """
    decimate = rows > most
    signals = 1 if table.x == 0 else 2
    size = math.ceil(rows / max(1, most // (2 * signals))) if decimate else 1
    block = size * max(1, BLOCK_ROWS // size)  # whole buckets
    parts: dict[int, list[tuple[np.ndarray, np.ndarray]]] = {k: [] for k in table.curves}
    for start in range(0, rows, block):
        values = table.read(slice(start, start + block))
        length = len(values[0])
        for k in table.curves:
            kept = slice(None)
            if decimate:
                ends = np.array([0] * (start == 0) + [length - 1] * (start + length == rows), int)
                kept = np.unique(
                    np.concatenate(
                        [_extremes(values[k], size), ends] + ([_extremes(values[table.x], size)] if table.x else [])
                    )
                )
            parts[k].append((values[table.x][kept], values[k][kept]))
    return {k: tuple(np.concatenate(axis) for axis in zip(*curve)) for k, curve in parts.items()}


def _strided(table: _Table, rows: int, most: int) -> dict[int, tuple[np.ndarray, np.ndarray]]:
    """Each curve's (x, y) at one stride: every sample if `most` or fewer, the last always."""
    values = [np.concatenate(column) for column in zip(*map(table.read, strides(rows, most)))]
    return {k: (values[table.x], values[k]) for k in table.curves}


def _axis(column: Column) -> dict:
    return {"label": column.label, "unit": column.unit}


def _curves(src: Source, name: str, points: int) -> dict:
    chart = _CHARTS[name]
    table = chart.table(src)
    most = _at_most(points, MAX_POINTS)
    curves = (_strided if chart.stacked else _min_max)(table, src.rows, most)
    label, unit = chart.y
    return {
        "x": _axis(table.columns[table.x]),
        "y": {"label": label, "unit": unit},
        "samples": src.rows,
        "decimated": any(len(y) < src.rows for _, y in curves.values()),
        "series": [
            {"key": table.columns[k].key, "label": table.columns[k].label, "x": x, "y": y}
            for k, (x, y) in curves.items()
        ],
    }


def _fields(src: Source, times: int, stations: int) -> dict:
    stress = src.h5["fields/stress"]
    frames = _spread(stress.shape[0], _at_most(times, MAX_FIELD_SIDE))
    nodes = _spread(stress.shape[1], _at_most(stations, MAX_FIELD_SIDE))
    shown = np.block([[stress[rows, columns] for columns in nodes] for rows in frames])
    return {
        "x": {"label": "x along the tool", "unit": "m"},
        "time": {"unit": "s"},
        "stress_unit": "Pa",
        "stations": take(src.h5["fields/x"], nodes),
        "times": take(src.h5["fields/time"], frames),
        "stress": shown,
        "samples": {"times": stress.shape[0], "stations": stress.shape[1]},
        "decimated": shown.shape != stress.shape,
    }


def series(
    path: str | Path,
    name: str,
    points: int = DEFAULT_POINTS,
    times: int = DEFAULT_TIMES,
    stations: int = DEFAULT_STATIONS,
) -> dict:
    """Series `name` of the result at `path`, its values as NumPy arrays (`dumps` writes it).

    A curve has about `points` samples (0: every one; MAX_POINTS at the most); the stress field
    `times` frames and `stations` stations, by strides, the first and the last kept (0: all;
    MAX_FIELD_SIDE at the most).
    """
    with open_result(path) as src:
        _check(src, name)
        data = _fields(src, times, stations) if name == FIELDS else _curves(src, name, points)
        return {"name": name, "title": SERIES[name], "case": src.case.get("name", "case"), **data}


def _numbers(values: np.ndarray) -> str:
    """`values` as JSON numbers, to SIGNIFICANT digits."""
    text = (f"%.{SIGNIFICANT}g," * len(values))[:-1] % tuple(values.tolist())
    # JSON has no NaN or infinity.
    return text if np.isfinite(values).all() else re.sub(r"-?\b(nan|inf)\b", "null", text)


def _json(value) -> str:
    if isinstance(value, np.ndarray):
        return f"[{_numbers(value) if value.ndim == 1 else ','.join(map(_json, value))}]"
    if isinstance(value, dict):
        return "{" + ",".join(f"{_json(key)}:{_json(item)}" for key, item in value.items()) + "}"
    if isinstance(value, list):
        return f"[{','.join(map(_json, value))}]"
    return json.dumps(value, ensure_ascii=False)


def dumps(data: dict) -> bytes:
    """A `series` answer as compact JSON: its arrays' numbers to SIGNIFICANT digits."""
    return _json(data).encode()


def _csv_line(cells: list[str]) -> str:
    out = io.StringIO()
    csv.writer(out, lineterminator="\n").writerow(cells)
    return out.getvalue()


def _rows(table: np.ndarray) -> str:
    """CSV rows of a 2-D `table`, each number as Python's repr: read back, the same float."""
    rows, columns = table.shape
    return (",".join(["%r"] * columns) + "\n") * rows % tuple(table.ravel().tolist())


def _field_rows(src: Source) -> tuple[list[str], int, Callable[[slice], np.ndarray]]:
    """The stress field's header, frames, and its rows read: a frame's time, then its stations'."""
    stress, frame_times = src.h5["fields/stress"], src.h5["fields/time"]
    stations = [f"x={x!r} m" for x in src.h5["fields/x"][()].tolist()]
    return (
        [f"{TIME.label} ({TIME.unit})", *stations],
        stress.shape[0],
        lambda rows: np.column_stack([frame_times[rows], stress[rows]]),
    )


def _curve_rows(src: Source, name: str) -> tuple[list[str], int, Callable[[slice], np.ndarray]]:
    """A chart's header, samples, and its rows read: time, then each column."""
    table = _CHARTS[name].table(src)
    return (
        [f"{column.label} ({column.unit})" for column in table.columns],
        src.rows,
        lambda rows: np.column_stack(table.read(rows)),
    )


def _csv(path: str | Path, name: str) -> Iterator[str]:
    with open_result(path) as src:
        _check(src, name)
        header, rows, read = _field_rows(src) if name == FIELDS else _curve_rows(src, name)
        yield _csv_line(header)
        block = max(1, CSV_VALUES // len(header))
        for start in range(0, rows, block):
            yield _rows(read(slice(start, start + block)))


def csv_chunks(path: str | Path, name: str) -> Iterator[str]:
    """Series `name` of the result at `path` as CSV, every sample: a header of names and units,
    then a row a sample (of the stress field, a row a frame: its time, then a column a station).

    A chunk of rows at a time, read as it is taken; a name unknown or unavailable, or a file that
    is not a result, is refused here, before any chunk."""
    chunks = _csv(path, name)
    return itertools.chain([next(chunks)], chunks)
