"""The bench's own copies of the kernel's step (bench/kernel.py: the C step of bench/kernel_c/step.c
and the NumPy/SciPy solve_banded loop) restate its slots and laws by hand: they must still compute
what the kernel computes, or the bench's ratios compare different things."""

from __future__ import annotations

import importlib.util
import sys
import tempfile
from pathlib import Path

import pytest

BENCH = Path(__file__).resolve().parents[1] / "bench" / "kernel.py"
# The peak force differs by a step's change: the kernel records the force the scheme applies,
# centred on a layer, and refines the ends' extremes between layers, the copies keep the layers'.
PEAK_FORCE = 1e-3
EXACT = 1e-8  # every other quantity (the energy terms as a share of the impact energy)


@pytest.fixture(scope="module")
def bench():
    spec = importlib.util.spec_from_file_location("kernel_bench", BENCH)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # its dataclasses look their module up
    spec.loader.exec_module(module)
    yield module
    del sys.modules[spec.name]


@pytest.mark.slow
@pytest.mark.parametrize("grid", ["paper 100", "explicit 100", "paper 2000"])
def test_the_bench_copies_compute_the_kernels_run(bench, grid):
    fig3 = bench.load_case(bench.ROOT / "solver" / "presets" / "fig3.json")
    scheme, cells = grid.split()
    numerics = bench.explicit_courant_one(fig3, int(cells)) if scheme == "explicit" else {"cells": int(cells)}
    setup = bench.prepare(grid, grid, fig3, **numerics)
    impact_energy = 0.5 * fig3.striker.mass * fig3.striker.velocity**2
    numba = bench.numba_run(setup)
    with tempfile.TemporaryDirectory() as folder:
        copies = {"C": bench.c_run(bench.build_c(folder), setup), "solve_banded": bench.banded_run(setup)}
    for name, found in copies.items():
        assert found["contacts"] == numba["contacts"], name
        for key, value in numba.items():
            if key == "contacts":
                continue
            off = abs(found[key] - value) / impact_energy if key.startswith("energy") else abs(found[key] / value - 1.0)
            assert off <= (PEAK_FORCE if key == "peak contact force" else EXACT), (name, key, found[key], value)
