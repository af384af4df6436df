"""How the kernel is compiled and kept: Numba's on-disk cache, in a folder named after a hash of
every source of the solver, so that machine code compiled from other sources is never loaded.

Numba checks a cached function against its own file's time stamp and size only (numba issue
1833): a change to a module it reads constants from, such as `layout.py`'s slots, would leave the
old machine code in use, and wrong numbers with no error. Here a change to any source of the
solver moves the cache to a new folder, and the next run compiles again.

Inside that folder each solver folder's machine code is kept under its path in the solver
(`kernel`, `.`), where Numba would name it by a hash of its absolute path: a copy of the same
sources (an installed wheel, a moved checkout) sharing `NUMBA_CACHE_DIR` finds it.

Each version of the sources leaves a folder of about 2 MB. `prune_caches` (run by `percussim
warmup`) removes those of other versions that have not been used for a while.
"""

from __future__ import annotations

import hashlib
import os
import re
import shutil
import time
from functools import lru_cache
from pathlib import Path

from numba import njit
from numba.core import config
from numba.core.caching import UserProvidedCacheLocator

SOLVER = Path(__file__).resolve().parent
CACHE_PREFIX = "percussim-"  # and the sources' hash: one folder of compiled kernel a version
_CACHE_NAME = re.compile(CACHE_PREFIX + "[0-9a-f]{16}")


@lru_cache(maxsize=1)
def sources_hash() -> str:
    """A hash of every Python source of the solver, by path and content."""
    digest = hashlib.sha256()
    for path in sorted(SOLVER.rglob("*.py")):
        digest.update(path.relative_to(SOLVER).as_posix().encode() + b"\0" + path.read_bytes() + b"\0")
    return digest.hexdigest()[:16]


@lru_cache(maxsize=1)
def cache_folder() -> str:
    """Where the compiled kernel is kept: a folder for these sources in `NUMBA_CACHE_DIR` when it
    is set (a read-only install's), else in the solver's `__pycache__` when the solver's folder can
    be written, else in the user's cache."""
    base = os.environ.get("NUMBA_CACHE_DIR") or (
        str(SOLVER / "__pycache__") if os.access(SOLVER, os.W_OK) else str(Path.home() / ".cache" / "percussim")
    )
    return os.path.join(base, f"{CACHE_PREFIX}{sources_hash()}")


# Other versions' compiled kernels kept beside this one's: the most recently used, and any used
# within a day (another checkout or install may be loading or compiling into it now)
KEPT_CACHES = 8
KEPT_SECONDS = 86_400.0


def mark_cache_used() -> None:
    """Record that this version's compiled kernel was used now (its folder's time stamp), so that
    `prune_caches` run by another version keeps it."""
    try:
        os.utime(cache_folder())
    except OSError:  # not made yet, or a folder this user cannot touch
        pass


def prune_caches(keep: int = KEPT_CACHES, kept_seconds: float = KEPT_SECONDS) -> list[Path]:
    """Remove the compiled kernels of other versions of the solver's sources from the folder this
    version's is in: all but the `keep` most recently used, and none used within `kept_seconds`.
    Returns the folders removed."""
    own = Path(cache_folder())
    others = []
    for folder in own.parent.glob(CACHE_PREFIX + "*"):
        if folder != own and _CACHE_NAME.fullmatch(folder.name) and folder.is_dir():
            try:
                others.append((folder.stat().st_mtime, folder))
            except OSError:  # removed meanwhile by another prune
                pass
    others.sort(reverse=True)
    cutoff = time.time() - kept_seconds
    removed = [folder for used, folder in others[keep:] if used < cutoff]
    for folder in removed:
        shutil.rmtree(folder, ignore_errors=True)
    return removed


class SolverCacheLocator(UserProvidedCacheLocator):
    """Numba's locator for a folder the user gives (`config.CACHE_DIR`), with a function's machine
    code under its file's folder relative to the solver rather than under a hash of the absolute
    path. Numba still checks each function against a hash of its own file's content."""

    def __init__(self, py_func, py_file):
        super().__init__(py_func, py_file)
        folder = Path(py_file).resolve().parent.relative_to(SOLVER).as_posix()
        self._cache_path = os.path.join(config.CACHE_DIR, "solver" if folder == "." else folder)


# Numba's own after it, for a cache folder that cannot be written
LOCATORS = f"{__name__}.{SolverCacheLocator.__name__},InTreeCacheLocator,UserWideCacheLocator"


def compiled(**options):
    """`numba.njit(cache=True, error_model="numpy", **options)` with its cache in
    `cache_folder()`, laid out by `SolverCacheLocator`. Numba reads the cache's folder and locator
    when a function is decorated, so they are set for that moment only: other Numba code in the
    process keeps its own.

    Divisions follow IEEE arithmetic (`error_model="numpy"`): Python's check for a zero divisor is
    a branch on every division, and the ends' steps are chains of divisions. A zero divisor gives
    an infinity or a NaN, which the kernel's checks for non-finite values report, where Python's
    model raised an error no caller handles."""

    def decorate(function):
        previous = config.CACHE_DIR, config.CACHE_LOCATOR_CLASSES
        config.CACHE_DIR = cache_folder()
        config.CACHE_LOCATOR_CLASSES = LOCATORS
        try:
            return njit(cache=True, **{"error_model": "numpy", **options})(function)
        finally:
            config.CACHE_DIR, config.CACHE_LOCATOR_CLASSES = previous

    return decorate
