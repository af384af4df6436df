"""The bench's own copies of the kernel's step (bench/kernel.py: the C step of bench/kernel_c/step.c
and the NumPy/SciPy solve_banded loop; bench/sawtooth.py: the explicit scheme with its ends'
SDIRK, written apart from the kernel) restate its slots and laws by hand: they must still compute
what the kernel computes, or the bench's ratios and comparisons compare different things."""

from __future__ import annotations

import importlib.util
import sys
import tempfile
from pathlib import Path

import numpy as np
import pytest

BENCH = Path(__file__).resolve().parents[1] / "bench" / "kernel.py"
SAWTOOTH = BENCH.with_name("sawtooth.py")
# The peak force differs by a step's change: the kernel records the force the scheme applies,
# centred on a layer, and refines the ends' extremes between layers, the copies keep the layers'.
PEAK_FORCE = 1e-3
EXACT = 1e-8  # every other quantity (the energy terms as a share of the impact energy)


def loaded(name: str, path: Path):
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # its dataclasses look their module up
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def bench():
    yield loaded("kernel_bench", BENCH)
    del sys.modules["kernel_bench"]


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


@pytest.mark.slow
def test_the_sawtooth_replica_computes_the_kernels_run():
    """bench/sawtooth.py's replica of matrix-31 without its force (a tapered tool, a lumped striker
    on a damped linear contact, a free far end) steps as the kernel does: the same contact force at
    every step of the first 0.2 ms, within what rounding makes of it."""
    from percussim.solver.case import parse_case
    from percussim.solver.controller import simulate_rod
    from percussim.solver.grid import explicit_numerics

    sawtooth = loaded("sawtooth_bench", SAWTOOTH)
    try:
        raw = sawtooth.variant("without its external force")
        raw["numerics"]["duration"], raw["outputs"] = 2e-4, {"history_stride": 1}
        case = parse_case(raw)
        kernel = simulate_rod(case, numerics=explicit_numerics(case, 1000)).history["contact/force"]
        replica = sawtooth.replica(sawtooth.variant("without its external force"), 1000, 2e-4, 1)[:, 2]
    finally:
        del sys.modules["sawtooth_bench"]
    count = min(len(kernel), len(replica))
    assert count > 1000
    assert np.abs(replica[1:count] - kernel[1:count]).max() <= EXACT * np.abs(kernel[1:count]).min()
