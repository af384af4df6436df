"""Plots of a result: each one drawn from the datasets themselves, refused with what to change
when the result lacks what it needs, from the command line and over HTTP (cached once drawn)."""

from __future__ import annotations

import json
import math
import os
import shutil
import struct
import subprocess
import sys
import xml.etree.ElementTree as ET

import h5py
import numpy as np
import pytest
from conftest import BASE_CASE, merge, succeeded_job
from fastapi.testclient import TestClient

import percussim.solver.plots as plots
from percussim.cli import main
from percussim.common.settings import Settings
from percussim.common.store import SUCCEEDED, JobStore
from percussim.service.app import create_app
from percussim.solver.case import parse_case
from percussim.solver.io import write_result
from percussim.solver.plots import PLOTS, NotAResult, NotAvailable, UnknownPlot, figure, problem, render, write_plots
from percussim.solver.presets import preset_json
from percussim.solver.simulate import simulate
from percussim.testing.closed_forms import MEDIUM_FINE, drilling, hammer_at_work, soil_case
from percussim.testing.live_stack import ROOT

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
# The result each plot is drawn from in the tests that draw every plot: the Fig. 9 preset's, but
# for the blows table, which only a case run blow after blow has.
DRAWN_FROM = {name: name if name in ("blows", "cycle") else "full" for name in PLOTS}


def _write(folder, name: str, case: dict) -> str:
    return str(write_result(simulate(parse_case(case)), folder / f"{name}.h5"))


def _result(folder, name: str, changes: dict) -> str:
    return _write(folder, name, merge(preset_json("fig9"), {"numerics": {"cells": 40}, **changes}))


@pytest.fixture(scope="module")
def results(tmp_path_factory) -> dict[str, str]:
    """The Fig. 9 preset on 40 cells with fields and probes (`full`), with fields every 125 µs
    (`sparse`), without fields or probes (`bare`), without a medium (`free`), and as the lumped
    model with fields asked for (`lumped`); an elastic piston on bilinear rock, 3 blows
    (`blows`); one on Smith soil that flows, without and with damping (`soil`, `damped soil`)."""
    folder = tmp_path_factory.mktemp("results")
    blows = drilling(3, {"scheme": "explicit", "cells": 100})
    return {
        "full": _result(folder, "full", {"outputs": {"fields": True, "field_stride": 20}}),
        "sparse": _result(folder, "sparse", {"outputs": {"fields": True, "field_stride": 400}}),
        "bare": _result(folder, "bare", {"outputs": None}),
        "free": _result(folder, "free", {"medium": None, "outputs": None}),
        "lumped": _result(
            folder, "lumped", {"numerics": {"model": "lumped"}, "outputs": {"fields": True, "probes": []}}
        ),
        "blows": _write(folder, "blows", {**blows, "name": "blows"}),
        "cycle": _write(folder, "cycle", hammer_at_work(cycles={"count": 3}) | {"name": "cycle"}),
        "soil": _write(folder, "soil", soil_case(MEDIUM_FINE)),
        "damped soil": _write(folder, "damped soil", soil_case(MEDIUM_FINE, damping_factor=0.5)),
    }


def _strided(dataset: h5py.Dataset, most: int) -> np.ndarray:
    """Every k-th row, k = ⌈rows / most⌉, and the last."""
    k = math.ceil(len(dataset) / most)
    assert (len(dataset) - 1) % k, "the last row is not on the stride: the test would not see it added"
    return np.concatenate([dataset[::k], dataset[-1:]])


def _line(ax, label: str):
    [line] = [line for line in ax.get_lines() if line.get_label() == label]
    return line


@pytest.mark.parametrize("name", PLOTS)
def test_every_plot_renders_as_png_and_svg(results, name):
    png = render(results[DRAWN_FROM[name]], name, "png")
    assert png.startswith(PNG_SIGNATURE)
    width, height = struct.unpack(">II", png[16:24])  # the IHDR chunk
    assert (width, height) == (plots.FIGSIZE[0] * plots.DPI, plots.FIGSIZE[1] * plots.DPI)
    svg = ET.fromstring(render(results[DRAWN_FROM[name]], name, "svg"))
    assert svg.tag == "{http://www.w3.org/2000/svg}svg"


@pytest.mark.parametrize("name", PLOTS)
def test_every_plot_has_labelled_axes_with_data_and_a_title_naming_the_case(results, name):
    fig = figure(results[DRAWN_FROM[name]], name)
    ax = fig.axes[0]
    assert ax.get_xlabel() and ax.get_ylabel()
    assert ax.get_lines() or ax.images
    case = name if name in ("blows", "cycle") else "fig9"
    assert fig.get_suptitle() == f"{PLOTS[name]} — {case}"


def test_the_force_plot_is_the_contact_medium_and_external_force_in_kN(results):
    ax = figure(results["full"], "force").axes[0]
    with h5py.File(results["full"]) as f:
        ms = f["time"][()] * 1e3  # a 4-ms run is drawn in ms
        for label, path in (
            ("contact force", "contact/force"),
            ("medium force", "medium/force"),
            ("external force on the striker", "external/force"),
        ):
            np.testing.assert_array_equal(_line(ax, label).get_xdata(), ms)
            np.testing.assert_array_equal(_line(ax, label).get_ydata(), f[path][()] / 1e3)
        contacts = json.loads(f["summary"][()])["contacts"]
    [shading] = [c for c in ax.collections if c.get_label() == "in contact"]
    assert len(shading.get_paths()) == len(contacts) > 1
    assert ax.get_xlabel() == "time t (ms)" and "kN" in ax.get_ylabel()


def test_the_envelope_is_each_stretchs_greatest_stresses_along_the_tool_in_mpa(results):
    ax = figure(results["full"], "envelope").axes[0]
    with h5py.File(results["full"]) as f:
        summary = json.loads(f["summary"][()])
    envelope = summary["stress_envelope"]
    for label, key in (("greatest compression", "compression"), ("greatest tension", "tension")):
        line = _line(ax, label)
        assert list(line.get_xdata()) == [x for k in range(len(envelope[key])) for x in envelope["x"][k : k + 2]]
        assert list(line.get_ydata()[::2]) == [v / 1e6 for v in envelope[key]]
    # the largest of the stretches' is the summary's largest (Fig. 9 on the paper's scheme: its
    # extremes are its layers', as the envelope's are)
    assert max(envelope["tension"]) == summary["max_tensile_stress"]["value"]
    assert max(envelope["compression"]) == summary["max_compressive_stress"]["value"]


def test_the_displacements_are_the_striker_and_both_tool_ends_in_mm(results):
    ax = figure(results["full"], "displacements").axes[0]
    with h5py.File(results["full"]) as f:
        for label, path in (
            ("striker", "striker/displacement"),
            ("struck end of the tool", "tool/struck_end_displacement"),
            ("working end of the tool", "tool/working_end_displacement"),
        ):
            np.testing.assert_array_equal(_line(ax, label).get_ydata(), f[path][()] * 1e3)


def test_the_probe_plot_has_a_curve_a_probe_in_MPa_with_its_x(results):
    ax = figure(results["full"], "probes").axes[0]
    with h5py.File(results["full"]) as f:
        stress = f["probes/stress"][()]
        assert list(f["probes/x"][()]) == [0.01, 0.12, 0.235, 0.485]
    for k, label in enumerate(["x = 0.01 m", "x = 0.12 m", "x = 0.235 m", "x = 0.485 m"]):
        np.testing.assert_array_equal(_line(ax, label).get_ydata(), stress[:, k] / 1e6)


def test_stress_along_the_tool_at_given_times_is_the_nearest_stored_frames(results):
    ax = figure(results["full"], "stress_along", times=[1e-4, 2.02e-4]).axes[0]
    with h5py.File(results["full"]) as f:
        frame_times, stress, x = f["fields/time"][()], f["fields/stress"][()], f["fields/x"][()]
    lines = [line for line in ax.get_lines() if line.get_label().startswith("t = ")]
    assert [line.get_label() for line in lines] == ["t = 100 µs", "t = 200 µs"]  # frames every 6.25 µs
    for line, t in zip(lines, (1e-4, 2e-4)):
        frame = int(np.argmin(abs(frame_times - t)))
        np.testing.assert_array_equal(line.get_xdata(), x)
        np.testing.assert_array_equal(line.get_ydata(), stress[frame] / 1e6)


def test_stress_along_the_tool_by_default_spans_the_first_contact_after_its_start(results):
    ax = figure(results["full"], "stress_along").axes[0]
    with h5py.File(results["full"]) as f:
        first = json.loads(f["summary"][()])["contacts"][0]
    times = [
        float(line.get_label().split()[2]) * 1e-6 for line in ax.get_lines() if line.get_label().startswith("t = ")
    ]
    assert len(times) == plots.DEFAULT_TIMES and times == sorted(times)
    assert first["start"] < times[0] and times[-1] == pytest.approx(first["end"], abs=7e-6)


def test_stress_along_the_tool_from_sparse_fields_takes_the_first_frames_after_the_start(results):
    ax = figure(results["sparse"], "stress_along").axes[0]
    labels = [line.get_label() for line in ax.get_lines() if line.get_label().startswith("t = ")]
    assert labels == ["t = 125 µs", "t = 250 µs", "t = 375 µs", "t = 500 µs", "t = 625 µs"]


def test_a_time_outside_the_run_is_refused_naming_the_run(results):
    with pytest.raises(ValueError, match=r"time 0.5 s is outside the run's fields \(0 … 0.004 s\)"):
        figure(results["full"], "stress_along", times=[0.5])


def test_the_space_time_map_is_read_with_strides_and_centred_on_zero(results, monkeypatch):
    monkeypatch.setattr(plots, "MAX_MAP_SIDE", 30)
    fig = figure(results["full"], "spacetime")
    [image] = fig.axes[0].images
    with h5py.File(results["full"]) as f:
        stored = f["fields/stress"]
        rows, cols = math.ceil(stored.shape[0] / 30), math.ceil(stored.shape[1] / 30)
        expected = stored[::rows, ::cols].T / 1e6
    assert max(expected.shape) <= 30
    np.testing.assert_array_equal(image.get_array(), expected)
    low, high = image.get_clim()
    assert low == -high == -np.abs(expected).max()
    assert "MPa" in fig.axes[1].get_ylabel()  # the colorbar


def test_long_histories_are_read_with_a_stride(results, monkeypatch):
    monkeypatch.setattr(plots, "MAX_CURVE_POINTS", 1000)
    ax = figure(results["full"], "force").axes[0]
    with h5py.File(results["full"]) as f:
        expected = _strided(f["contact/force"], 1000) / 1e3
        end = f["time"][-1] * 1e3
    assert len(expected) <= 1001
    np.testing.assert_array_equal(_line(ax, "contact force").get_ydata(), expected)
    assert ax.get_xlim() == (0, end)


def test_the_energy_budget_stacks_every_term_up_to_the_input(results):
    ax = figure(results["full"], "energy").axes[0]
    with h5py.File(results["full"]) as f:
        case = json.loads(f.attrs["case"])
        supplied = 0.5 * case["striker"]["mass"] * case["striker"]["velocity"] ** 2 + _strided(
            f["energy/external_work"], plots.MAX_FILL_POINTS
        )
        end = f["time"][-1] * 1e3
    np.testing.assert_allclose(_line(ax, "input: initial + external work").get_ydata(), supplied)
    stacked = [c for c in ax.collections if c.get_label()]
    assert [c.get_label() for c in stacked] == [
        "striker kinetic",
        "tool kinetic",
        "tool strain",
        "contact potential",
        "medium potential",
        "dissipated in the contact",
        "dissipated in the medium",
        "lost by the scheme (numerical)",
    ]
    top = stacked[-1].get_paths()[0].vertices[:, 1].max()
    assert top == pytest.approx(supplied.max(), rel=1e-9)
    assert ax.get_xlim() == (0, end)


def test_the_energy_budget_of_an_elastic_striker_on_soil_has_their_terms(results):
    """The input is the piston's ½·ρ·S·L_s·W1²; the striker's strain and the soil's plastic work
    are stacked with the others, so what is left for the scheme to have lost is its own small
    loss, not the energy the soil kept."""
    ax = figure(results["soil"], "energy").axes[0]
    with h5py.File(results["soil"]) as f:
        striker = json.loads(f.attrs["case"])["striker"]
    piston = 0.5 * striker["density"] * striker["area"] * striker["length"] * striker["velocity"] ** 2
    np.testing.assert_allclose(_line(ax, "input: initial + external work").get_ydata(), piston, rtol=1e-12)
    labels = [c.get_label() for c in ax.collections if c.get_label()]
    assert {"striker strain", "medium plastic (permanent penetration)"} <= set(labels)
    with h5py.File(results["soil"]) as f:
        assert f["energy/medium_plastic"][-1] > 0.5 * piston  # the soil keeps most of it
        numerical = json.loads(f["summary"][()])["energy"]["numerical"]
    [said] = [t.get_text() for t in ax.texts if t.get_text().startswith("the scheme")]
    assert said == f"the scheme lost {100 * numerical / piston:.2g}% of the input"
    assert abs(numerical) < 5e-3 * piston


def test_the_energy_budget_of_several_blows_takes_each_launch_as_it_comes(results):
    """Three blows: the input steps up by a striker's energy at each relaunch, what each striker
    took away is its own band, and what is left for the scheme is the summary's numerical."""
    ax = figure(results["blows"], "energy").axes[0]
    with h5py.File(results["blows"]) as f:
        summary = json.loads(f["summary"][()])
    energy = summary["energy"]
    launch = energy["initial"] / 3
    supplied = _line(ax, "input: initial + external work").get_ydata()
    assert supplied[0] == pytest.approx(launch, rel=1e-12)
    assert supplied[-1] == pytest.approx(energy["initial"], rel=1e-12)
    assert sorted(set(np.round(supplied / launch, 9))) == [1.0, 2.0, 3.0]
    assert np.all(np.diff(supplied) >= 0)
    labels = [c.get_label() for c in ax.collections if c.get_label()]
    assert "withdrawn with the striker between blows" in labels
    [said] = [t.get_text() for t in ax.texts if t.get_text().startswith("the scheme")]
    assert said == f"the scheme lost {100 * energy['numerical'] / energy['initial']:.2g}% of the input"


def _shoelace(x: np.ndarray, y: np.ndarray) -> float:
    """The area the polygon through (x, y), closed back to its start, encloses."""
    return 0.5 * abs(float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))


@pytest.mark.parametrize("name", ["soil", "damped soil"])
def test_the_force_penetration_loop_encloses_the_energy_to_the_medium(results, name):
    """The soil ends unloaded, so the loop ∮F du is the net work on it; kN against mm is J."""
    ax = figure(results[name], "force_penetration").axes[0]
    loop = _line(ax, "medium force")
    with h5py.File(results[name]) as f:
        np.testing.assert_array_equal(loop.get_xdata(), f["medium/penetration"][()] * 1e3)
        np.testing.assert_array_equal(loop.get_ydata(), f["medium/force"][()] / 1e3)
        summary = json.loads(f["summary"][()])
    assert _shoelace(loop.get_xdata(), loop.get_ydata()) == pytest.approx(summary["energy"]["to_medium"], rel=1e-2)
    permanent = summary["medium_penetration"]["permanent"] * 1e3
    [marker] = [line for line in ax.get_lines() if line.get_label().startswith("permanent penetration")]
    assert list(marker.get_xdata()) == [permanent] and list(marker.get_ydata()) == [0.0]
    assert 0.0 < permanent < loop.get_xdata().max()
    assert "mm" in ax.get_xlabel() and "kN" in ax.get_ylabel()


def test_the_force_penetration_of_a_linear_medium_is_against_the_working_end(results):
    """A linear medium records no penetration of its own: it is the working end's u_N, and no
    penetration is permanent."""
    ax = figure(results["full"], "force_penetration").axes[0]
    with h5py.File(results["full"]) as f:
        assert "medium/penetration" not in f
        np.testing.assert_array_equal(
            _line(ax, "medium force").get_xdata(), f["tool/working_end_displacement"][()] * 1e3
        )
    assert _line(ax, "permanent penetration 0 mm").get_xdata() == [0.0]


def test_the_blows_plot_has_a_point_a_blow_equal_to_the_summarys_table(results):
    fig = figure(results["blows"], "blows")
    with h5py.File(results["blows"]) as f:
        table = json.loads(f["summary"][()])["blows"]
    assert len(table) == 3
    expected = {  # panel -> (column, unit, scale from SI)
        "peak contact force": ("peak_contact_force", "kN", 1e-3),
        "max compressive stress": ("max_compressive_stress", "MPa", 1e-6),
        "energy to the medium": ("to_medium", "J", 1.0),
        "transfer efficiency": ("transfer_efficiency", "%", 100.0),
        "permanent penetration": ("permanent_penetration", "mm", 1e3),
        "set (added by the blow)": ("set", "mm", 1e3),
    }
    assert [ax.get_title() for ax in fig.axes] == list(expected)
    for ax in fig.axes:
        column, unit, scale = expected[ax.get_title()]
        [line] = ax.get_lines()
        assert list(line.get_xdata()) == [1, 2, 3]
        assert list(line.get_ydata()) == [row[column] * scale for row in table]
        assert ax.get_ylabel() == unit and ax.get_xlabel() == "blow"


def test_a_result_without_fields_or_probes_says_what_to_change(results, tmp_path):
    with h5py.File(results["bare"]) as f:
        assert problem(f, "spacetime") == ("this result has no stress fields: run the case with outputs.fields = true")
        assert problem(f, "stress_along") == problem(f, "spacetime")
        assert "run the case with outputs.probes" in problem(f, "probes")
        assert problem(f, "force") is None and problem(f, "energy") is None
    with h5py.File(results["lumped"]) as f:
        assert 'numerics.model = "rod"' in problem(f, "spacetime")
        assert 'numerics.model = "rod"' in problem(f, "envelope")
    with pytest.raises(NotAvailable, match="outputs.fields = true"):
        figure(results["bare"], "spacetime")
    written, skipped = write_plots(results["bare"], tmp_path, formats=["png"])
    assert sorted(skipped) == ["blows", "cycle", "probes", "spacetime", "stress_along"]
    assert sorted(p.name for p in written) == [
        "displacements.png",
        "energy.png",
        "envelope.png",
        "force.png",
        "force_penetration.png",
    ]


def test_a_plot_that_does_not_apply_says_why(results):
    with h5py.File(results["bare"]) as f:
        assert problem(f, "blows") == (
            'this case has no blows table: run it blow after blow with blows.count, e.g. "blows": {"count": 5}'
        )
    with h5py.File(results["free"]) as f:
        assert problem(f, "force_penetration").startswith("this case has no medium at the working end")
        assert problem(f, "energy") is None and problem(f, "force") is None
    with h5py.File(results["blows"]) as f:
        assert problem(f, "blows") is None and problem(f, "force_penetration") is None
    with pytest.raises(NotAvailable, match="no medium"):
        figure(results["free"], "force_penetration")


def test_an_unknown_plot_or_a_file_that_is_not_a_result_is_refused(results, tmp_path):
    with pytest.raises(UnknownPlot, match="the plots are: force, displacements, probes"):
        figure(results["full"], "forces")
    with h5py.File(tmp_path / "other.h5", "w") as f:
        f["time"] = np.zeros(3)
    (tmp_path / "text.h5").write_text("not HDF5")
    for name in ("other.h5", "text.h5"):
        with pytest.raises(NotAResult, match="is not a percussim result"):
            figure(tmp_path / name, "force")


def test_cli_writes_the_plots_next_to_the_result_and_says_what_it_skipped(results, tmp_path, capsys):
    bare = shutil.copy(results["bare"], tmp_path / "run.h5")
    assert main(["plot", str(bare)]) == 0
    out, err = capsys.readouterr()
    folder = tmp_path / "run-plots"
    names = {
        f"{n}.{fmt}"
        for n in ("force", "displacements", "energy", "force_penetration", "envelope")
        for fmt in ("png", "svg")
    }
    assert {p.name for p in folder.iterdir()} == names
    assert set(out.split()) == {str(folder / n) for n in names}
    assert ("skipped spacetime: this result has no stress fields: run the case with outputs.fields = true") in err
    assert "skipped probes" in err


def test_cli_plots_chosen_plots_formats_and_times(results, tmp_path, capsys):
    assert (
        main(
            [
                "plot",
                results["full"],
                "--out",
                str(tmp_path / "p"),
                "--only",
                "stress_along",
                "probes",
                "--format",
                "png",
                "--times",
                "1e-4,2e-4",
            ]
        )
        == 0
    )
    assert sorted(p.name for p in (tmp_path / "p").iterdir()) == ["probes.png", "stress_along.png"]
    assert capsys.readouterr().err == ""


@pytest.mark.parametrize(
    "make, message",
    [
        (lambda p: None, "no such result file"),
        (lambda p: p.write_text("not HDF5"), "is not a percussim result"),
    ],
)
def test_cli_refuses_a_missing_file_or_one_that_is_not_a_result_with_status_2(tmp_path, capsys, make, message):
    make(tmp_path / "r.h5")
    assert main(["plot", str(tmp_path / "r.h5")]) == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "r-plots").exists()


def test_cli_refuses_an_unknown_plot_with_status_2(results, tmp_path, capsys):
    assert main(["plot", results["full"], "--out", str(tmp_path / "p"), "--only", "forse"]) == 2
    assert "unknown plot 'forse'" in capsys.readouterr().err
    assert not (tmp_path / "p").exists()


def test_http_lists_the_plots_with_their_links_and_reasons(results, api_store):
    client, jobs = api_store
    job_id = succeeded_job(client, jobs, results["bare"])
    assert client.get(f"/v1/jobs/{job_id}").json()["links"]["plots"] == f"/v1/jobs/{job_id}/plots"
    answer = client.get(f"/v1/jobs/{job_id}/plots")
    assert answer.status_code == 200
    listed = {p["name"]: p for p in answer.json()["plots"]}
    assert list(listed) == list(PLOTS)
    assert listed["force"] == {
        "name": "force",
        "title": "Contact force",
        "available": True,
        "reason": None,
        "links": {"png": f"/v1/jobs/{job_id}/plots/force.png", "svg": f"/v1/jobs/{job_id}/plots/force.svg"},
    }
    assert listed["spacetime"]["available"] is False
    assert "outputs.fields = true" in listed["spacetime"]["reason"]


def test_http_serves_a_plot_as_png_and_svg_and_keeps_it(results, api_store, monkeypatch):
    client, jobs = api_store
    job_id = succeeded_job(client, jobs, results["full"])
    png = client.get(f"/v1/jobs/{job_id}/plots/force.png")
    assert png.status_code == 200 and png.headers["content-type"] == "image/png"
    assert png.content.startswith(PNG_SIGNATURE)
    svg = client.get(f"/v1/jobs/{job_id}/plots/spacetime.svg")
    assert svg.status_code == 200 and svg.headers["content-type"].startswith("image/svg+xml")
    ET.fromstring(svg.content)
    assert jobs.plot_path(job_id, "force", "png").read_bytes() == png.content

    def no_drawing(*args):
        raise AssertionError("a kept plot was drawn again")

    monkeypatch.setattr("percussim.service.jobs.render", no_drawing)
    again = client.get(f"/v1/jobs/{job_id}/plots/force.png")
    assert again.status_code == 200 and again.content == png.content


def test_http_draws_again_a_plot_older_than_its_result(results, api_store):
    client, jobs = api_store
    job_id = succeeded_job(client, jobs, results["full"])
    kept = jobs.plot_path(job_id, "force", "png")
    kept.parent.mkdir()
    kept.write_bytes(b"stale")
    result = jobs.result_path(job_id)
    os.utime(kept, (result.stat().st_mtime - 10,) * 2)
    answer = client.get(f"/v1/jobs/{job_id}/plots/force.png")
    assert answer.content.startswith(PNG_SIGNATURE) and kept.read_bytes() == answer.content


def test_http_answers_404_for_an_unknown_plot_and_for_one_this_result_cannot_make(results, api_store):
    client, jobs = api_store
    job_id = succeeded_job(client, jobs, results["bare"])
    unknown = client.get(f"/v1/jobs/{job_id}/plots/..%2Fresult.png")
    assert unknown.status_code == 404
    unknown = client.get(f"/v1/jobs/{job_id}/plots/forces.png")
    assert unknown.status_code == 404
    assert unknown.json()["detail"] == (
        "no plot named 'forces'; the plots are: force, displacements, "
        "probes, stress_along, spacetime, energy, force_penetration, envelope, blows, cycle"
    )
    missing = client.get(f"/v1/jobs/{job_id}/plots/probes.svg")
    assert missing.status_code == 404
    assert (
        f"job {job_id} has no probes plot: this result has no probes: run the case with outputs.probes"
        in missing.json()["detail"]
    )
    assert not jobs.plot_path(job_id, "probes", "svg").exists()
    assert client.get(f"/v1/jobs/{job_id}/plots/force.pdf").status_code == 422


def test_http_draws_stress_along_the_tool_at_chosen_times_and_names_bad_ones(results, api_store):
    client, jobs = api_store
    job_id = succeeded_job(client, jobs, results["full"])
    url = f"/v1/jobs/{job_id}/plots/stress_along"
    chosen = client.get(f"{url}.png", params={"times": "5e-5,1e-4,1.5e-4"})
    assert chosen.status_code == 200 and chosen.headers["content-type"] == "image/png"
    assert chosen.content == render(results["full"], "stress_along", "png", [5e-5, 1e-4, 1.5e-4])
    assert not jobs.plot_path(job_id, "stress_along", "png").exists()  # chosen times are not kept
    assert chosen.content != client.get(f"{url}.png").content  # the default times are others
    assert jobs.plot_path(job_id, "stress_along", "png").exists()  # the default plot is
    assert client.get(f"{url}.svg", params={"times": "1e-4"}).headers["content-type"] == "image/svg+xml"
    for times, message in (
        ("abc", "expected times in s"),
        ("1e-4,nan", "must be finite"),
        ("1", "outside the run's fields"),
        (",".join(["1e-4"] * 13), "more than the 12"),
    ):
        bad = client.get(f"{url}.png", params={"times": times})
        assert bad.status_code == 422 and bad.json()["detail"][0]["field"] == "query.times", bad.text
        assert message in bad.json()["detail"][0]["message"], (times, bad.text)
    other = client.get(f"/v1/jobs/{job_id}/plots/force.png", params={"times": "1e-4"})
    assert other.status_code == 422 and other.json()["detail"] == [
        {"field": "query.times", "message": "only the stress_along plot takes times"}
    ]


def test_http_answers_409_until_the_job_has_succeeded_and_404_for_another_key(results, tmp_path, clean_environment):
    client = TestClient(create_app(Settings(results_dir=tmp_path, api_keys="alice-key,bob-key")))
    alice, bob = {"X-API-Key": "alice-key"}, {"X-API-Key": "bob-key"}
    job_id = client.post("/v1/jobs", json=BASE_CASE, headers=alice).json()["id"]
    for path in ("plots", "plots/force.png"):
        answer = client.get(f"/v1/jobs/{job_id}/{path}", headers=alice)
        assert answer.status_code == 409 and "queued" in answer.json()["detail"]
    jobs = JobStore(Settings(results_dir=tmp_path))
    shutil.copy(results["full"], jobs.result_path(job_id))
    jobs.start(job_id, "w1@x")
    jobs.finish(job_id, SUCCEEDED)
    assert client.get(f"/v1/jobs/{job_id}/plots/force.png", headers=alice).status_code == 200
    for path in ("plots", "plots/force.png"):
        assert client.get(f"/v1/jobs/{job_id}/{path}", headers=bob).status_code == 404


def test_the_plot_example_runs_a_preset_and_draws_every_plot(tmp_path):
    """examples/plot_preset.py, which draws the README's pictures."""
    done = subprocess.run(
        [
            sys.executable,
            "examples/plot_preset.py",
            "--preset",
            "fig9",
            "--result",
            str(tmp_path / "fig9.h5"),
            "--out",
            str(tmp_path / "plots"),
        ],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 0, done.stderr
    drawn = sorted(p.stem for p in (tmp_path / "plots").glob("*.png"))
    # every plot but the blows table and the work cycle, which the one blow of a preset has not
    assert drawn == sorted(set(PLOTS) - {"blows", "cycle"})
    assert [line for line in done.stdout.splitlines() if "skipped" in line] == [
        f"skipped {name}: " + plots.problems(tmp_path / "fig9.h5")[name] for name in ("blows", "cycle")
    ]
    assert all(p.read_bytes().startswith(b"\x89PNG\r\n\x1a\n") for p in (tmp_path / "plots").glob("*.png"))
