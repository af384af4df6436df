"""A Hertz contact on a tapered tool converges under refinement at the scheme's first order."""

import json
import math
from pathlib import Path

import numpy as np
import pytest

from percussim.solver.case import parse_case
from percussim.solver.controller import simulate_rod
from percussim.testing import merge

TAPERED = json.loads((Path(__file__).parent / "cases" / "tapered_hertz.json").read_text())
WAVE_SPEED = math.sqrt(2.1e11 / 7800.0)


def _quantities(cells: int) -> dict[str, float]:
    case = parse_case(merge(TAPERED, {"numerics": {"cells": cells, "time_step": 0.5 * (0.5 / cells) / WAVE_SPEED}}))
    result = simulate_rod(case)
    s = result.summary
    assert s["warnings"] == []
    return {
        "co_impact_time": s["co_impact_time"],
        "peak_contact_force": s["peak_contact_force"]["value"],
        "max_tensile_stress": s["max_tensile_stress"]["value"],
        "max_compressive_stress": s["max_compressive_stress"]["value"],
        "cone_probe_compression": -result.probe_stress[:, 0].min(),
    }


@pytest.fixture(scope="module")
def ladder() -> dict[int, dict[str, float]]:
    return {cells: _quantities(cells) for cells in (50, 100, 200, 400, 800, 1600)}


@pytest.mark.parametrize(
    "name, grids",
    [
        ("co_impact_time", (50, 100, 200, 400)),
        ("peak_contact_force", (50, 100, 200, 400)),
        ("max_tensile_stress", (50, 100, 200, 400)),
        # The peak moves from the struck end into the cone once the grid resolves the cone's front.
        ("max_compressive_stress", (400, 800, 1600)),
        ("cone_probe_compression", (400, 800, 1600)),
    ],
)
def test_differences_shrink_at_first_order(ladder, name, grids):
    values = np.array([ladder[g][name] for g in grids])
    differences = np.abs(np.diff(values))
    orders = np.log2(differences[:-1] / differences[1:])
    assert np.all((orders > 0.7) & (orders < 1.3)), (name, values, orders)
    # The last refinement changes the value by little: the ladder really is converging.
    assert differences[-1] / abs(values[-1]) < 0.02
