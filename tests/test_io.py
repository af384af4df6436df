"""HDF5 results: the contract's layout, a lossless round trip, atomic writes, streamed runs."""

import json
import os
import re
import stat
from pathlib import Path

import h5py
import numpy as np
import pytest
from conftest import BASE_CASE, merge

import percussim.solver.controller as controller
import percussim.solver.io as io
from percussim.solver.case import parse_case
from percussim.solver.controller import simulate_rod
from percussim.solver.errors import Cancelled
from percussim.solver.io import read_result, remove_partial, write_result
from percussim.solver.simulate import simulate
from percussim.testing.closed_forms import drilling

HDF5_DOC = Path(__file__).resolve().parents[1] / "docs" / "hdf5.md"
CASE = merge(
    BASE_CASE,
    {"numerics": {"duration": 5e-4}, "outputs": {"probes": [0.0, 0.6, 1.2], "fields": True, "field_stride": 25}},
)
CONTRACT_DATASETS = [
    "time",
    "striker/displacement",
    "striker/velocity",
    "tool/struck_end_displacement",
    "tool/working_end_displacement",
    "contact/force",
    "contact/overlap",
    "medium/force",
    "probes/x",
    "probes/stress",
    "fields/x",
    "fields/time",
    "fields/displacement",
    "fields/stress",
]


def test_round_trip_keeps_every_dataset_and_the_case(tmp_path):
    result = simulate_rod(parse_case(CASE))
    path = write_result(result, tmp_path / "r.h5")
    assert [p.name for p in tmp_path.iterdir()] == ["r.h5"]  # no temporary left behind
    back = read_result(path)
    assert back.case == result.case
    assert back.numerics == result.numerics
    assert back.summary == result.summary
    assert back.history.keys() == result.history.keys()
    for name, data in result.history.items():
        np.testing.assert_array_equal(back.history[name], data, err_msg=name)
    np.testing.assert_array_equal(back.probe_x, result.probe_x)
    np.testing.assert_array_equal(back.probe_stress, result.probe_stress)
    for name in ("x", "time", "displacement", "stress"):
        np.testing.assert_array_equal(getattr(back.fields, name), getattr(result.fields, name))


def test_layout_and_units_follow_the_contract(tmp_path):
    result = simulate_rod(parse_case(CASE))
    with h5py.File(write_result(result, tmp_path / "r.h5")) as f:
        assert f.attrs["format"] == "percussim-result"
        assert f.attrs["format_version"] >= 1
        assert "solver_version" in f.attrs and f.attrs["numerics.cells"] == 100
        assert parse_case(f.attrs["case"]) == result.case
        for name in CONTRACT_DATASETS:
            assert name in f, name
            assert f[name].attrs["units"], name
        assert f["contact/force"].attrs["units"] == "N"
        assert f["fields/stress"].attrs["units"] == "Pa"
        assert f["fields/stress"].compression == "gzip"
        assert f["fields/displacement"].shape == (len(result.fields.time), 101)


def test_a_failed_write_leaves_nothing(tmp_path):
    result = simulate_rod(parse_case(CASE))
    result.history["bad/name"] = np.zeros(3)  # no units known for it: the write fails midway
    with pytest.raises(KeyError):
        write_result(result, tmp_path / "r.h5")
    assert list(tmp_path.iterdir()) == []


def _layout(f: h5py.File) -> dict:
    """Every dataset's shape, type, storage and attributes, and the file's attributes."""
    found = {"/": dict(f.attrs)}
    f.visititems(
        lambda name, d: (
            found.__setitem__(
                name, (d.shape, d.dtype, d.chunks, d.compression, d.compression_opts, d.shuffle, dict(d.attrs))
            )
            if isinstance(d, h5py.Dataset)
            else None
        )
    )
    return found


def _same_files(streamed, held) -> None:
    with h5py.File(streamed) as s, h5py.File(held) as h:
        assert _layout(s) == _layout(h)
        for name in _layout(h):
            if name != "/":
                np.testing.assert_array_equal(s[name][()], h[name][()], err_msg=name)


def test_a_streamed_result_is_the_file_write_result_makes(tmp_path, monkeypatch):
    # Chunks of 13 steps, history written 40 rows at a time and fields in chunks of 10 rows: every
    # buffer boundary is crossed.
    monkeypatch.setattr(controller, "CHUNK_NODE_STEPS", 101 * 13)
    monkeypatch.setattr(io, "HELD_BYTES", 8 * 40)
    monkeypatch.setattr(io, "FIELD_CHUNK_BYTES", 8 * 101 * 10)
    case = parse_case(merge(CASE, {"outputs": {"field_stride": 1}}))
    held = simulate(case)
    write_result(held, tmp_path / "held.h5")
    streamed = simulate(case, result_path=tmp_path / "streamed.h5")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["held.h5", "streamed.h5"]
    assert streamed.streamed and not held.streamed
    assert streamed.summary == held.summary and streamed.numerics == held.numerics
    assert streamed.history == {} and streamed.fields is None and len(streamed.probe_stress) == 0
    with h5py.File(tmp_path / "held.h5") as f:
        assert f["fields/stress"].chunks == (10, 101)  # whole rows, several rows of chunks
    _same_files(tmp_path / "streamed.h5", tmp_path / "held.h5")
    back = read_result(tmp_path / "streamed.h5")
    assert back.summary == held.summary
    for name, data in held.arrays().items():
        np.testing.assert_array_equal(back.arrays()[name], data, err_msg=name)


def test_a_tolerance_ladder_streams_only_its_result(tmp_path):
    case = parse_case(
        merge(
            CASE,
            {"numerics": {"duration": 2e-3, "tolerance": 1e-2, "scheme": "explicit", "cells": None, "time_step": None}},
        )
    )
    held = simulate(case)
    assert len(held.summary["runs"]) >= 3  # a later run replaced an earlier candidate
    write_result(held, tmp_path / "held.h5")
    streamed = simulate(case, result_path=tmp_path / "streamed.h5")
    assert streamed.summary == held.summary
    _same_files(tmp_path / "streamed.h5", tmp_path / "held.h5")


@pytest.mark.parametrize("stop", [Cancelled, RuntimeError])
def test_a_streamed_run_stopped_midway_leaves_nothing(tmp_path, monkeypatch, stop):
    monkeypatch.setattr(controller, "CHUNK_NODE_STEPS", 101 * 50)
    seen = []

    def progress(fraction):
        seen.append(fraction)
        if len(seen) == 5:  # by then the file holds several chunks' rows
            assert len(list(tmp_path.iterdir())) == 1
            raise stop("stopped")

    with pytest.raises(stop):
        simulate(parse_case(CASE), progress=progress, result_path=tmp_path / "r.h5")
    assert list(tmp_path.iterdir()) == []


def test_a_stopped_run_leaves_the_previous_file_as_it_was(tmp_path, monkeypatch):
    monkeypatch.setattr(controller, "CHUNK_NODE_STEPS", 101 * 50)
    path = write_result(simulate_rod(parse_case(CASE)), tmp_path / "r.h5")
    before = path.read_bytes()
    with pytest.raises(Cancelled):
        simulate(parse_case(CASE), cancelled=lambda: True, result_path=path)
    assert [p.name for p in tmp_path.iterdir()] == ["r.h5"] and path.read_bytes() == before


def test_remove_partial_removes_only_what_dead_writers_left(tmp_path):
    path = write_result(simulate_rod(parse_case(CASE)), tmp_path / "r.h5")
    (tmp_path / ".r.h5.x1y2.part").write_bytes(b"half a file")
    (tmp_path / ".other.h5.x1y2.part").write_bytes(b"another file's")
    remove_partial(path)
    assert sorted(p.name for p in tmp_path.iterdir()) == [".other.h5.x1y2.part", "r.h5"]


def test_a_result_file_gets_the_permissions_of_the_users_umask(tmp_path):
    """Written through a temporary file, yet not owner-only as mkstemp's would be."""
    old = os.umask(0o022)
    try:
        path = write_result(simulate(parse_case(CASE)), tmp_path / "result.h5")
    finally:
        os.umask(old)
    assert stat.S_IMODE(path.stat().st_mode) == 0o644


# An elastic piston on bilinear rock, two blows: every dataset the newer models add.
BLOWS_CASE = drilling(2, {"scheme": "explicit", "cells": 100})
ADDED_UNITS = {
    "medium/penetration": "m",
    "medium/permanent_penetration": "m",
    "energy/medium_plastic": "J",
    "energy/striker_strain": "J",
}


def documented_units() -> dict[str, str]:
    """Each dataset of docs/hdf5.md's table (a row may name several) and its units column."""
    units = {}
    for line in HDF5_DOC.read_text().splitlines():
        cells = [cell.strip() for cell in line.strip().strip("|").split("|")]
        if line.startswith("| `/") and len(cells) == 4:
            for path in re.findall(r"`/([^`]+)`", cells[0]):
                units[path] = cells[2]
    return units


def test_a_yielding_medium_an_elastic_striker_and_blows_are_written_with_their_units(tmp_path):
    case = parse_case(BLOWS_CASE)
    held = simulate(case)
    write_result(held, tmp_path / "held.h5")
    # the service streams its results: the same file
    simulate(case, result_path=tmp_path / "streamed.h5")
    _same_files(tmp_path / "streamed.h5", tmp_path / "held.h5")
    with h5py.File(tmp_path / "held.h5") as f:
        for path, unit in ADDED_UNITS.items():
            assert f[path].attrs["units"] == unit, path
        # the penetration is the working end's u_N, and what stays of it ends as the summary's
        np.testing.assert_array_equal(f["medium/penetration"][()], f["tool/working_end_displacement"][()])
        summary = json.loads(f["summary"][()])
        assert f["medium/permanent_penetration"][-1] == summary["medium_penetration"]["permanent"] > 0
        assert f["energy/medium_plastic"][-1] > 0 and f["energy/striker_strain"][0] == 0.0
        # the blows table is the summary's, stored whole
        assert len(summary["blows"]) == 2 and summary["blows"] == held.summary["blows"]
        assert summary["blows"][1]["permanent_penetration"] == summary["medium_penetration"]["permanent"]
    back = read_result(tmp_path / "held.h5")
    assert set(ADDED_UNITS) <= back.history.keys() == held.history.keys()
    for name, data in held.history.items():
        np.testing.assert_array_equal(back.history[name], data, err_msg=name)


def test_every_dataset_written_is_documented_with_its_units(tmp_path):
    documented = documented_units()
    assert documented["fields/stress"] == "Pa" and documented["energy/tool_strain"] == "J"
    # an elastic striker with its fields, an anvil and blows: every dataset the newer models add
    anvil = merge(
        BLOWS_CASE,
        {
            "anvil": {"mass": 0.5, "contact": {"stiffness": 1e10, "exponent": 0.0}},
            "outputs": {"fields": True, "field_stride": 50},
        },
    )
    for name, case in (("paper", CASE), ("blows", BLOWS_CASE), ("anvil", anvil)):
        with h5py.File(write_result(simulate(parse_case(case)), tmp_path / f"{name}.h5")) as f:
            written = {}
            f.visititems(
                lambda path, d: (
                    written.__setitem__(path, d.attrs.get("units", "")) if isinstance(d, h5py.Dataset) else None
                )
            )
        for path, unit in written.items():
            assert documented.get(path) == unit, (name, path, unit)
