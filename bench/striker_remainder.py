"""An elastic striker's length between two nodes: the rock drill's energy to the rock on grids
that place the piston's end differently, against Lundberg's closed form.

    .venv/bin/python bench/striker_remainder.py

At Courant number 1 the piston's cells are whole time steps; the part of its length beyond its
last node is a delay its back end returns the wave after (`grid.striker_grid`, `free_back_end`).
Printed: the default accuracy's own grids (49 cells, doubled), grids on which the piston is a whole
number of cells (61, doubled), and consecutive grids around 240, 480 and 960 cells, each with the
fraction of a cell the piston's end lies past a node, the energy to the rock and the co-impact
time. `LundbergRock` (a rigid contact) gives the rock's share of a rectangular wave.
"""

from __future__ import annotations

from percussim.solver.case import parse_case
from percussim.solver.controller import simulate_rod, warm_up
from percussim.solver.grid import explicit_numerics, striker_transit, wave_speed
from percussim.solver.presets import preset_json
from percussim.testing import merge
from percussim.testing.reference import LundbergRock


def main() -> None:
    warm_up()
    case = parse_case(merge(preset_json("rock_drill"), {"numerics": {"cells": None, "time_step": None, "gamma": None}}))
    per_cell = striker_transit(case.striker) * wave_speed(case.tool) / case.tool.length  # piston cells a tool cell
    lundberg = LundbergRock.of_case(case)
    supplied = None
    rows = {
        "the ladder's grids (49, doubled)": [49 * 2**k for k in range(6)],
        "the piston a whole number of cells (61, doubled)": [61 * 2**k for k in range(6)],
        "consecutive grids": list(range(232, 246)) + list(range(476, 490)) + list(range(952, 980, 2)),
    }
    for title, grids in rows.items():
        print(f"\n{title}:")
        print(
            f"  {'cells':>6s} {'piston cells':>13s} {'past a node':>12s} {'to the rock (J)':>16s} {'co-impact (µs)':>15s}"
        )
        for cells in grids:
            numerics = explicit_numerics(case, cells)
            summary = simulate_rod(case.summary_only(), numerics=numerics).summary
            energy = summary["energy"]
            supplied = energy["initial"]
            piston = cells * per_cell
            print(
                f"  {cells:6d} {piston:13.3f} {piston % 1.0:12.3f} {energy['to_medium']:16.4f} "
                f"{summary['co_impact_time'] * 1e6:15.3f}"
            )
    print(f"\nLundberg (a rigid contact): {lundberg.efficiency * supplied:.4f} J to the rock")


if __name__ == "__main__":
    main()
