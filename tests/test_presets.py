"""The presets: every file is a valid case and runs; the paper's cases match the references, the
rock drill and the pile the closed forms of their first blow."""

from __future__ import annotations

import json
import math
from functools import cache
from pathlib import Path

import numpy as np
import pytest

from percussim.solver.case import CaseError, load_case, parse_case
from percussim.solver.controller import simulate_rod
from percussim.solver.grid import wave_speed
from percussim.solver.presets import PRESETS_ENV, load_preset, preset_json, preset_names
from percussim.solver.simulate import simulate
from percussim.testing.reference import CushionedImpact, LundbergRock, impedance

EXAMPLES = Path(__file__).resolve().parents[1] / "solver" / "presets"  # as shipped
PAPER_FIGURES = [f"fig{k}" for k in range(3, 10)]
FILES = sorted(EXAMPLES.glob("*.json"))


@pytest.fixture(autouse=True)
def default_folder(monkeypatch):
    """Read the package's own presets, whatever the environment running the tests says."""
    monkeypatch.delenv(PRESETS_ENV, raising=False)


@cache
def summary(name: str) -> dict:
    """Run a preset once, as `simulate` does (its numerics, or the default accuracy), for all the
    tests that look at it."""
    return simulate(load_preset(name)).summary


@pytest.mark.parametrize("path", FILES, ids=[p.stem for p in FILES])
def test_every_preset_file_is_a_valid_case(path):
    case = load_case(path)
    assert case.name == path.stem
    assert case.description, "a preset says which figure it is and what it chose"


def test_preset_names_lists_every_file_and_every_figure():
    names = preset_names()
    assert names == sorted(p.stem for p in FILES)
    assert set(PAPER_FIGURES) <= set(names)


def test_preset_json_is_the_file_and_load_preset_the_case():
    assert preset_json("fig3") == json.loads((EXAMPLES / "fig3.json").read_text())
    assert load_preset("fig3") == load_case(EXAMPLES / "fig3.json")


@pytest.mark.parametrize("name", ["nope", "../x", "fig3.json", "FIG3", "fig3/", "", "fig3\n"])
def test_unknown_or_path_like_names_are_refused(name):
    for lookup in (load_preset, preset_json):
        with pytest.raises(KeyError) as refused:
            lookup(name)
        message = str(refused.value)
        assert all(known in message for known in PAPER_FIGURES), "the error names the known presets"


def test_the_folder_comes_from_the_environment_and_names_never_leave_it(tmp_path, monkeypatch):
    folder = tmp_path / "presets"
    folder.mkdir()
    case = preset_json("fig3") | {"name": "mine"}
    (folder / "mine.json").write_text(json.dumps(case))
    (folder / "Not_A_Name.json").write_text(json.dumps(case))
    (tmp_path / "x.json").write_text(json.dumps(case))  # reachable as "../x" if a path were built
    monkeypatch.setenv(PRESETS_ENV, str(folder))

    assert preset_names() == ["mine"]
    assert load_preset("mine").name == "mine"
    with pytest.raises(KeyError):
        preset_json("../x")


def test_an_invalid_preset_file_is_reported_as_an_invalid_case(tmp_path, monkeypatch):
    (tmp_path / "broken.json").write_text(json.dumps(preset_json("fig3") | {"striker": {}}))
    monkeypatch.setenv(PRESETS_ENV, str(tmp_path))
    with pytest.raises(CaseError, match="striker.velocity"):
        load_preset("broken")


@pytest.mark.parametrize("name", [p.stem for p in FILES])
def test_every_preset_runs_to_finite_results(name):
    s = summary(name)
    values = [
        s["co_impact_time"],
        s["peak_contact_force"]["value"],
        s["max_compressive_stress"]["value"],
        s["max_tensile_stress"]["value"],
        *s["energy"].values(),
    ]
    assert all(v is not None and math.isfinite(v) for v in values), values
    assert s["co_impact_time"] > 0 and s["peak_contact_force"]["value"] > 0


def test_fig3_matches_the_reference_co_impact_time_and_peak_force():
    # model.md: the paper's scheme on the Fig. 3 parameters gives about 335 µs and 860 kN.
    s = summary("fig3")
    assert s["co_impact_time"] == pytest.approx(335e-6, rel=0.03)
    assert s["peak_contact_force"]["value"] == pytest.approx(860e3, rel=0.03)


def test_fig4_is_fig3_on_a_finer_grid():
    fig3, fig4 = preset_json("fig3"), preset_json("fig4")
    physics = ("striker", "tool", "contact", "medium", "force")
    assert all(fig3.get(k) == fig4.get(k) for k in physics)
    assert fig4["numerics"]["cells"] > fig3["numerics"]["cells"]
    assert fig4["numerics"]["time_step"] < fig3["numerics"]["time_step"]


def test_fig5_uses_the_papers_numerics_and_shows_repeated_collisions():
    numerics = load_preset("fig5").numerics
    assert (numerics.cells, numerics.time_step, numerics.gamma) == (5, 2e-5, 0.8)
    assert len(summary("fig5")["contacts"]) > 1


def test_fig6_is_fig5_with_the_periodic_force():
    fig5, fig6 = preset_json("fig5"), preset_json("fig6")
    force = fig6.pop("force")
    assert force == {"kind": "abs_sine", "amplitude": 9e4, "omega": 800.0}
    assert {k: v for k, v in fig6.items() if k not in ("name", "description")} == {
        k: v for k, v in fig5.items() if k not in ("name", "description")
    }


def test_fig8_samples_the_papers_field_times_exactly():
    result = simulate_rod(load_preset("fig8"))
    assert result.fields is not None
    assert np.isin([31.25e-6, 125e-6, 250e-6], result.fields.time).all()


def test_fig9_stress_is_the_papers_order_and_peaks_in_the_cone():
    case = load_preset("fig9")
    assert case.outputs.probes == [0.01, 0.12, 0.235, 0.485]
    assert case.striker.mass == 10.0
    peak = summary("fig9")["max_compressive_stress"]
    # The paper: 200–250 MPa at most, in the conical part (where the profile starts to narrow).
    assert 150e6 <= peak["value"] <= 300e6
    assert peak["x"] >= case.tool.profile.x[-2]


def test_the_rock_drill_is_lundbergs_single_pass():
    """The piston sends Z_p·Z·v/(Z_p + Z) into the rod for 2L_p/a; of matched impedances that wave
    is all its energy, and Lundberg's closed forms give the peak force at the bit, the rock's share
    of the energy and the penetration it keeps."""
    case = load_preset("rock_drill")
    piston, rod = case.striker.rod(), case.tool
    wave = 2.0 * piston.length / wave_speed(piston)
    # What the closed forms assume of the preset: matched impedances, and a run that ends once the
    # wave has passed the bit, before its reflection is back at the struck end.
    assert impedance(piston) == pytest.approx(impedance(rod), rel=1e-6)
    assert rod.length / wave_speed(rod) + wave < case.numerics.duration < 2.0 * rod.length / wave_speed(rod)
    rock_blow = LundbergRock.of_case(case)
    s = summary("rock_drill")
    assert s["peak_contact_force"]["value"] == pytest.approx(rock_blow.incident, rel=1e-2)
    peak = s["max_compressive_stress"]
    assert peak["value"] == pytest.approx(rock_blow.peak_force / rod.area, rel=1e-2)
    assert peak["x"] == pytest.approx(rod.length)  # at the bit, where the rock's force is
    assert s["energy"]["transfer_efficiency"] == pytest.approx(rock_blow.efficiency, rel=1e-2)
    assert 0.6 < rock_blow.efficiency < 0.9  # a drill that works, not a rock that stops it
    assert s["medium_penetration"]["max"] == pytest.approx(rock_blow.max_penetration, rel=1e-2)
    assert s["medium_penetration"]["permanent"] == pytest.approx(rock_blow.permanent_penetration, rel=1e-2)
    assert abs(s["energy"]["numerical"]) < 5e-3 * s["energy"]["initial"]


def test_the_piles_first_peak_is_the_ram_on_its_cushion_on_a_long_pile():
    """Before the toe's reflection is back the pile is an impedance Z to the cushion: the ram's
    first peak force is the damped oscillator's, below the rigid ram's Z·v (the preset's ram on
    its cushion with what the closed form has not left out: the helmet, gravity, and the shaft,
    whose reflections from 3 m down would be back before the peak)."""
    tree = preset_json("pile")
    del tree["anvil"], tree["gravity"], tree["shaft"]
    case = parse_case(tree)
    pile, cushion = case.tool, case.contact
    assert (cushion.exponent, cushion.damping) == (0.0, 0.0)  # the closed form's linear cushion
    ram = CushionedImpact.of_case(case)
    assert ram.peak_time < 2.0 * pile.length / wave_speed(pile)
    assert ram.peak_force < impedance(pile) * case.impact_velocity
    s = simulate(case).summary
    assert s["peak_contact_force"]["value"] == pytest.approx(ram.peak_force, rel=1e-2)
    assert s["peak_contact_force"]["time"] == pytest.approx(ram.peak_time, rel=2e-2)
    assert s["max_compressive_stress"]["value"] >= ram.peak_force / pile.area * (1 - 1e-2)


def test_the_pile_sets_as_smiths_soil_says():
    """Elastic–perfectly plastic at the toe: the work into the set is R_u a metre of it, and once
    unloaded the toe springs back by the quake."""
    soil = load_preset("pile").medium
    s = summary("pile")
    penetration, energy = s["medium_penetration"], s["energy"]
    assert penetration["permanent"] > soil.quake  # the toe went through its quake and set
    assert penetration["max"] - penetration["permanent"] == pytest.approx(soil.quake, rel=1e-3)
    assert energy["medium_plastic"] == pytest.approx(soil.ultimate_resistance * penetration["permanent"], rel=1e-3)
    assert energy["dissipated_medium"] > 0  # the toe's damping J worked
    assert abs(energy["numerical"]) < 5e-3 * energy["initial"]
