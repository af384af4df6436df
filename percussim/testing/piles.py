"""A pile and its soil for the pile studies' tests and bench: the pile preset (a 4.5-t ram falling
0.99 m on a helmet and a 15-m steel pipe, under gravity) with 1.8 MN of resistance, a third at the toe and the
rest over the shaft's lower 10 m; and sand over dense sand, whose shaft resistance gains half again
over a pause, its toe refusal within 11 m."""

from __future__ import annotations

from percussim.solver.presets import preset_json

from . import merge

PILE = merge(
    preset_json("pile"),
    {
        "medium": {"ultimate_resistance": 6e5},
        "shaft": [
            {"from": 5.0, "to": 10.0, "ultimate_resistance": 4e5, "quake": 2.54e-3, "damping_factor": 0.16},
            {"from": 10.0, "to": 15.0, "ultimate_resistance": 8e5, "quake": 2.54e-3, "damping_factor": 0.16},
        ],
    },
)
# Smith's quakes (0.1 in) and damping factors (0.05 s/ft on the shaft, 0.15 s/ft at the toe)
LAYER = {"shaft_quake": 2.54e-3, "toe_quake": 2.54e-3, "shaft_damping_factor": 0.16, "toe_damping_factor": 0.49}
SOIL = {
    "layers": [
        {"from": 0.0, "to": 6.0, "shaft_resistance": 2e4, "toe_resistance": 4e5, **LAYER},
        {"from": 6.0, "to": 20.0, "shaft_resistance": 6e4, "toe_resistance": 2.5e6, "setup_factor": 1.5, **LAYER},
    ],
    "depths": [3.0, 5.0, 7.0, 9.0, 11.0],
    "blow_rate": 0.8,
    "refusal": 150.0,
}
