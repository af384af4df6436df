"""Dotted paths into a case (`solver/paths.py`): a list's items by index, or all of them tied by
`*`, as sweeps, fits and optimisations vary them."""

from __future__ import annotations

from percussim.solver.paths import set_field, value_at
from percussim.solver.sweep import Sweep, variants
from percussim.testing.piles import PILE


def test_a_star_sets_every_item_and_reads_the_first():
    tree = {"shaft": [{"quake": 1.0}, {"quake": 2.0}], "tool": {"length": 3.0}}
    set_field(tree, "shaft.*.quake", 5e-3)
    assert [segment["quake"] for segment in tree["shaft"]] == [5e-3, 5e-3]
    set_field(tree, "shaft.1.quake", 7e-3)
    assert value_at(tree, "shaft.*.quake") == 5e-3 and value_at(tree, "shaft.-1.quake") == 7e-3
    set_field(tree, "tool.length", 4.0)
    assert tree["tool"] == {"length": 4.0}


def test_a_sweep_over_every_segments_damping_varies_them_together():
    cases = variants(Sweep.model_validate({"case": PILE, "parameters": {"shaft.*.damping_factor": [0.2, 0.4]}}))
    assert [[segment.damping_factor for segment in case.shaft] for _, case in cases] == [[0.2, 0.2], [0.4, 0.4]]
