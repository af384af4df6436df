"""HDF5 results in the contract's layout, written to a temporary name and renamed when complete."""

from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path

import h5py
import numpy as np

from .case import Case
from .controller import Fields, Result
from .grid import ResolvedNumerics

FORMAT = "percussim-result"
FORMAT_VERSION = 1

_UNITS = {"time": "s", "displacement": "m", "velocity": "m/s", "force": "N", "overlap": "m",
          "energy": "J", "x": "m", "stress": "Pa"}


def units(path: str) -> str:
    """SI units of a result dataset, from its path."""
    if path.startswith("energy/"):
        return "J"
    name = path.rsplit("/", 1)[-1]
    return "m" if name.endswith("_displacement") else _UNITS[name]


def _dataset(group: h5py.Group, path: str, data: np.ndarray, **options) -> None:
    group.create_dataset(path, data=data, **options).attrs["units"] = units(path)


def write_result(result: Result, path: str | Path) -> Path:
    """Write `result` to `path` atomically: a reader never sees half a file."""
    from . import __version__

    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".part", dir=path.parent)
    os.close(fd)
    try:
        with h5py.File(tmp, "w") as f:
            f.attrs["format"] = FORMAT
            f.attrs["format_version"] = FORMAT_VERSION
            f.attrs["solver_version"] = __version__
            f.attrs["case"] = result.case.model_dump_json()
            f.attrs["numerics"] = json.dumps(result.numerics.as_dict())
            for key, value in result.numerics.as_dict().items():
                f.attrs[f"numerics.{key}"] = value
            f.create_dataset("summary", data=json.dumps(result.summary))
            for name, data in result.history.items():
                _dataset(f, name, data)
            _dataset(f, "probes/x", result.probe_x)
            _dataset(f, "probes/stress", result.probe_stress)
            if result.fields is not None:
                _dataset(f, "fields/x", result.fields.x)
                _dataset(f, "fields/time", result.fields.time)
                big = {"chunks": True, "compression": "gzip", "compression_opts": 4, "shuffle": True}
                _dataset(f, "fields/displacement", result.fields.displacement, **big)
                _dataset(f, "fields/stress", result.fields.stress, **big)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def read_result(path: str | Path) -> Result:
    """Read a result file back into a `Result`."""
    with h5py.File(path, "r") as f:
        if f.attrs.get("format") != FORMAT:
            raise ValueError(f"{path} is not a {FORMAT} file")
        case = Case.model_validate_json(f.attrs["case"])
        numerics = ResolvedNumerics(**json.loads(f.attrs["numerics"]))
        summary = json.loads(f["summary"][()])
        history = {}
        f.visititems(lambda name, obj: history.__setitem__(name, obj[()])
                     if isinstance(obj, h5py.Dataset) else None)
        fields = None
        if "fields" in f:
            fields = Fields(*(history.pop(f"fields/{k}") for k in ("x", "time", "displacement", "stress")))
    probe_x, probe_stress = history.pop("probes/x"), history.pop("probes/stress")
    history.pop("summary")
    return Result(case=case, numerics=numerics, history=history, probe_x=probe_x,
                  probe_stress=probe_stress, fields=fields, summary=summary)
