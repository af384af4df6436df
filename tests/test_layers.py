"""The layers point down: percussim (API, command line, client) → service and worker, side by side
→ common (what they share) → solver, and what validates input loads no kernel. percussim.testing
(the tests' and benches' references and live stack) stands beside them: none imports it."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
ABOVE_SOLVER = (
    "percussim.common",
    "percussim.service",
    "percussim.worker",
    "percussim.cli",
    "percussim.client",
    "percussim.testing",
)
# Each folder, the package it installs as, and the packages it may not import.
LAYERS = {
    "solver": ("percussim.solver", (*ABOVE_SOLVER, "fastapi", "celery", "starlette", "sqlalchemy")),
    "percussim/common": (
        "percussim.common",
        (
            "percussim.service",
            "percussim.worker",
            "percussim.cli",
            "percussim.client",
            "percussim.testing",
            "fastapi",
            "celery",
        ),
    ),
    "worker": ("percussim.worker", ("percussim.service", "percussim.cli", "percussim.testing", "fastapi")),
    "service": ("percussim.service", ("percussim.worker", "percussim.cli", "percussim.testing")),
}


def imported(path: Path, folder: str) -> set[str]:
    """Every module `path` (in `folder`) imports, relative imports resolved within its package."""
    names = set()
    here = LAYERS[folder][0].split(".") + list(path.parent.relative_to(ROOT / folder).parts)
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names |= {alias.name for alias in node.names}
        elif isinstance(node, ast.ImportFrom):
            base = here[: len(here) - node.level + 1] if node.level else []
            module = ".".join(base + ([node.module] if node.module else []))
            names |= {module} | {f"{module}.{alias.name}" for alias in node.names}
    return names


@pytest.mark.parametrize("folder", LAYERS)
def test_a_layer_imports_nothing_above_it(folder):
    package, forbidden = LAYERS[folder]
    wrong = {
        f"{path.relative_to(ROOT)}: {name}"
        for path in (ROOT / folder).rglob("*.py")
        for name in imported(path, folder)
        if any(name == f or name.startswith(f + ".") for f in forbidden)
    }
    assert not wrong, sorted(wrong)


@pytest.mark.parametrize("folder", ["solver", "worker", "service"])
def test_a_folder_is_only_its_package(folder):
    """Loaded under its folder's name it would be a second copy of every module."""
    done = subprocess.run([sys.executable, "-c", f"import {folder}"], cwd=ROOT, capture_output=True, text=True)
    assert done.returncode != 0 and f"import percussim.{folder}, not {folder}" in done.stderr


def loaded_after(statement: str) -> set[str]:
    probe = f"import sys\n{statement}\nprint(*sys.modules)"
    done = subprocess.run([sys.executable, "-c", probe], cwd=ROOT, capture_output=True, text=True, check=True)
    return set(done.stdout.split())


@pytest.mark.parametrize(
    "statement",
    [
        "import percussim",
        "import percussim; percussim.Case, percussim.load_preset('fig3'), percussim.Client",
        "from percussim.solver.case import parse_case",
        "from percussim.service.app import create_app; create_app()",
        "from percussim.solver.summary import Summary",
        "from percussim.solver.limits import check_case",
    ],
)
def test_validating_input_loads_neither_the_kernel_nor_scipy(statement):
    """The API validates cases and study requests and reads results: neither Numba (the kernel)
    nor scipy (the studies' searches and fits, the soil's rest), which the workers load."""
    heavy = {"numba", "scipy", "percussim.solver.kernel", "percussim.solver.controller"} & loaded_after(statement)
    assert not heavy, sorted(heavy)


def test_a_run_loads_the_kernel_when_it_needs_it():
    loaded = loaded_after("import percussim; percussim.simulate(percussim.load_preset('fig3'))")
    assert {"numba", "percussim.solver.kernel"} <= loaded


def runtime_imports(name: str) -> set[str]:
    """The solver modules `solver/<name>.py` imports when it runs (not those for type hints only)."""
    tree = ast.parse((ROOT / "solver" / f"{name}.py").read_text())
    hints = {
        id(inner)
        for node in ast.walk(tree)
        if isinstance(node, ast.If) and getattr(node.test, "id", "") == "TYPE_CHECKING"
        for inner in ast.walk(node)
    }
    return {
        node.module.split(".")[0]
        for node in ast.walk(tree)
        if isinstance(node, ast.ImportFrom) and node.level == 1 and node.module and id(node) not in hints
    }


def callers(function: str) -> set[str]:
    """The solver modules that call `function` by name."""
    return {
        path.stem
        for path in (ROOT / "solver").glob("*.py")
        for node in ast.walk(ast.parse(path.read_text()))
        if isinstance(node, ast.Call) and getattr(node.func, "id", "") == function
    }


def test_the_accuracy_path_runs_one_way_down():
    """simulate → adaptive (the runs) → accuracy (the estimate, once) → summary (prints it): no
    module on the way calls back up, estimation is assessed only where the runs are chosen, and
    only the entry point prints it into the summary."""
    assert runtime_imports("accuracy").isdisjoint({"adaptive", "controller", "summary", "simulate"})
    assert runtime_imports("summary").isdisjoint({"accuracy", "adaptive", "simulate"})
    assert runtime_imports("adaptive").isdisjoint({"simulate", "summary"})
    assert "accuracy" in runtime_imports("adaptive")
    assert callers("assess") == {"adaptive"}
    assert callers("add_accuracy") == {"simulate"}
