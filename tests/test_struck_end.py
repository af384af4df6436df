"""The struck end driven by a given history (`struck_end`): the work it does and the wave it
sends against closed forms, a Smith toe's set under a rectangular force, force and velocity
alike, and what is refused, naming the field."""

from __future__ import annotations

import numpy as np
import pytest

from percussim.solver.case import CaseError, parse_case
from percussim.solver.simulate import simulate
from percussim.testing import closed_forms as CF

FINE = {"scheme": "explicit", "cells": 1000}


def test_a_force_on_a_free_rod_sends_its_wave_and_does_its_work():
    case = CF.rectangular_force_case(FINE)
    del case["medium"]
    case["numerics"]["duration"] = 0.9 * CF.TOOL / CF.SPEED  # before the free end's reflection returns
    result = simulate(parse_case(case))
    energy, h = result.summary["energy"], result.history
    # the end moves at F_i/Z while driven: its work F_i²·T/Z, all in the tool
    assert energy["external_work"] == pytest.approx(CF.INCIDENT**2 * CF.T / CF.Z, rel=1e-9)
    assert energy["initial"] == 0.0
    assert abs(energy["numerical"]) < 5e-3 * energy["external_work"]
    assert energy["transferred"] == pytest.approx(energy["external_work"], rel=1e-2)
    during = (h["time"] > 0.1 * CF.T) & (h["time"] < 0.9 * CF.T)
    speed = np.gradient(h["tool/struck_end_displacement"], h["time"])[during]
    assert np.allclose(speed, CF.INCIDENT / CF.Z, rtol=1e-6)
    assert result.summary["peak_contact_force"]["value"] == pytest.approx(CF.INCIDENT, rel=1e-12)
    assert "striker/velocity" not in h  # no striker


@pytest.mark.parametrize("share", [1.0, 1.2, 1.6, 1.9])
def test_a_rectangular_force_sets_smith_soil_as_the_closed_form(share):
    resistance = share * CF.INCIDENT
    quake = CF.SOIL_RESISTANCE / CF.SOIL_STIFFNESS
    summary = simulate(parse_case(CF.rectangular_force_case(FINE, resistance, quake))).summary
    _, expected = CF.smith_set(resistance, resistance / quake)
    assert summary["set"] == pytest.approx(expected, rel=5e-3)
    assert summary["blow_count"] == pytest.approx(1.0 / expected, rel=5e-3)


def test_a_toe_at_twice_the_force_refuses():
    summary = simulate(parse_case(CF.rectangular_force_case(FINE, 2.05 * CF.INCIDENT))).summary
    assert summary["set"] <= 1e-12
    assert summary["blow_count"] is None
    assert any(w.startswith("refusal") for w in summary["warnings"])


def test_driven_by_its_velocity_the_end_sets_the_soil_as_by_its_force():
    by_force = simulate(parse_case(CF.rectangular_force_case(FINE))).summary
    by_velocity = simulate(parse_case(CF.rectangular_force_case(FINE, drive="velocity"))).summary
    assert by_velocity["set"] == pytest.approx(by_force["set"], rel=1e-9)
    assert by_velocity["peak_contact_force"]["value"] == pytest.approx(CF.INCIDENT, rel=1e-3)


def test_at_the_default_accuracy_the_set_is_within_its_estimate():
    summary = simulate(parse_case(CF.rectangular_force_case())).summary
    _, expected = CF.smith_set()
    error = abs(summary["set"] - expected) / expected
    assert error < 0.01
    assert summary["error_estimate"]["set"] < 0.01


@pytest.mark.parametrize(
    "change, field",
    [
        (lambda c: c.update(striker={"mass": 1.0, "velocity": 1.0}), "struck_end"),
        (lambda c: c.update(contact={"stiffness": 1e9, "exponent": 0.0}), "contact"),
        (lambda c: c["struck_end"]["force"].update(time=[0.0, 0.0]), "struck_end.force.time"),
        (lambda c: c["struck_end"]["force"].update(values=[1.0, 2.0, 3.0]), "struck_end.force.values"),
        (lambda c: c["struck_end"].update(velocity={"time": [0.0, 1.0], "values": [1.0, 1.0]}), "struck_end.force"),
        (lambda c: c["struck_end"].pop("force"), "struck_end.force"),
        (lambda c: c.pop("struck_end"), "striker"),
    ],
)
def test_a_bad_struck_end_is_refused_naming_the_field(change, field):
    case = CF.rectangular_force_case()
    change(case)
    with pytest.raises(CaseError) as refused:
        parse_case(case)
    assert [e.field for e in refused.value.errors] == [field]


def test_a_driven_end_is_refused_by_the_schemes_that_do_not_take_it():
    case = CF.rectangular_force_case({"scheme": "paper", "cells": 100})
    del case["medium"]
    with pytest.raises(CaseError) as refused:
        simulate(parse_case(case))
    assert [e.field for e in refused.value.errors] == ["struck_end"]


def test_a_bearing_graph_reads_smiths_set_and_the_refusal_off_its_rows():
    """The toe takes every capacity (no shaft); one blow each, from rest: each row's set is the
    closed form's, and from R_u = 2F_i on the rows are refusals."""
    from percussim.solver.pile_studies import bearing_graph

    quake = CF.SOIL_RESISTANCE / CF.SOIL_STIFFNESS
    case = CF.rectangular_force_case(FINE, quake=quake) | {"blows": {"count": 1}}
    shares = (1.0, 1.3, 1.6, 1.9, 2.0, 2.3)
    graph = bearing_graph({"case": case, "capacity": [s * CF.INCIDENT for s in shares]}, processes=1)
    assert graph["toe_share"] == 1.0
    for share, row in zip(shares, graph["rows"]):
        _, expected = CF.smith_set(share * CF.INCIDENT, share * CF.INCIDENT / quake)
        if share < 2.0:
            assert row["set"] == pytest.approx(expected, rel=5e-3), share
            assert row["blow_count"] == pytest.approx(1.0 / expected, rel=5e-3)
        else:
            assert row["set"] <= 1e-12 and row["blow_count"] is None, share


def test_a_driven_end_draws_the_plots_and_series_it_can_without_a_striker(tmp_path):
    """No striker: the displacements are the tool's ends' alone, as a plot and as the page's series."""
    from percussim.solver import plots, series
    from percussim.solver.io import write_result

    path = write_result(simulate(parse_case(CF.rectangular_force_case())), tmp_path / "driven.h5")
    drawn = [name for name, why in plots.problems(path).items() if why is None]
    assert {"force", "displacements", "energy", "force_penetration"} <= set(drawn)
    for name in drawn:
        assert plots.render(path, name, "png").startswith(b"\x89PNG")
    labels = [curve["label"] for curve in series.series(path, "displacements")["series"]]
    assert labels == ["struck end of the tool", "working end of the tool"]
