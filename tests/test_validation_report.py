"""The validation report (bench/validation.py, which writes docs/validation.md and its figures)
runs, and what it reports is what the other tests assert: the closed form met, the observed
orders, the rigid-tool limit."""

from __future__ import annotations

import importlib.util
import re

import pytest

from live_stack import ROOT

pytestmark = pytest.mark.slow  # a live stack, a browser or the solver's full reports


def _validation_module():
    spec = importlib.util.spec_from_file_location("validation_report", ROOT / "bench" / "validation.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_report_and_its_figures_are_made_from_the_solver(tmp_path):
    figures = {}
    text = _validation_module().report(figures)
    assert set(figures) == {"reference", "wave", "rigid_limit"}
    for name, fig in figures.items():
        fig.savefig(tmp_path / f"{name}.png")
        assert (tmp_path / f"{name}.png").read_bytes().startswith(b"\x89PNG")
        assert all(ax.lines for ax in fig.axes if not ax.images), name  # every panel has curves
        assert f"(validation/{name}.png)" in text
    # The observed orders of each scheme against the closed form: 1 for the paper's, 2 for the others.
    orders = {m[0]: (float(m[1]), float(m[2])) for m in
              re.findall(r"^\| (paper|sigma|explicit) \| \S+ \| ([\d.]+) \| \S+ \| ([\d.]+) \|$", text, re.M)}
    assert set(orders) == {"paper", "sigma", "explicit"}
    assert all(0.9 < o < 1.1 for o in orders["paper"])
    assert all(1.7 < o < 2.4 for s in ("sigma", "explicit") for o in orders[s])
    # The rigid-tool limit: at E × 10⁴ the rod is within 0.5% of the model problem.
    stiff = re.search(r"^\| 10000 \| [\d.]+ \| ([+-][\d.]+)% \| [\d.]+ \| ([+-][\d.]+)% \|$", text, re.M)
    assert stiff and all(abs(float(e)) < 0.5 for e in stiff.groups())
