"""HDF5 results in the contract's layout, written to a temporary name and renamed when complete.

One writer, `ResultWriter`, makes every file: streamed to while a run goes (it is the run's
`Recorder`), or given a finished in-memory result (`write_result`).

Datasets and attributes are made through h5py's low-level API, into the same files as its
high-level one makes. That one spends tens of microseconds of Python on each dataset, attribute and
write, and a small job's file has 20 datasets, 33 attributes and as many writes: it was most of the
job's time (`bench/load.py` prints what the write costs a job).
"""

from __future__ import annotations

import glob
import json
import os
import secrets
from functools import cache
from importlib.metadata import version
from math import prod
from pathlib import Path
from typing import BinaryIO

import h5py
import numpy as np
import pydantic_core
from h5py import h5a, h5d, h5p, h5s, h5t

from .case import Case
from .grid import ResolvedNumerics
from .result import Result

FORMAT = "percussim-result"
FORMAT_VERSION = 1
PARTIAL = ".part"  # suffix of a file being written
COMPRESSED = {"fields/displacement", "fields/stress"}  # gzip after byte shuffling
DEFLATE_LEVEL = 4
# A field's chunks span the whole tool, as few rows as make about this many bytes: a row of chunks
# is what a writer holds (h5py's own choice on 10^4 cells held 32 rows, 2.6 MB a dataset).
FIELD_CHUNK_BYTES = 1 << 18
# An unchunked dataset's rows are written in blocks of about this size: a write costs tens of
# microseconds beside its bytes, and a hammer's 100 cycles write 700,000 rows to each of 54
# datasets (in blocks of 32 KiB, 0.15 s more of the 1.1 s they took; at most 14 MB held).
HELD_BYTES = 1 << 18

_UNITS = {
    "time": "s",
    "displacement": "m",
    "velocity": "m/s",
    "force": "N",
    "overlap": "m",
    "penetration": "m",
    "energy": "J",
    "x": "m",
    "stress": "Pa",
    "resistance": "N/m",  # along the tool, per metre
    "pressure": "Pa",  # a hammer's drive's
}


def units(path: str) -> str:
    """SI units of a result dataset, from its path: every `energy/` term's, else its name's or its
    name's last word's (`struck_end_displacement`, `permanent_penetration`). An unknown name is a
    KeyError: no dataset is written without its units."""
    if path.startswith("energy/"):
        return "J"
    name = path.rsplit("/", 1)[-1]
    return _UNITS[name] if name in _UNITS else _UNITS[name.rsplit("_", 1)[-1]]


def _chunk_rows(shape: tuple[int, ...], dtype: np.dtype) -> int:
    """A field's rows a chunk: whole rows, about FIELD_CHUNK_BYTES a chunk."""
    row_bytes = np.dtype(dtype).itemsize * prod(shape[1:])
    return max(1, min(shape[0], FIELD_CHUNK_BYTES // max(1, row_bytes)))


_TEXT = h5py.string_dtype()  # variable-length UTF-8, as h5py stores a str


@cache
def _hdf5_type(dtype: np.dtype) -> h5t.TypeID:
    """The HDF5 type h5py gives `dtype`, made once a dtype rather than once an object."""
    return h5t.py_create(dtype, logical=True)


def _attribute(target: h5d.DatasetID | h5py.h5f.FileID, name: str, value: str | int | float | bool) -> None:
    """Set attribute `name` of a new HDF5 object, typed as h5py's `attrs[name] = value` types it."""
    data = np.array(value, dtype=_TEXT if isinstance(value, str) else None)
    h5a.create(target, name.encode(), _hdf5_type(data.dtype), h5s.create(h5s.SCALAR)).write(data)


def _property_list(kind: h5p.PropClassID, **settings: tuple) -> h5p.PropID:
    properties = h5p.create(kind)
    for setting, arguments in settings.items():
        getattr(properties, setting)(*arguments)
    return properties


_LINKS = _property_list(h5p.LINK_CREATE, set_create_intermediate_group=(True,))
# Never filled: every row is written once (`_Rows`).
_NEVER_FILLED = _property_list(h5p.DATASET_CREATE, set_fill_time=(h5d.FILL_TIME_NEVER,))
# Each chunk is written once, whole (see `_Rows`), so HDF5's chunk cache (8 MiB a dataset from
# HDF5 2.0) is of no use: 1 byte turns it off.
_NO_CHUNK_CACHE = _property_list(h5p.DATASET_ACCESS, set_chunk_cache=(0, 1, 1.0))


def _dataset(
    file: h5py.File, name: str, shape: tuple[int, ...], dtype: np.dtype, chunk_rows: int | None
) -> h5d.DatasetID:
    """A new dataset at path `name` (its groups made as needed); chunked by `chunk_rows` rows and
    compressed when given."""
    layout, access = _NEVER_FILLED, None
    if chunk_rows is not None:
        layout = _NEVER_FILLED.copy()
        layout.set_chunk((chunk_rows,) + tuple(shape[1:]))
        layout.set_shuffle()
        layout.set_deflate(DEFLATE_LEVEL)
        access = _NO_CHUNK_CACHE
    return h5d.create(
        file.id,
        name.encode(),
        _hdf5_type(np.dtype(dtype)),
        h5s.create_simple(shape),
        dcpl=layout,
        lcpl=_LINKS,
        dapl=access,
    )


class _Rows:
    """One dataset filled in order through a buffer of rows, written when full. A chunked
    dataset's buffer is one row of chunks, so that each chunk is compressed and written once (a
    chunk written in parts is read back, decompressed and rewritten, and may leave its old space
    unused in the file); an unchunked one's is about HELD_BYTES, so that a long history is not
    written a few rows at a time."""

    def __init__(
        self, name: str, dataset: h5d.DatasetID, shape: tuple[int, ...], dtype: np.dtype, chunk_rows: int | None
    ):
        self.name, self.dataset, self.rows = name, dataset, shape[0]
        row_bytes = np.dtype(dtype).itemsize * prod(shape[1:])
        block = chunk_rows if chunk_rows is not None else HELD_BYTES // max(1, row_bytes)
        self.buffer = np.empty((max(1, min(block, self.rows)),) + tuple(shape[1:]), dtype)
        self.held = 0
        self.written = 0

    def append(self, rows: np.ndarray) -> None:
        if not self.held:
            # Whole blocks, or all that is left, go to the file at once: a held result is
            # written one write a dataset.
            last = self.written + len(rows) == self.rows
            whole = len(rows) if last else len(rows) - len(rows) % len(self.buffer)
            if whole:
                self._write(np.ascontiguousarray(rows[:whole]))
                rows = rows[whole:]
        while len(rows):
            take = min(len(rows), len(self.buffer) - self.held)
            self.buffer[self.held : self.held + take] = rows[:take]
            self.held += take
            rows = rows[take:]
            if self.held == len(self.buffer):
                self._write_held()

    def close(self) -> None:
        self._write_held()
        if self.written != self.rows:
            raise RuntimeError(f"{self.name}: {self.written} of {self.rows} rows written")

    def _write_held(self) -> None:
        if self.held:
            self._write(self.buffer[: self.held])
            self.held = 0

    def _write(self, block: np.ndarray) -> None:
        """Write the C-contiguous `block` of rows after those written."""
        target = self.dataset.get_space()
        target.select_hyperslab((self.written,) + (0,) * (block.ndim - 1), block.shape)
        self.dataset.write(h5s.create_simple(block.shape), target, block)
        self.written += len(block)


class ResultWriter:
    """A result file in the making, to be used in a `with` block.

    It is a `Recorder`: a run streams its datasets into a temporary file next to `path`, and
    `commit` completes the file with the result's attributes and summary and renames it to
    `path`. Leaving the block without a commit (an exception, a cancellation) removes the
    temporary file: a reader never sees half a file, and a job run again rewrites it whole.
    """

    def __init__(self, path: str | Path):
        self.path = Path(path)
        self._tmp: Path | None = None
        self._file: h5py.File | None = None
        self._rows: dict[str, _Rows] = {}

    def __enter__(self) -> ResultWriter:
        self.path.parent.mkdir(parents=True, exist_ok=True)
        # A fresh name that h5py creates, not mkstemp's file: the result gets the permissions the
        # user's umask gives, not mkstemp's owner-only ones.
        self._tmp = self.path.with_name(f".{self.path.name}.{secrets.token_hex(8)}{PARTIAL}")
        return self

    def __exit__(self, kind, error, trace) -> None:
        try:
            self._close()
        except (OSError, RuntimeError):
            # Closing a file whose write failed (a full disk) fails too: the write's error is
            # the one to tell, and the file goes anyway.
            if error is None:
                raise
        finally:
            if self._tmp is not None:
                self._tmp.unlink(missing_ok=True)

    def start(self) -> None:
        self._close()
        self._file = h5py.File(self._tmp, "w")
        self._rows = {}

    def create(self, name: str, shape: tuple[int, ...], dtype: np.dtype = np.dtype(float)) -> None:
        chunk_rows = _chunk_rows(shape, dtype) if name in COMPRESSED else None
        dataset = _dataset(self._file, name, shape, dtype, chunk_rows)
        _attribute(dataset, "units", units(name))
        self._rows[name] = _Rows(name, dataset, shape, dtype, chunk_rows)

    def append(self, name: str, rows: np.ndarray) -> None:
        self._rows[name].append(rows)

    def held(self) -> None:
        return None

    def commit(self, result: Result) -> Path:
        """Complete the file with `result`, and its arrays unless it was streamed here; rename it."""
        if not result.streamed:
            self.start()
            for name, data in result.arrays().items():
                self.create(name, data.shape, data.dtype)
                self.append(name, data)
        elif self._file is None:
            raise ValueError("a streamed result's arrays are only in the file it was streamed to")
        numerics = result.numerics.as_dict()
        summary = result.summary
        estimate = summary.get("error_estimate")
        attributes = {
            "format": FORMAT,
            "format_version": FORMAT_VERSION,
            "solver_version": version("percussim"),
            "case": result.case.model_dump_json(),
            "numerics": json.dumps(numerics),
            **{f"numerics.{key}": value for key, value in numerics.items()},
            # what the summary says of its accuracy, readable without parsing it
            "error_estimate": json.dumps(estimate),
            "not_estimated": json.dumps(summary.get("not_estimated", {})),
            "warnings": json.dumps(summary["warnings"]),
        }
        if estimate is not None:
            attributes["error_estimate.worst"] = float(estimate["worst"])
        if summary.get("tolerance") is not None:
            attributes["tolerance"] = float(summary["tolerance"])
        for name, value in attributes.items():
            _attribute(self._file.id, name, value)
        # pydantic's compiled encoder: the same text as json.dumps (NaN aside, which becomes null),
        # at a fraction of its cost on a summary's force history.
        result.summary_json = pydantic_core.to_json(result.summary).decode()
        summary = np.array(result.summary_json, dtype=_TEXT)
        h5d.create(self._file.id, b"summary", _hdf5_type(summary.dtype), h5s.create(h5s.SCALAR)).write(
            h5s.ALL, h5s.ALL, summary
        )
        for rows in self._rows.values():
            rows.close()
        self._close()
        os.replace(self._tmp, self.path)
        self._tmp = None
        return self.path

    def _close(self) -> None:
        if self._file is not None:
            self._file.close()
            self._file = None


def write_result(result: Result, path: str | Path) -> Path:
    """Write `result`, held in memory, to `path` atomically: a reader never sees half a file."""
    with ResultWriter(path) as writer:
        return writer.commit(result)


def remove_partial(path: str | Path) -> None:
    """Remove what writers of `path` that died before finishing (a killed worker) left behind."""
    path = Path(path)
    for tmp in path.parent.glob(f".{glob.escape(path.name)}.*{PARTIAL}"):
        tmp.unlink(missing_ok=True)


def read_result(source: str | Path | BinaryIO) -> Result:
    """Read a result file, or a binary file object holding one (bytes downloaded), into a `Result`."""
    with h5py.File(source, "r") as f:
        if f.attrs.get("format") != FORMAT:
            raise ValueError(f"{source if isinstance(source, (str, Path)) else 'the data'} is not a {FORMAT} file")
        case = Case.model_validate_json(f.attrs["case"])
        numerics = ResolvedNumerics(**json.loads(f.attrs["numerics"]))
        arrays = {}
        f.visititems(lambda name, obj: arrays.__setitem__(name, obj[()]) if isinstance(obj, h5py.Dataset) else None)
    summary = json.loads(arrays.pop("summary"))
    return Result.from_arrays(case, numerics, arrays, summary)
