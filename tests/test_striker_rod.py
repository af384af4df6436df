"""The striker as an elastic rod (a piston) against the closed forms of one-dimensional impact.

A piston of impedance Z_s = ρ·a·S_s at velocity v strikes a tool of impedance Z through a stiff
contact. While the wave that the impact sends into the piston runs to its free back end and back
(2·L_s/a_s), the force is that of two impedances in series, `Z_s·Z·v/(Z_s + Z)`. Then:
- equal impedances: the returning wave unloads the face, the force drops to 0 and the piston is
  left at rest, having passed all its energy;
- a lower-impedance piston separates, having passed `4r/(1 + r)²` of its energy (r = Z_s/Z);
- a higher-impedance one stays on, and the force steps down by `R = (Z_s − Z)/(Z_s + Z)` every
  2·L_s/a_s.
A lumped striker of the same mass meets none of these: its force rises and decays smoothly.
"""

from __future__ import annotations

import h5py
import numpy as np
import pytest

import percussim
from percussim.solver.case import CaseError, parse_case
from percussim.testing import at_default_accuracy
from percussim.testing.closed_forms import (
    AREA,
    PISTON,
    PISTON_MASS,
    SPEED,
    STEEL,
    STEPPED_DURATION,
    T,
    V,
    Z,
    first_force,
    passed_share,
    piston_case,
    reflection,
    stepped_piston_case,
)
from percussim.testing.closed_forms import PISTON_FINE as FINE


def force_at(result, fraction: float) -> float:
    """The contact force at `fraction` of the piston's round trip."""
    return float(np.interp(fraction * T, result.history["time"], result.history["contact/force"]))


@pytest.fixture(scope="module", params=["fine", "tolerance"])
def accuracy(request) -> dict:
    return FINE if request.param == "fine" else {"tolerance": 0.01}


def test_equal_impedances_give_a_rectangular_pulse_and_leave_the_piston_at_rest(accuracy):
    result = percussim.simulate(piston_case(1.0, accuracy))
    summary = result.summary
    height = Z * V / 2.0
    for fraction in (0.05, 0.3, 0.6, 0.95):
        assert force_at(result, fraction) == pytest.approx(height, rel=2e-3)
    for fraction in (1.05, 1.3, 1.8):
        assert abs(force_at(result, fraction)) < 1e-3 * height
    assert summary["peak_contact_force"]["value"] == pytest.approx(height, rel=1e-3)
    energy = summary["energy"]
    left = energy["striker_kinetic"] + energy["striker_strain"]
    assert left < 5e-3 * energy["initial"]
    assert abs(energy["numerical"]) < 5e-3 * energy["initial"]


def test_a_lower_impedance_piston_passes_4r_over_1_plus_r_squared(accuracy):
    r = 0.5
    result = percussim.simulate(piston_case(r, accuracy))
    summary = result.summary
    assert summary["peak_contact_force"]["value"] == pytest.approx(first_force(r), rel=2e-3)
    assert force_at(result, 0.5) == pytest.approx(first_force(r), rel=2e-3)
    energy = summary["energy"]
    passed = (energy["tool_kinetic"] + energy["tool_strain"]) / energy["initial"]
    assert passed == pytest.approx(passed_share(r), rel=1e-2)
    # it leaves at the velocity its momentum says: v − impulse/m, the impulse F·T
    assert summary["striker_rebound_velocity"] == pytest.approx(
        V - first_force(r) * T / (STEEL["density"] * r * AREA * PISTON), rel=1e-2
    )
    assert summary["co_impact_time"] == pytest.approx(T, rel=1e-2)


def test_a_higher_impedance_piston_gives_the_stepped_pulse(accuracy):
    r = 2.0
    result = percussim.simulate(piston_case(r, {**accuracy, "duration": STEPPED_DURATION}))
    for step in range(3):
        assert force_at(result, step + 0.5) == pytest.approx(first_force(r) * reflection(r) ** step, rel=1e-2)
    assert abs(result.summary["energy"]["numerical"]) < 5e-3 * result.summary["energy"]["initial"]


def test_a_lumped_striker_of_the_same_mass_is_not_the_piston():
    """The comparisons above tell the models apart: the lumped striker's force is no rectangle."""
    mass = PISTON_MASS
    lumped = piston_case(1.0, FINE)
    lumped["striker"] = {"mass": mass, "velocity": V}
    result = percussim.simulate(lumped)
    assert abs(force_at(result, 0.6) - Z * V / 2.0) > 0.05 * Z * V / 2.0


def test_the_fields_along_the_piston_carry_its_wave(tmp_path):
    """Equal impedances, at a quarter of the round trip: the wave the impact sent into the piston
    has run half its length, compressing it at −Z·v/(2·S) behind its front and leaving the rest
    unstrained and still at v; the piston's fields go to the result file with their units."""
    case = piston_case(1.0, {"scheme": "explicit", "cells": 400})
    case["outputs"] = {"fields": True, "field_stride": 1}
    result = percussim.simulate(case)
    f = result.fields
    frame = int(np.argmin(np.abs(f.time - T / 4)))
    t = f.time[frame]
    front = SPEED * t
    behind, ahead = f.striker_x < 0.8 * front, f.striker_x > 1.2 * front
    assert f.striker_stress[frame, behind] == pytest.approx(-Z * V / 2 / AREA, rel=1e-2)
    assert np.abs(f.striker_stress[frame, ahead]).max() < 1e-2 * Z * V / 2 / AREA
    assert f.striker_displacement[frame, ahead] == pytest.approx(V * t, rel=1e-3)
    assert f.striker_x[-1] <= PISTON < f.striker_x[-1] + 2 * (f.striker_x[1] - f.striker_x[0])

    path = percussim.write_result(result, tmp_path / "piston.h5")
    with h5py.File(path) as h5:
        assert h5["fields/striker_stress"].attrs["units"] == "Pa"
        assert h5["fields/striker_displacement"].attrs["units"] == "m"
        assert h5["fields/striker_x"].attrs["units"] == "m"
    back = percussim.read_result(path).fields
    np.testing.assert_array_equal(back.striker_stress, f.striker_stress)


def test_a_profiled_piston_on_a_whole_and_a_fractional_number_of_cells_agree():
    """A stepped piston (the rod model's profile) whose length is not a whole number of cells
    converges to the run whose is: the part beyond the last node is a delay at the free end."""
    whole = percussim.simulate(stepped_piston_case(2000)).summary
    fractional = percussim.simulate(stepped_piston_case(2003)).summary
    for quantity in ("peak_contact_force", "max_compressive_stress"):
        assert fractional[quantity]["value"] == pytest.approx(whole[quantity]["value"], rel=2e-3)
    assert fractional["energy"]["tool_kinetic"] + fractional["energy"]["tool_strain"] == pytest.approx(
        whole["energy"]["tool_kinetic"] + whole["energy"]["tool_strain"], rel=2e-3
    )
    assert abs(fractional["energy"]["numerical"]) < 5e-3 * fractional["energy"]["initial"]


def test_the_striker_is_lumped_or_a_rod_not_both():
    case = piston_case(1.0)
    case["striker"]["mass"] = 1.0
    with pytest.raises(CaseError, match=r"striker\.mass.*striker\.length"):
        percussim.simulate(case)


def test_a_grid_too_coarse_for_the_piston_is_refused_naming_the_cells():
    with pytest.raises(CaseError, match="numerics.cells") as refused:
        percussim.simulate(piston_case(1.0, {"scheme": "explicit", "cells": 6}))
    assert "at least 10 cells" in str(refused.value)


@pytest.mark.parametrize("numerics", [{"cells": 200}, {"scheme": "sigma", "cells": 200}, {"model": "lumped"}])
def test_other_schemes_refuse_an_elastic_striker_naming_the_field(numerics):
    with pytest.raises(CaseError, match="striker.length: .*explicit scheme at Courant number 1"):
        percussim.simulate(piston_case(1.0, numerics))


def test_an_external_force_on_an_elastic_striker_is_refused():
    case = piston_case(1.0)
    case["force"] = {"kind": "pulse", "amplitude": 1e3, "duration": 1e-4}
    with pytest.raises(CaseError, match="force: acts on a lumped striker"):
        percussim.simulate(case)


def test_a_piston_commensurate_with_its_rod_is_a_whole_number_of_cells_on_every_grid_of_its_ladder():
    """The rock drill's 0.30-m piston on its 3.66-m rod is 5/61 of it: on multiples of 61 cells it
    is a whole number of cells, its back end on a node, with no delay for a rest beyond it. The
    default accuracy's grids had been doubled from 49 cells, and agreed with each other on an
    energy to the rock 0.40% under what whole-number grids converge to; at the default accuracy
    it was 4.5e-4 under Lundberg's closed form (rigid contact: 90.825 J), which the preset's
    1e12-N/m contact lowers by 1.7e-4."""
    from percussim.solver.grid import striker_grid
    from percussim.testing.reference import LundbergRock

    case = parse_case(at_default_accuracy("rock_drill"))
    summary = percussim.simulate(case).summary
    grids = [run["cells"] for run in summary["runs"]]
    assert grids[0] == 61 and all(cells % 61 == 0 for cells in grids), grids
    for run in summary["runs"]:
        assert striker_grid(case.striker, run["time_step"])[1] < 1e-9 * run["time_step"]
    rock = LundbergRock.of_case(case)
    assert summary["energy"]["transfer_efficiency"] == pytest.approx(rock.efficiency, rel=2.5e-4)


def test_a_piston_incommensurate_with_its_rod_or_a_lumped_striker_keeps_the_grids_it_had():
    from percussim.solver.grid import first_cells, ladder_unit, whole_striker, whole_striker_unit

    rock_drill = percussim.load_preset("rock_drill")
    assert whole_striker_unit(rock_drill) == 61
    assert (whole_striker(rock_drill, 49), whole_striker(rock_drill, 100), whole_striker(rock_drill, 30)) == (
        61,
        122,
        30,
    )
    assert (ladder_unit(rock_drill, 122), ladder_unit(rock_drill, 26)) == (61, 1)  # 26: a ladder started off them
    longer = rock_drill.model_copy(
        update={"striker": rock_drill.striker.model_copy(update={"length": 0.3 * (1 + 1e-7)})}
    )
    assert whole_striker_unit(longer) == 1 and first_cells(longer, 0.01) == 49
    assert whole_striker_unit(percussim.load_preset("fig3")) == 1
