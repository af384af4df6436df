"""The Python client and `percussim submit` against the live stack (the real API and a real
embedded worker), and the client's handling of 401 and 503 against a stand-in transport."""

from __future__ import annotations

import csv
import json
import os
import signal
import stat
import subprocess
import sys

import h5py
import httpx
import numpy as np
import pytest
from conftest import CHATTERS, merge
from test_cli import _percussim
from test_live import LONG

from percussim.client import Client, JobFailed, NotFound, Refused, ServiceError, Unauthorized, Unavailable
from percussim.solver.case import load_case
from percussim.solver.io import read_result
from percussim.solver.presets import load_preset, preset_json
from percussim.solver.record import read_record
from percussim.solver.simulate import run_sweep, simulate
from percussim.solver.sweep import COLUMNS, Sweep
from percussim.testing.live_stack import ROOT, Stack, wait_for

pytestmark = pytest.mark.slow  # a live stack, a browser or the solver's full reports

BAD = {"contact": {"exponent": 0.9}, "striker": {"mass": 0}}


@pytest.fixture(scope="module")
def stack(tmp_path_factory):
    s = Stack(tmp_path_factory.mktemp("client"), None, workers=1)
    yield s
    s.stop()


@pytest.fixture
def api(stack):
    with Client(stack.url) as client:
        yield client


def test_a_preset_runs_to_the_local_summary_and_arrays(api, tmp_path):
    case = api.preset("fig9")
    assert case == preset_json("fig9")
    job = api.submit(case)
    assert job["status"] == "queued" and job["id"] in {j["id"] for j in api.jobs()}
    seen = []
    record = api.wait(job["id"], progress=lambda fraction, record: seen.append((fraction, record["status"])))
    assert record["status"] == "succeeded" and seen[-1] == (1.0, "succeeded")
    assert [f for f, _ in seen] == sorted(f for f, _ in seen)
    direct = simulate(load_preset("fig9"))
    summary = api.summary(job["id"])
    assert summary["co_impact_time"] == direct.summary["co_impact_time"]
    assert summary["peak_contact_force"] == direct.summary["peak_contact_force"]

    result = api.result(job["id"])
    force = result.history["contact/force"]
    assert force.shape == direct.history["contact/force"].shape == (direct.numerics.steps + 1,)
    np.testing.assert_array_equal(force, direct.history["contact/force"])
    np.testing.assert_array_equal(result.probe_stress, direct.probe_stress)
    # The summary's peak is refined between time steps (a parabola's vertex): a little above the samples'.
    assert force.max() <= summary["peak_contact_force"]["value"] == pytest.approx(force.max(), rel=1e-4)
    assert result.summary == summary and result.case == load_preset("fig9")

    old_umask = os.umask(0o022)
    try:
        path = api.download(job["id"], tmp_path / "out" / "fig9.h5")
    finally:
        os.umask(old_umask)
    assert sorted(p.name for p in path.parent.iterdir()) == ["fig9.h5"]  # no partial file left
    assert stat.S_IMODE(path.stat().st_mode) == 0o644  # the umask's permissions, not owner-only
    with h5py.File(path) as f:
        assert f.attrs["format"] == "percussim-result" and f["contact/force"].attrs["units"] == "N"
    np.testing.assert_array_equal(read_result(path).history["contact/force"], force)


def test_a_case_file_and_a_case_object_are_submitted_as_they_are(api, tmp_path):
    assert api.run(ROOT / "solver" / "presets" / "fig3.json") == api.run(
        load_case(ROOT / "solver" / "presets" / "fig3.json")
    )
    broken = tmp_path / "broken.json"
    broken.write_text("{not json")
    with pytest.raises(Refused) as refused:
        api.submit(str(broken))
    assert refused.value.errors[0].field == "body" and "not valid JSON" in str(refused.value)


def test_an_invalid_case_raises_naming_every_field(api):
    with pytest.raises(Refused) as refused:
        api.submit(merge(preset_json("fig3"), BAD))
    assert refused.value.status == 422
    assert ("contact.exponent", "must be ≤ 0.5") in refused.value.errors
    assert "contact.exponent: must be ≤ 0.5" in str(refused.value)
    assert "striker.mass: must be > 0" in str(refused.value)


def test_a_failed_job_raises_with_its_reason(api):
    with pytest.raises(JobFailed) as failed:
        api.run(CHATTERS)
    assert failed.value.record["status"] == "failed"
    assert "the contact chattered" in str(failed.value) and "numerics.cells only" in str(failed.value)
    with pytest.raises(ServiceError, match="failed, so it has no summary: .*chattered") as conflict:
        api.summary(failed.value.record["id"])
    assert conflict.value.status == 409
    with pytest.raises(NotFound, match="no job with id 'nope'"):
        api.job("nope")
    with pytest.raises(NotFound, match="unknown preset 'nope'"):
        api.preset("nope")


def test_a_running_job_reports_its_progress_and_is_cancelled(api):
    job = api.submit(merge(preset_json("fig3"), LONG))
    seen, cancels = [], []

    def watch(fraction, record):
        seen.append(fraction)
        if record["status"] == "running" and fraction > 0 and not cancels:
            cancels.append(api.cancel(job["id"]))

    with pytest.raises(JobFailed, match=f"job {job['id']} was cancelled") as cancelled:
        api.wait(job["id"], progress=watch, poll=0.05, timeout=60)
    assert cancelled.value.record["status"] == "cancelled"
    assert seen == sorted(seen) and 0 < seen[-1] < 1, seen
    with pytest.raises(ServiceError, match="has already finished: it is cancelled"):
        api.cancel(job["id"])


def test_a_sweep_runs_to_the_table_a_local_sweep_gives(api, tmp_path):
    parameters = {"striker.velocity": [3.0, 7.0], "contact.stiffness": [4e11, 8e11]}
    path = tmp_path / "fig5.json"
    path.write_text(json.dumps(preset_json("fig5")))
    seen = []
    rows = api.run_sweep(path, parameters, progress=lambda fraction, sweep: seen.append(fraction), timeout=60)
    local = run_sweep(Sweep(case=load_preset("fig5"), parameters=parameters), processes=1)
    assert [row["values"] for row in rows] == [{k: row[k] for k in parameters} for row in local]
    for row, expected in zip(rows, local):
        assert row["status"] == "succeeded"
        for column, _ in COLUMNS:
            assert row[column] == expected[column], column
    assert seen == sorted(seen) and seen[-1] == 1.0


def test_a_sweep_with_a_bad_value_is_refused_naming_it(api):
    with pytest.raises(Refused) as refused:
        api.submit_sweep(preset_json("fig5"), {"contact.exponent": [0.5, 0.9]})
    [e] = refused.value.errors
    assert e.field == "parameters['contact.exponent'][1]" and "contact.exponent" in e.message


def test_a_sweep_is_cancelled_and_its_rows_say_so(api):
    sweep = api.submit_sweep(merge(preset_json("fig3"), LONG), {"striker.velocity": [4.0, 5.0]})
    api.cancel_sweep(sweep["id"])
    done = api.wait_sweep(sweep["id"], poll=0.05, timeout=60)
    assert done["finished"] and done["counts"] == {"cancelled": 2}, done
    assert [row["status"] for row in done["rows"]] == ["cancelled", "cancelled"]


def test_sweep_url_runs_the_variants_on_the_service_into_the_same_table(stack, tmp_path):
    case = tmp_path / "fig5.json"
    case.write_text(json.dumps(preset_json("fig5")))
    vary = ["--vary", "striker.velocity=3,5", "--vary", "contact.stiffness=8e11"]
    here = _percussim("sweep", str(case), *vary, "--processes", "1", cwd=tmp_path)
    there = _percussim("sweep", str(case), *vary, "--url", stack.url, "--csv", "t.csv", cwd=tmp_path)
    assert here.returncode == 0 and there.returncode == 0, there.stderr
    assert "2/2 variants" in there.stderr

    def table(printed: str) -> list[dict]:
        header, *rows = printed.splitlines()
        return [dict(zip(header.split("\t"), row.split("\t"))) for row in rows]

    local, remote = table(here.stdout), table(there.stdout)
    assert [r["status"] for r in remote] == ["succeeded", "succeeded"] and all(r["job"] for r in remote)
    for mine, theirs in zip(local, remote, strict=True):
        assert {k: theirs[k] for k in mine} == mine  # the service's rows carry the job and status too
    assert list(csv.DictReader((tmp_path / "t.csv").open()))[1]["striker.velocity"] == "5"
    refused = _percussim("sweep", str(case), "--vary", "contact.exponent=0.5,0.9", "--url", stack.url, cwd=tmp_path)
    assert refused.returncode == 2
    assert "parameters['contact.exponent'][1]" in refused.stderr


def test_submit_prints_the_summary_and_downloads_the_result(stack, tmp_path):
    case = tmp_path / "case.json"
    case.write_text(json.dumps(preset_json("fig3")))
    done = _percussim("submit", str(case), "--url", stack.url, "--summary", "s.json", "--output", "r.h5", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    printed = json.loads(done.stdout)
    assert json.loads((tmp_path / "s.json").read_text()) == printed
    assert printed["co_impact_time"] == simulate(load_preset("fig3")).summary["co_impact_time"]
    assert read_result(tmp_path / "r.h5").summary == printed
    queued = _percussim("submit", str(case), "--url", stack.url, "--no-wait", cwd=tmp_path)
    assert json.loads(queued.stdout)["status"] == "queued"


def test_submit_exits_2_naming_the_field_and_1_with_a_failed_jobs_reason(stack, tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(merge(preset_json("fig3"), BAD)))
    refused = _percussim("submit", str(bad), "--url", stack.url, cwd=tmp_path)
    assert refused.returncode == 2 and refused.stdout == ""
    assert f"percussim: invalid case {bad}:\n" in refused.stderr
    assert "  contact.exponent: must be ≤ 0.5\n" in refused.stderr
    chatters = tmp_path / "chatters.json"
    chatters.write_text(json.dumps(CHATTERS))
    failed = _percussim("submit", str(chatters), "--url", stack.url, cwd=tmp_path)
    assert failed.returncode == 1 and failed.stdout == ""
    assert "failed: " in failed.stderr and "the contact chattered" in failed.stderr


def test_ctrl_c_during_submit_cancels_the_job_on_the_service(stack, tmp_path):
    case = tmp_path / "long.json"
    case.write_text(json.dumps(merge(preset_json("fig3"), LONG)))
    # SIGINT at its default in the child, as in a terminal: a shell's background job inherits it
    # ignored, and Python then never turns it into KeyboardInterrupt.
    submit = subprocess.Popen(
        [sys.executable, "-m", "percussim", "submit", str(case), "--url", stack.url],
        cwd=tmp_path,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    try:

        def newest_running():  # the job just submitted is the newest
            jobs = stack.client.get("/v1/jobs", params={"limit": 1}).json()["jobs"]
            return jobs[0] if jobs and jobs[0]["status"] == "running" and jobs[0]["name"] == "fig3" else None

        job = wait_for(newest_running, 30, "the submitted job running")
        submit.send_signal(signal.SIGINT)
        out, err = submit.communicate(timeout=30)
    finally:
        submit.kill()
    assert submit.returncode == 130 and out == "", err
    assert f"percussim: cancelled job {job['id']}" in err
    assert stack.wait_status(job["id"], ("cancelled", "succeeded", "failed"))["status"] == "cancelled"


@pytest.mark.parametrize("when", ["recorded", "running"])
def test_ctrl_c_during_a_sweep_on_the_service_cancels_its_variants(stack, tmp_path, when):
    """Ctrl-C once a variant runs, or as soon as the service has recorded one: often before the
    sweep's id has reached the client, which then cancels it once it has."""
    case = tmp_path / "long.json"
    case.write_text(json.dumps(merge(preset_json("fig3"), LONG)))
    sweep = subprocess.Popen(
        [sys.executable, "-m", "percussim", "sweep", str(case), "--vary", "striker.velocity=4,5", "--url", stack.url],
        cwd=tmp_path,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    try:
        statuses = ("queued", "running") if when == "recorded" else ("running",)

        def a_variant():
            jobs = stack.client.get("/v1/jobs", params={"limit": 2}).json()["jobs"]
            return any(j["status"] in statuses and j["name"] == "fig3" for j in jobs)

        wait_for(a_variant, 30, f"a variant {when}", interval=0.01)
        sweep.send_signal(signal.SIGINT)
        out, err = sweep.communicate(timeout=30)
    finally:
        sweep.kill()
    assert sweep.returncode == 130 and out == "", err
    sweep_id = err.split("percussim: cancelled sweep ")[1].split()[0]
    done = wait_for(
        lambda: (v := stack.client.get(f"/v1/sweeps/{sweep_id}").json())["finished"] and v,
        30,
        "the sweep's variants ended",
    )
    assert done["counts"] == {"cancelled": 2}, done


def _csv_record(path, quantity: str, stretch: float = 1.0):
    """A σ-scheme record with noise (see test_calibrate) written to `path` as CSV, its times
    multiplied by `stretch` (1000: milliseconds given as seconds)."""
    from test_calibrate import other_setting_record

    from percussim.solver.record import parse_record, record_to_csv

    record = other_setting_record(quantity)
    record["time"] = [t * stretch for t in record["time"]]
    path.write_text(record_to_csv(parse_record(record)))
    return path


def test_a_calibration_from_a_csv_file_gives_the_local_fit(api, tmp_path):
    """The client reads the CSV record, the service's workers fit it: the same fit, number for
    number, as `percussim.calibrate` here (both are deterministic: a seeded global stage)."""
    from test_calibrate import BOUNDS, TRUE, start_case

    from percussim.solver.calibrate import calibrate

    names = ("contact.stiffness", "medium.stiffness")
    request = {
        "case": start_case(names),
        "record": str(_csv_record(tmp_path / "record.csv", "stress")),
        "parameters": {n: BOUNDS[n] for n in names},
    }
    seen = []
    fit = api.calibrate(request, progress=lambda fraction, study: seen.append(study["kind"]))
    assert seen and set(seen) == {"calibration"}
    here = calibrate(request | {"record": read_record(request["record"])}, processes=1)
    for name in names:
        assert fit["parameters"][name] == pytest.approx(here["parameters"][name], rel=1e-9)
        assert fit["parameters"][name]["value"] == pytest.approx(TRUE[name], rel=0.05)
    assert fit["evaluations"] == here["evaluations"] and fit["warnings"] == here["warnings"]
    late = _csv_record(tmp_path / "late.csv", "stress", stretch=1e3)
    with pytest.raises(Refused) as refused:
        api.submit_calibration(request | {"record": late})
    assert refused.value.status == 422 and refused.value.errors[0].field == "record.time"


def test_calibrate_and_optimize_url_print_what_they_print_here(stack, tmp_path):
    """`--url` runs the study on the service's workers: the same printed answer as a local run;
    a record the service refuses exits 2 naming its field."""
    from test_calibrate import start_case
    from test_optimize import short_rock_drill

    (tmp_path / "case.json").write_text(json.dumps(start_case(("contact.stiffness",))))
    (tmp_path / "drill.json").write_text(json.dumps(short_rock_drill()))
    _csv_record(tmp_path / "record.csv", "contact_force")
    _csv_record(tmp_path / "late.csv", "contact_force", stretch=1e3)
    fit = ["calibrate", "case.json", "--record", "record.csv", "--fit", "contact.stiffness=1e9:1e15"]
    optimise = [
        "optimize",
        "drill.json",
        "--vary",
        "striker.length=0.1:0.6",
        "--maximize",
        "energy.to_medium",
        "--limit",
        "max_compressive_stress<=250e6",
        "--evaluations",
        "40",
    ]
    printed = {}
    for name, arguments in (("fit", fit), ("optimum", optimise)):
        here = _percussim(*arguments, "--processes", "1", cwd=tmp_path)
        there = _percussim(*arguments, "--url", stack.url, "--plot", f"{name}.svg", cwd=tmp_path)
        assert here.returncode == 0 and there.returncode == 0, there.stderr
        printed[name] = json.loads(here.stdout), json.loads(there.stdout)
        assert printed[name][0].keys() == printed[name][1].keys()
        assert (tmp_path / f"{name}.svg").read_text().startswith("<?xml")
    local, remote = printed["fit"]
    assert remote["parameters"]["contact.stiffness"] == pytest.approx(local["parameters"]["contact.stiffness"])
    assert remote["evaluations"] == local["evaluations"]
    local, remote = printed["optimum"]
    assert remote["values"] == pytest.approx(local["values"]) and remote["stopped"] == local["stopped"]
    assert remote["quantities"]["max_compressive_stress"] <= 250e6
    refused = _percussim(*fit[:3], "late.csv", *fit[4:], "--url", stack.url, cwd=tmp_path)
    assert refused.returncode == 2 and refused.stdout == "", refused.stderr
    assert "percussim: invalid calibration of case.json:\n  record.time: " in refused.stderr


def _stand_in(*answers: httpx.Response) -> tuple[Client, list[httpx.Request]]:
    """A client whose calls get `answers` in turn, and the requests it made."""
    requests = []

    def answer(request: httpx.Request) -> httpx.Response:
        requests.append(request)
        return answers[len(requests) - 1]

    return Client("http://percussim.test", api_key="k1", retries=2, transport=httpx.MockTransport(answer)), requests


def test_a_503_is_retried_after_its_retry_after_a_bounded_number_of_times():
    down = httpx.Response(503, headers={"Retry-After": "0"}, json={"detail": "the job queue is unavailable"})
    client, requests = _stand_in(down, down, httpx.Response(202, json={"id": "j1", "status": "queued"}))
    assert client.submit(preset_json("fig3"))["id"] == "j1"
    assert len(requests) == 3 and all(json.loads(r.content) == preset_json("fig3") for r in requests)
    client, requests = _stand_in(down, down, down, down)
    with pytest.raises(Unavailable, match="the job queue is unavailable"):
        client.job("j1")
    assert len(requests) == 3  # the call and its 2 retries


def test_the_key_is_sent_and_a_401_says_so():
    client, requests = _stand_in(httpx.Response(401, json={"detail": "this service needs an API key"}))
    with pytest.raises(Unauthorized, match="needs an API key") as refused:
        client.presets()
    assert refused.value.status == 401 and requests[0].headers["X-API-Key"] == "k1"


def test_the_client_imports_without_the_service_or_the_solver():
    loaded = subprocess.run(
        [sys.executable, "-c", "import sys, percussim.client; print(*sorted(sys.modules))"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=True,
    ).stdout.split()
    assert not {"fastapi", "celery", "numba", "numpy", "percussim.solver", "percussim.service"} & set(loaded)


def test_the_worked_example_runs_a_preset_and_downloads_its_result(stack, tmp_path):
    """examples/submit.py, as `scripts/run` runs it."""
    output = tmp_path / "fig3.h5"
    done = subprocess.run(
        [sys.executable, "examples/submit.py", "--url", stack.url, "--preset", "fig3", "--output", str(output)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 0, done.stderr
    assert "succeeded" in done.stdout and f"result written to {output}" in done.stdout
    # the answer shown and downloaded is the trusted one: the default accuracy, its estimate within it
    summary = read_result(output).summary
    assert summary["name"] == "fig3" and summary["tolerance"] == 0.01 and summary["scheme"] == "explicit"
    assert summary["error_estimate"]["worst"] <= 0.01 and not summary["warnings"]
    # beside it, the paper's numerics: each quantity with its estimate, what each cost and lost
    table = done.stdout[done.stdout.index("default accuracy (1%)") :]
    for line in (
        "peak contact force (kN)",
        "energy to the medium (J)",
        "work",
        "job time",
        "energy lost by the scheme",
    ):
        assert line in table
    assert "the paper's numerics warn:" in done.stdout and "estimated errors over 1%" in done.stdout


def test_a_signal_match_from_a_csv_record_gives_the_local_match(api, tmp_path):
    """The client reads the head's CSV record, the service's workers match it: the same match,
    number for number, as `percussim.signal_match` here (a seeded global stage). Gauges off the
    pile are refused, naming the field."""
    from test_signal_match import RESISTANCES, guessed

    from percussim.solver.signal_match import signal_match
    from percussim.testing.pile_records import head_record, pile

    record = head_record(pile())
    rows = "\n".join(f"{t!r},{f!r},{v!r}" for t, f, v in zip(record["time"], record["force"], record["velocity"]))
    (tmp_path / "blow.csv").write_text("time,force@0,velocity@0\n" + rows + "\n")
    request = {"case": guessed(), "record": str(tmp_path / "blow.csv"), "parameters": RESISTANCES}
    match = api.match(request)
    here = signal_match(request | {"record": record}, processes=1)
    for name in RESISTANCES:
        assert match["parameters"][name] == pytest.approx(here["parameters"][name], rel=1e-9)
    assert match["capacity"] == pytest.approx(here["capacity"], rel=1e-9)
    assert match["evaluations"] == here["evaluations"] and match["warnings"] == here["warnings"]
    with pytest.raises(Refused) as refused:
        api.submit_signal_match(request | {"record": record | {"x": 12.0}})
    assert refused.value.status == 422 and refused.value.errors[0].field == "record.x"
    # `percussim match --url`: the same match through the command line, its plot drawn from it
    (tmp_path / "pile.json").write_text(json.dumps(guessed()))
    fits = [arg for path, (low, high) in RESISTANCES.items() for arg in ("--fit", f"{path}={low}:{high}")]
    there = _percussim(
        "match", "pile.json", "--record", "blow.csv", *fits, "--url", api.url, "--plot", "m.svg", cwd=tmp_path
    )
    assert there.returncode == 0, there.stderr
    assert json.loads(there.stdout)["capacity"] == pytest.approx(here["capacity"], rel=1e-9)
    assert (tmp_path / "m.svg").read_text().startswith("<?xml")
