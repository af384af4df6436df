"""percussim as a user installs it: a wheel built from the repository, in a fresh virtual
environment, used from a folder outside the repository."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import venv
import zipfile
from importlib.metadata import version
from pathlib import Path

import pytest

import percussim
from percussim.solver.compiled import cache_folder

ROOT = Path(__file__).resolve().parents[1]

pytestmark = pytest.mark.slow


def run(command: list, cwd: Path, status: int = 0) -> subprocess.CompletedProcess:
    # No PYTHONPATH and a folder outside the repository: only what the wheel installed is found.
    # The kernel's cache is this tree's: the wheel's sources are the same, so it is not compiled again.
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PERCUSSIM_PRESETS")}
    env["NUMBA_CACHE_DIR"] = str(Path(cache_folder()).parent)
    done = subprocess.run([str(c) for c in command], cwd=cwd, env=env, capture_output=True, text=True, timeout=600)
    assert done.returncode == status, f"{command}: {done.stderr}"
    return done


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("wheel")
    run([sys.executable, "-m", "pip", "wheel", "--quiet", "--no-deps", "--wheel-dir", out, ROOT], cwd=out)
    (built,) = out.glob("percussim-*.whl")
    return built


@pytest.fixture(scope="module")
def installed(wheel, tmp_path_factory) -> Path:
    """A fresh environment with the wheel and its required dependencies only (no extras)."""
    env = tmp_path_factory.mktemp("env") / "venv"
    venv.create(env, with_pip=True)
    run(
        [env / "bin" / "python", "-m", "pip", "install", "--quiet", "--disable-pip-version-check", wheel],
        cwd=env.parent,
    )
    return env


def test_the_wheel_has_one_top_level_name_and_its_data(wheel):
    names = zipfile.ZipFile(wheel).namelist()
    assert {n.split("/")[0] for n in names if ".dist-info/" not in n} == {"percussim"}
    presets = {Path(n).stem for n in names if n.startswith("percussim/solver/presets/") and n.endswith(".json")}
    assert presets == set(percussim.preset_names())
    static = {Path(n).name for n in names if n.startswith("percussim/service/static/")}
    assert static == {p.name for p in (ROOT / "service" / "static").iterdir() if p.is_file()}


def test_the_installed_package_lists_runs_and_simulates_a_preset(installed, tmp_path):
    bin_ = installed / "bin"
    listed = run([bin_ / "percussim", "presets"], cwd=tmp_path).stdout.split("\n")
    assert [line.split()[0] for line in listed if line] == percussim.preset_names()

    run([bin_ / "percussim", "run", "fig3", "--summary", "fig3.json"], cwd=tmp_path)
    here = percussim.simulate(percussim.load_preset("fig3")).summary
    there = json.loads((tmp_path / "fig3.json").read_text())
    # The same code on the same machine: the same numbers, to the last bit.
    assert there["co_impact_time"] == here["co_impact_time"]
    assert there["peak_contact_force"] == here["peak_contact_force"]

    script = """
import json, sys
import percussim
lazy = "numba" not in sys.modules
result = percussim.simulate(percussim.load_preset("fig3"))
from percussim.solver import kernel
stats = kernel.advance.stats
print(json.dumps({"lazy": lazy, "file": percussim.__file__, "version": percussim.__version__,
                  "loaded": [sum(stats.cache_hits.values()), sum(stats.cache_misses.values())],
                  "peak": result.summary["peak_contact_force"]["value"],
                  "elsewhere": [m for m in ("solver", "service", "worker") if m in sys.modules]}))
"""
    got = json.loads(run([bin_ / "python", "-c", script], cwd=tmp_path).stdout)
    assert got["lazy"], "import percussim loads no Numba"
    assert Path(got["file"]).is_relative_to(installed), got["file"]
    assert got["version"] == version("percussim")
    assert got["peak"] == here["peak_contact_force"]["value"]
    assert got["elsewhere"] == []
    assert got["loaded"] == [1, 0], "the wheel's solver is this tree's: its kernel is loaded, not compiled"


def test_a_command_needing_an_extra_names_it(installed, tmp_path):
    """The install has no extras: serving and plotting say what to install."""
    bin_ = installed / "bin"
    serve = run([bin_ / "percussim", "serve", "--port", "1"], cwd=tmp_path, status=1)
    assert "pip install 'percussim[service]'" in serve.stderr, serve.stderr
    run([bin_ / "percussim", "run", "fig3", "--output", "fig3.h5"], cwd=tmp_path)
    plot = run([bin_ / "percussim", "plot", "fig3.h5"], cwd=tmp_path, status=1)
    assert "pip install 'percussim[plots]'" in plot.stderr, plot.stderr
    assert "Traceback" not in serve.stderr + plot.stderr
