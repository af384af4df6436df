"""A new process finds the kernel in Numba's cache and does not compile it again."""

import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

from percussim.solver import compiled
from percussim.solver.compiled import CACHE_PREFIX, cache_folder
from percussim.solver.controller import simulate_rod, warm_up
from percussim.solver.presets import load_preset

PROBE = """
import json
from percussim.solver import kernel
from percussim.solver.presets import load_preset
from percussim.solver.controller import simulate_rod
simulate_rod(load_preset("fig3"))
s = kernel.advance.stats
print(json.dumps({"hits": sum(s.cache_hits.values()), "misses": sum(s.cache_misses.values())}))
"""


def test_a_new_process_loads_the_compiled_kernel():
    root = Path(__file__).resolve().parents[1]
    runs = [
        json.loads(
            subprocess.run(
                [sys.executable, "-c", PROBE], cwd=root, capture_output=True, text=True, check=True, timeout=300
            ).stdout
        )
        for _ in range(2)
    ]
    # The first run may have filled the cache; the second must only read it.
    assert runs[1] == {"hits": 1, "misses": 0}


STALE_PROBE = """
import json
from percussim.solver import kernel
from percussim.solver.controller import simulate_rod
from percussim.solver.presets import load_preset
result = simulate_rod(load_preset("fig3"))
s = kernel.advance.stats
print(json.dumps({"kernel": kernel.__file__, "hits": sum(s.cache_hits.values()),
                  "misses": sum(s.cache_misses.values()),
                  "peak": result.summary["peak_contact_force"]["value"],
                  "force": result.history["contact/force"].tolist()}))
"""
SLOTS = "H_CONTACT_FORCE, H_OVERLAP, H_MEDIUM_FORCE, H_EXTERNAL_FORCE = 5, 6, 7, 8"


@pytest.mark.slow
def test_a_copy_loads_the_kernel_and_a_changed_slot_constant_recompiles_it(tmp_path):
    """A copy of the package with this tree's compiled kernel in its cache folder: its first run
    loads it, compiled elsewhere (the cache is named by the sources, not by where they are). Then
    two history slots swapped in layout.py alone (the kernel's own file unchanged, which is all
    Numba checks): the next run compiles again and records the contact force where the
    controller reads it."""
    root = Path(__file__).resolve().parents[1]
    warm_up()  # this tree's kernel in its cache, if a run has not put it there yet
    package = tmp_path / "percussim"
    shutil.copytree(root / "percussim", package, ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copytree(root / "solver", package / "solver", ignore=shutil.ignore_patterns("__pycache__"))
    here = Path(cache_folder())
    shutil.copytree(here, package / "solver" / "__pycache__" / here.name)
    env = {**os.environ, "PYTHONPATH": str(tmp_path)}
    env.pop("NUMBA_CACHE_DIR", None)  # the copy's own cache, in its __pycache__

    def probe() -> dict:
        done = subprocess.run(
            [sys.executable, "-c", STALE_PROBE], cwd=tmp_path, capture_output=True, text=True, env=env, timeout=600
        )
        assert done.returncode == 0, done.stderr
        return json.loads(done.stdout)

    copied = probe()
    assert Path(copied["kernel"]).is_relative_to(tmp_path)
    assert copied["misses"] == 0 and copied["hits"] == 1
    here_result = simulate_rod(load_preset("fig3"))
    assert copied["force"] == here_result.history["contact/force"].tolist()
    layout = package / "solver" / "layout.py"
    assert SLOTS in layout.read_text()
    layout.write_text(layout.read_text().replace(SLOTS, SLOTS.replace("5, 6", "6, 5")))
    swapped = probe()
    assert swapped["misses"] == 1 and swapped["hits"] == 0
    assert swapped["force"] == copied["force"] and swapped["peak"] == copied["peak"]


def _folders(base: Path, ages_hours: list[float]) -> list[Path]:
    """Compiled kernels of other versions in `base`, each last used `ages_hours` ago."""
    now = time.time()
    made = []
    for k, age in enumerate(ages_hours):
        folder = base / f"{CACHE_PREFIX}{k:016x}"
        (folder / "kernel").mkdir(parents=True)
        (folder / "kernel" / "step.nbi").write_bytes(b"\0" * 64)
        os.utime(folder, (now - age * 3600, now - age * 3600))
        made.append(folder)
    return made


def test_pruning_keeps_the_recent_versions_and_any_used_within_a_day(tmp_path, monkeypatch):
    own = tmp_path / f"{CACHE_PREFIX}{'f' * 16}"
    own.mkdir()
    monkeypatch.setattr(compiled, "cache_folder", lambda: str(own))
    # ten used within the day, three older: the eight most recent are kept, and the two recent
    # beyond them too, since another checkout may be compiling into them
    recent = _folders(tmp_path, [1, 2, 3, 4, 5, 6, 7, 8, 9, 10] + [50, 100, 200])
    strangers = [tmp_path / "percussim-notahash", tmp_path / "numba"]
    for folder in strangers:
        folder.mkdir()
    removed = compiled.prune_caches()
    assert sorted(removed) == sorted(recent[10:])
    assert all(f.is_dir() for f in recent[:10] + strangers + [own])
    assert not any(f.exists() for f in recent[10:])
    assert compiled.prune_caches() == []


def test_warmup_prunes_old_versions_and_marks_its_own_used(tmp_path):
    """`percussim warmup` with a cache of this tree's kernel and of eleven other versions, five
    used within the day and six over two to seven days ago: it loads the kernel, keeps the eight
    most recently used others and removes the three oldest, and marks its own as used now."""
    warm_up()
    here = Path(cache_folder())
    own = tmp_path / here.name
    shutil.copytree(here, own)
    os.utime(own, (0, 0))
    others = _folders(tmp_path, [1, 2, 3, 4, 5] + [48, 72, 96, 120, 144, 168])
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path)}
    done = subprocess.run(
        [sys.executable, "-m", "percussim", "warmup"], capture_output=True, text=True, env=env, timeout=300
    )
    assert done.returncode == 0, done.stderr
    assert "removed the compiled kernels of 3 other version(s)" in done.stdout
    assert [f.is_dir() for f in others] == [True] * 8 + [False] * 3
    assert time.time() - own.stat().st_mtime < 300
    assert sorted(p.name for p in own.iterdir()) == sorted(p.name for p in here.iterdir())


LADDER_PROBE = """
import json, sys
from percussim.solver.controller import warm_up
from percussim.solver.simulate import simulate
from percussim.testing import at_default_accuracy
warm_up()
before = set(sys.modules)
runs = simulate(at_default_accuracy("fig3")).summary["runs"]
print(json.dumps({"grids": [r["cells"] for r in runs], "loaded": sorted(set(sys.modules) - before)}))
"""


def test_a_warmed_up_process_loads_nothing_for_a_ladder_that_refines_unevenly():
    """A worker warms up before its first job: that job, a ladder whose last grids are not twice
    as fine as the one before (its order found by a root finder), loads no module then."""
    root = Path(__file__).resolve().parents[1]
    done = subprocess.run(
        [sys.executable, "-c", LADDER_PROBE], cwd=root, capture_output=True, text=True, check=True, timeout=300
    )
    probe = json.loads(done.stdout)
    grids = probe["grids"]
    assert any(fine != 2 * coarse for coarse, fine in zip(grids, grids[1:])), grids
    assert probe["loaded"] == []
