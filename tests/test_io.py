"""HDF5 results: the contract's layout, a lossless round trip, atomic writes."""

import h5py
import numpy as np
import pytest

from conftest import BASE_CASE, merge
from solver import parse_case, simulate_rod
from solver.io import read_result, write_result

CASE = merge(BASE_CASE, {"numerics": {"duration": 5e-4},
                         "outputs": {"probes": [0.0, 0.6, 1.2], "fields": True, "field_stride": 25}})
CONTRACT_DATASETS = [
    "time", "striker/displacement", "striker/velocity", "tool/struck_end_displacement",
    "tool/working_end_displacement", "contact/force", "contact/overlap", "medium/force",
    "probes/x", "probes/stress", "fields/x", "fields/time", "fields/displacement", "fields/stress",
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
