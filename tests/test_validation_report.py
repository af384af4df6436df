"""The validation report (bench/validation.py, which writes docs/validation.md and its figures)
runs, and what it reports is what the other tests assert: the closed form met, the observed
orders, the rigid-tool limit, and each closed form of the models beyond the paper within what
its test holds it to, with the energy residual those tests allow."""

from __future__ import annotations

import importlib.util
import re

import pytest

from percussim.testing.live_stack import ROOT

pytestmark = pytest.mark.slow  # a live stack, a browser or the solver's full reports


def _validation_module():
    spec = importlib.util.spec_from_file_location("validation_report", ROOT / "bench" / "validation.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _rows(text: str, header: str) -> list[list[str]]:
    """The cells of every row of each table whose header starts with `header`."""
    lines = text.splitlines()
    rows = []
    for i, line in enumerate(lines):
        if line.startswith(header):
            for row in lines[i + 2 :]:
                if not row.startswith("|"):
                    break
                rows.append([cell.strip() for cell in row.strip("|").split("|")])
    return rows


def test_the_report_and_its_figures_are_made_from_the_solver(tmp_path):
    figures = {}
    text = _validation_module().report(figures)
    assert set(figures) == {"reference", "wave", "rigid_limit", "piston", "lundberg", "smith_loop", "blows", "anvil"}
    for name, fig in figures.items():
        fig.savefig(tmp_path / f"{name}.png")
        assert (tmp_path / f"{name}.png").read_bytes().startswith(b"\x89PNG")
        assert all(ax.lines for ax in fig.axes if not ax.images), name  # every panel has curves
        assert f"(validation/{name}.png)" in text
    # The observed orders of each scheme against the closed form: 1 for the paper's, 2 for the others.
    orders = {
        m[0]: (float(m[1]), float(m[2]))
        for m in re.findall(r"^\| (paper|sigma|explicit) \| \S+ \| ([\d.]+) \| \S+ \| ([\d.]+) \|$", text, re.M)
    }
    assert set(orders) == {"paper", "sigma", "explicit"}
    assert all(0.9 < o < 1.1 for o in orders["paper"])
    assert all(1.7 < o < 2.4 for s in ("sigma", "explicit") for o in orders[s])
    # The rigid-tool limit: at E × 10⁴ the rod is within 0.5% of the model problem.
    stiff = re.search(r"^\| 10000 \| [\d.]+ \| ([+-][\d.]+)% \| [\d.]+ \| ([+-][\d.]+)% \|$", text, re.M)
    assert stiff and all(abs(float(e)) < 0.5 for e in stiff.groups())
    # The models beyond the paper: every closed form within what its test holds it to, at fine
    # numerics and at the tolerance, and every run's energy residual within 0.5%.
    checks = _rows(text, "| case | quantity | closed form |")
    assert {row[0] for row in checks} >= {
        "r = 0.5",
        "r = 1",
        "r = 2",
        "x = 0.3",
        "x = 0.6",
        "x = 1.2564",
        "x = 2",
        "x = 3",
        "J = 0",
        "J = 0.5",
        "1-mg anvil, against none",
        "striker 2 kg on anvil 1 kg",
        "striker 1 kg on anvil 3 kg",
    }
    for case, quantity, _, _, fine, _, tolerance, held in checks:
        if held != "—":
            assert abs(float(fine)) <= float(held) and abs(float(tolerance)) <= float(held), (case, quantity)
    for quantity, _, _, difference, held in _rows(text, "| quantity | whole | fractional |"):
        assert abs(float(difference)) <= float(held), quantity
    runs = _rows(text, "| case | numerics | cells | run time (s) | energy residual |")
    assert len(runs) == 33
    assert all(abs(float(row[4])) < 5e-3 for row in runs), runs
    # Piles: each closed form within what its test holds it to
    closed = _rows(text, "| closed form | expected | solver | relative error |")
    assert len(closed) == 8 and all(float(row[3]) < 2e-3 for row in closed), closed
    toe = _rows(text, "| R_u / F_i | closed-form set |")
    assert [row[4] for row in toe[-2:]] == ["refusal", "refusal"]
    assert len(toe) == 8 and all(float(row[3]) < 5e-3 for row in toe[:-2]), toe
    smith = _rows(text, "| quantity | Smith's lumped model (600 masses) |")
    assert len(smith) == 5 and all(float(row[3]) < 3e-3 for row in smith), smith
    residual = re.search(r"^\| the residual \(`numerical`\), over what was supplied \| (\S+) \|$", text, re.M)
    assert residual and abs(float(residual.group(1))) < 5e-3
    # A hammer at work: the drive's closed forms as tests/test_drive.py holds them (what is spent
    # between blows within the scheme's loss, under 1%), the adaptive stroke at its target and
    # longer on the harder rock
    drive = _rows(text, "| closed form | expected | found | relative error |")
    spent = [row for row in drive if "spent as the tool comes to rest" in row[0]]
    assert len(drive) == 13 and len(spent) == 1 and float(spent[0][3]) < 1e-2, drive
    assert all(float(row[3]) < 1e-4 for row in drive if row not in spent), drive
    adaptive = _rows(text, "| rock's loading stiffness | last blow's set |")
    assert len(adaptive) == 2 and all(float(row[2]) < 0.03 for row in adaptive), adaptive
    last_stroke = [float(row[3].split("→")[1].split()[0]) for row in adaptive]
    assert last_stroke[1] > 2 * last_stroke[0]
    # Signal matching: every unknown and the capacity within 3 standard errors of the truth, the
    # shaft and the toe that reach the gauges together warned of, the Case method and the load test
    # against their closed forms as their tests hold them
    recovered = _rows(text, "| unknown | truth | matched | standard error | off by |")
    assert len(recovered) == 7 and all(float(row[4].split()[0]) <= 3.0 for row in recovered), recovered
    assert re.search(
        r"^Correlation of the two resistances -0\.99\d; the warning: \"shaft\.0\.ultimate_resistance", text, re.M
    )
    case_method = _rows(text, "| J_c | closed form")
    assert len(case_method) == 6 and all(float(row[3]) < 2e-3 for row in case_method), case_method
    load_test = _rows(text, "| closed form | expected | load test | relative error |")
    assert len(load_test) == 2 and float(load_test[0][3]) < 1e-9 and float(load_test[1][3]) < 1e-5, load_test
