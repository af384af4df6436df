"""The controller: chunking changes nothing, progress rises, cancellation stops, sampling as asked,
and a streamed run's memory stays bounded."""

import numpy as np
import pytest
from conftest import BASE_CASE, merge

import percussim.solver.controller as controller
from percussim.solver.case import parse_case
from percussim.solver.controller import simulate_rod
from percussim.solver.errors import Cancelled
from percussim.solver.io import read_result
from percussim.solver.limits import output_values
from percussim.solver.simulate import simulate
from percussim.solver.summary import FORCE_HISTORY_POINTS, _downsample

CASE = merge(
    BASE_CASE, {"numerics": {"duration": 1e-3}, "outputs": {"probes": [0.3], "fields": True, "field_stride": 7}}
)


def test_chunk_size_does_not_change_the_result(monkeypatch):
    whole = simulate_rod(parse_case(CASE))
    monkeypatch.setattr(controller, "CHUNK_NODE_STEPS", 101 * 13)  # 13 steps a chunk
    chunked = simulate_rod(parse_case(CASE))
    assert chunked.summary == whole.summary
    for name in whole.history:
        np.testing.assert_array_equal(chunked.history[name], whole.history[name])
    np.testing.assert_array_equal(chunked.fields.stress, whole.fields.stress)
    np.testing.assert_array_equal(chunked.fields.time, whole.fields.time)


def test_progress_rises_to_one_and_cancel_stops(monkeypatch):
    monkeypatch.setattr(controller, "CHUNK_NODE_STEPS", 101 * 100)
    seen = []
    simulate_rod(parse_case(CASE), progress=seen.append)
    assert len(seen) > 5 and seen == sorted(seen) and seen[-1] == 1.0
    calls = []
    with pytest.raises(Cancelled):
        simulate_rod(parse_case(CASE), cancelled=lambda: len(calls) >= 3 or calls.append(1) is not None)
    assert len(calls) == 3


def test_sampling_keeps_what_is_asked():
    full = simulate_rod(parse_case(CASE))
    steps = full.numerics.steps
    assert len(full.history["time"]) == steps + 1
    np.testing.assert_allclose(full.fields.time, np.arange(0, steps + 1, 7) * full.numerics.time_step)
    assert full.fields.displacement.shape == (steps // 7 + 1, 101)
    strided = simulate_rod(parse_case(merge(CASE, {"outputs": {"history_stride": 10, "fields": False}})))
    assert strided.fields is None
    for name in full.history:
        np.testing.assert_array_equal(strided.history[name], full.history[name][::10])
    np.testing.assert_array_equal(strided.probe_stress, full.probe_stress[::10])
    # The summary is observed every step, whatever is kept.
    assert strided.summary["peak_contact_force"] == full.summary["peak_contact_force"]


def test_probe_at_a_node_and_at_the_ends_match_the_field():
    case = merge(CASE, {"outputs": {"probes": [0.0, 0.36, 1.2], "field_stride": 1}})
    result = simulate_rod(parse_case(case))
    for k, node in enumerate((0, 30, 100)):
        np.testing.assert_allclose(result.probe_stress[:, k], result.fields.stress[:, node], rtol=1e-12)
    # At the struck end the stress is the contact force over the area (boundary row (9)).
    np.testing.assert_allclose(
        result.fields.stress[2:, 0], -result.history["contact/force"][2:] / 0.014209, rtol=1e-6, atol=1e3
    )


def test_a_summary_only_run_allocates_nothing_of_size_cells_times_steps():
    import tracemalloc

    case = parse_case(
        merge(
            CASE,
            {
                "numerics": {"cells": 2000, "time_step": 1e-8, "duration": 5e-5, "scheme": "explicit"},
                "outputs": {"probes": [], "fields": False},
            },
        )
    )
    simulate_rod(case)  # compiled and loaded before measuring
    tracemalloc.start()
    result = simulate_rod(case)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    cells, steps = result.numerics.cells, result.numerics.steps
    print(f"{cells} cells × {steps} steps: peak {peak / 1e6:.2f} MB traced")
    assert peak < 0.05 * 8 * cells * steps  # a field of N·M doubles would be 80 MB


def test_the_force_history_is_the_whole_history_downsampled():
    """The summary's force history is gathered during the run; it is the one the whole history gives."""
    result = simulate_rod(parse_case(merge(CASE, {"numerics": {"duration": 4e-3}})))
    assert len(result.history["time"]) > 2 * FORCE_HISTORY_POINTS
    assert result.summary["force_history"] == _downsample(result.history)


def test_a_streamed_run_holds_a_bounded_part_of_its_outputs(tmp_path):
    import tracemalloc

    case = parse_case(
        merge(
            CASE,
            {
                "numerics": {"cells": 2000, "time_step": 1e-8, "duration": 2e-4, "scheme": "explicit"},
                "outputs": {"probes": [0.3], "fields": True, "field_stride": 10},
            },
        )
    )
    simulate(parse_case(CASE), result_path=tmp_path / "warm.h5")  # compiled and loaded before measuring
    tracemalloc.start()
    result = simulate(case, result_path=tmp_path / "r.h5")
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    held = 8 * output_values(case, result.numerics)
    print(
        f"{result.numerics.cells} cells × {result.numerics.steps} steps: outputs {held / 1e6:.1f} MB, "
        f"peak {peak / 1e6:.2f} MB traced"
    )
    assert held > 60e6 and peak < 0.25 * held  # holding the outputs would take 1×
    assert len(read_result(tmp_path / "r.h5").history["time"]) == result.numerics.steps + 1
