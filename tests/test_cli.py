"""`percussim run`: prints the summary, writes files, exit 2 naming the field on a bad case."""

import json
import signal
import subprocess
import sys
from pathlib import Path

import h5py
import pytest
from conftest import BASE_CASE, merge

ROOT = Path(__file__).resolve().parents[1]
PRESETS = ROOT / "solver" / "presets"  # the presets as shipped


def _percussim(*args, cwd):
    return subprocess.run(
        [sys.executable, "-m", "percussim", *args], cwd=cwd, capture_output=True, text=True, env=None, timeout=120
    )


def test_run_prints_and_writes_the_summary_and_result(tmp_path):
    case = tmp_path / "case.json"
    case.write_text(json.dumps(merge(BASE_CASE, {"numerics": {"duration": 5e-4}})))
    done = _percussim("run", str(case), "--summary", "s.json", "--output", "r.h5", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    printed = json.loads(done.stdout)
    assert json.loads((tmp_path / "s.json").read_text()) == printed
    assert 3e-4 < printed["co_impact_time"] < 3.5e-4
    with h5py.File(tmp_path / "r.h5") as f:
        assert json.loads(f["summary"][()]) == printed


def test_invalid_case_exits_2_with_the_field(tmp_path):
    case = tmp_path / "bad.json"
    case.write_text(json.dumps(merge(BASE_CASE, {"contact": {"exponent": 0.9}, "striker": {"mass": 0}})))
    done = _percussim("run", str(case), cwd=tmp_path)
    assert done.returncode == 2
    assert "contact.exponent: must be ≤ 0.5" in done.stderr
    assert "striker.mass: must be > 0" in done.stderr
    assert done.stdout == ""
    broken = tmp_path / "broken.json"
    broken.write_text("{not json")
    assert _percussim("run", str(broken), cwd=tmp_path).returncode == 2
    assert _percussim("run", "missing.json", cwd=tmp_path).returncode == 2


def test_files_are_written_even_when_stdout_closes_early(tmp_path):
    case = tmp_path / "case.json"
    case.write_text(json.dumps(merge(BASE_CASE, {"numerics": {"duration": 5e-4}})))
    reader = subprocess.Popen(
        [sys.executable, "-m", "percussim", "run", str(case), "--summary", "s.json", "--output", "r.h5"],
        cwd=tmp_path,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    reader.stdout.close()  # like `| head -0`: nobody reads the summary
    assert reader.wait(timeout=120) == 141, "as a process stopped by SIGPIPE"
    assert "Traceback" not in reader.stderr.read()
    assert json.loads((tmp_path / "s.json").read_text())["name"] == "test"
    with h5py.File(tmp_path / "r.h5") as f:
        assert "contact/force" in f


def test_model_lumped_runs_the_model_problem():
    done = _percussim("run", "fig3", "--model", "lumped", cwd=ROOT)
    assert done.returncode == 0, done.stderr
    summary = json.loads(done.stdout)
    assert summary["model"] == "lumped" and summary["numerics"]["cells"] == 0
    # The rigid tool (133 kg) makes a shorter, harder contact than the elastic rod's 335 µs.
    assert 2.5e-4 < summary["co_impact_time"] < 3.2e-4
    assert summary["scheme"] == "dop853" and "'lumped' as asked" in summary["why"]
    # Its stress is quasi-static: at the struck end the peak force over the area.
    assert summary["max_compressive_stress"]["value"] >= summary["peak_contact_force"]["value"] / 0.01421


def test_presets_are_listed_printed_and_written(tmp_path):
    listed = _percussim("presets", cwd=tmp_path)
    assert listed.returncode == 0, listed.stderr
    lines = listed.stdout.splitlines()
    assert [line.split()[0] for line in lines] == sorted(path.stem for path in PRESETS.glob("*.json"))
    assert lines[0].split(maxsplit=1)[1].startswith("Fig. 3 of the paper: a 20-kg striker")
    assert json.loads(_percussim("presets", "fig9", cwd=tmp_path).stdout) == json.loads(
        (PRESETS / "fig9.json").read_text()
    )
    assert _percussim("presets", "fig3", "-o", "f.json", cwd=tmp_path).returncode == 0
    assert json.loads((tmp_path / "f.json").read_text())["name"] == "fig3"
    assert _percussim("presets", "--write", "all", cwd=tmp_path).returncode == 0
    for path in PRESETS.glob("*.json"):
        assert json.loads((tmp_path / "all" / path.name).read_text()) == json.loads(path.read_text())
    unknown = _percussim("presets", "fig99", cwd=tmp_path)
    assert unknown.returncode == 2 and "unknown preset 'fig99'" in unknown.stderr


def test_run_progress_goes_to_stderr_and_stdout_stays_the_summary(tmp_path):
    forced = _percussim("run", str(PRESETS / "fig9.json"), "--progress", cwd=ROOT)
    assert forced.returncode == 0, forced.stderr
    assert json.loads(forced.stdout)["name"] == "fig9"
    assert "percussim: 100%|" in forced.stderr
    # Not a terminal, and short: no bar unless forced.
    quiet = _percussim("run", "fig9", cwd=ROOT)
    assert "%|" not in quiet.stderr and json.loads(quiet.stdout) == json.loads(forced.stdout)


def test_a_bad_setting_is_one_line_naming_the_variable_with_exit_2(tmp_path):
    """In `run`, `serve` and `worker` alike: no traceback, the variable, its value and what it
    accepts; whole numbers may be written as 1e8."""
    import os

    def percussim(env: dict, *args):
        return subprocess.run(
            [sys.executable, "-m", "percussim", *args],
            cwd=tmp_path,
            capture_output=True,
            text=True,
            env={**os.environ, "PERCUSSIM_RESULTS_DIR": str(tmp_path), **env},
            timeout=120,
        )

    for command in (["run", "fig3"], ["serve", "--port", "1"], ["worker"]):
        done = percussim({"PERCUSSIM_MAX_STEPS": "1e8.5", "PERCUSSIM_MAX_NODE_STEPS": "lots"}, *command)
        assert done.returncode == 2, (command, done.stderr)
        assert done.stderr.splitlines() == [
            "percussim: PERCUSSIM_MAX_STEPS=1e8.5: must be a whole number, as 20000000 or 2e7",
            "percussim: PERCUSSIM_MAX_NODE_STEPS=lots: must be a number, as 2e10",
        ], command
    refused = percussim({"PERCUSSIM_JOB_TIME_LIMIT": "-1"}, "serve", "--port", "1")
    assert (
        refused.returncode == 2 and refused.stderr == "percussim: PERCUSSIM_JOB_TIME_LIMIT=-1: must be greater than 0\n"
    )
    other = percussim({"PERCUSSIM_BROKER_URL": "amqp://guest@localhost//"}, "worker")
    assert other.returncode == 2 and other.stderr == (
        "percussim: PERCUSSIM_BROKER_URL=amqp://guest@localhost//: must be a Redis URL (redis://host:6379/0, "
        "rediss://, redis+socket:// or sentinel://), or unset for the embedded queue\n"
    )
    # 1e8 and 1e3 are whole numbers: the limit applies (fig3 on the paper's grid takes 4820 steps)
    assert percussim({"PERCUSSIM_MAX_STEPS": "1e8"}, "run", "fig3").returncode == 0
    small = percussim({"PERCUSSIM_MAX_STEPS": "1e3"}, "run", "fig3")
    assert small.returncode == 2 and "exceed the limit of 1000 (PERCUSSIM_MAX_STEPS raises it)" in small.stderr


def test_ctrl_c_during_a_submission_takes_effect_once_the_answer_is_in():
    """The client's submission to a service is not cut by Ctrl-C: the answer, which names the job
    to cancel, is kept, then KeyboardInterrupt comes, and Ctrl-C is Python's own again."""
    from percussim.cli import _ctrl_c_after_the_answer

    answered = []
    with pytest.raises(KeyboardInterrupt), _ctrl_c_after_the_answer():
        signal.raise_signal(signal.SIGINT)
        answered.append({"id": "the job"})
    assert answered == [{"id": "the job"}]
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
