"""HDF5 results in the contract's layout, written to a temporary name and renamed when complete.

One writer, `ResultWriter`, makes every file: streamed to while a run goes (it is the run's
`Recorder`), or given a finished in-memory result (`write_result`).
"""

from __future__ import annotations

import glob
import json
import os
import secrets
from math import prod
from pathlib import Path
from typing import BinaryIO

import h5py
import numpy as np

from .case import Case
from .controller import Result
from .grid import ResolvedNumerics

FORMAT = "percussim-result"
FORMAT_VERSION = 1
PARTIAL = ".part"  # suffix of a file being written
COMPRESSED = {"fields/displacement", "fields/stress"}
# Each chunk is written once, whole (see `_Rows`), so HDF5's chunk cache (8 MiB a dataset from
# HDF5 2.0) is of no use; h5py reads a size of 0 as "the default", 1 byte turns it off.
_COMPRESSION = {"compression": "gzip", "compression_opts": 4, "shuffle": True, "rdcc_nbytes": 1}
# A field's chunks span the whole tool, as few rows as make about this many bytes: a row of chunks
# is what a writer holds (h5py's own choice on 10^4 cells held 32 rows, 2.6 MB a dataset).
FIELD_CHUNK_BYTES = 1 << 18
HELD_BYTES = 1 << 15  # an unchunked dataset's rows are written in blocks of about this size

_UNITS = {"time": "s", "displacement": "m", "velocity": "m/s", "force": "N", "overlap": "m",
          "energy": "J", "x": "m", "stress": "Pa"}


def units(path: str) -> str:
    """SI units of a result dataset, from its path."""
    if path.startswith("energy/"):
        return "J"
    name = path.rsplit("/", 1)[-1]
    return "m" if name.endswith("_displacement") else _UNITS[name]


def _compressed(shape: tuple[int, ...], dtype: np.dtype) -> dict:
    """Chunking and compression of a field: whole rows, about FIELD_CHUNK_BYTES a chunk."""
    row_bytes = np.dtype(dtype).itemsize * prod(shape[1:])
    rows = max(1, min(shape[0], FIELD_CHUNK_BYTES // max(1, row_bytes)))
    return {"chunks": (rows,) + tuple(shape[1:]), **_COMPRESSION}


class _Rows:
    """One dataset filled in order through a buffer of rows, written when full. A chunked
    dataset's buffer is one row of chunks, so that each chunk is compressed and written once (a
    chunk written in parts is read back, decompressed and rewritten, and may leave its old space
    unused in the file); an unchunked one's is about HELD_BYTES, so that a long history is not
    written a few rows at a time."""

    def __init__(self, dataset: h5py.Dataset):
        self.dataset = dataset
        row_bytes = dataset.dtype.itemsize * prod(dataset.shape[1:])
        block = dataset.chunks[0] if dataset.chunks else HELD_BYTES // max(1, row_bytes)
        self.buffer = np.empty((max(1, min(block, len(dataset))),) + dataset.shape[1:], dataset.dtype)
        self.held = 0
        self.written = 0

    def append(self, rows: np.ndarray) -> None:
        while len(rows):
            take = min(len(rows), len(self.buffer) - self.held)
            self.buffer[self.held:self.held + take] = rows[:take]
            self.held += take
            rows = rows[take:]
            if self.held == len(self.buffer):
                self._write()

    def close(self) -> None:
        self._write()
        if self.written != len(self.dataset):
            raise RuntimeError(f"{self.dataset.name}: {self.written} of {len(self.dataset)} rows written")

    def _write(self) -> None:
        if self.held:
            # write_direct: half the cost of slice assignment, which a small job pays ~40 times.
            self.dataset.write_direct(self.buffer, np.s_[:self.held],
                                      np.s_[self.written:self.written + self.held])
            self.written += self.held
            self.held = 0


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

    def __exit__(self, *exc) -> None:
        try:
            self._close()
        finally:
            if self._tmp is not None:
                self._tmp.unlink(missing_ok=True)

    def start(self) -> None:
        self._close()
        self._file = h5py.File(self._tmp, "w")
        self._rows = {}

    def create(self, name: str, shape: tuple[int, ...], dtype: np.dtype = np.dtype(float)) -> None:
        dataset = self._file.create_dataset(name, shape=shape, dtype=dtype,
                                            **(_compressed(shape, dtype) if name in COMPRESSED else {}))
        dataset.attrs["units"] = units(name)
        self._rows[name] = _Rows(dataset)

    def append(self, name: str, rows: np.ndarray) -> None:
        self._rows[name].append(rows)

    def held(self) -> None:
        return None

    def commit(self, result: Result) -> Path:
        """Complete the file with `result`, and its arrays unless it was streamed here; rename it."""
        from . import __version__

        if not result.streamed:
            self.start()
            for name, data in result.arrays().items():
                self.create(name, data.shape, data.dtype)
                self.append(name, data)
        elif self._file is None:
            raise ValueError("a streamed result's arrays are only in the file it was streamed to")
        f = self._file
        f.attrs["format"] = FORMAT
        f.attrs["format_version"] = FORMAT_VERSION
        f.attrs["solver_version"] = __version__
        f.attrs["case"] = result.case.model_dump_json()
        f.attrs["numerics"] = json.dumps(result.numerics.as_dict())
        for key, value in result.numerics.as_dict().items():
            f.attrs[f"numerics.{key}"] = value
        result.summary_json = json.dumps(result.summary)
        f.create_dataset("summary", data=result.summary_json)
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
        f.visititems(lambda name, obj: arrays.__setitem__(name, obj[()])
                     if isinstance(obj, h5py.Dataset) else None)
    summary = json.loads(arrays.pop("summary"))
    return Result.from_arrays(case, numerics, arrays, summary)
