"""The docker-compose deployment, built and run for real: docker/Dockerfile built on a Python base
made from Debian's packages (scripts/local-images), then docker/docker-compose.yml started with
the API, two workers, Redis, PostgreSQL and Flower, every service on the host's network on its
own loopback port (docker/docker-compose.loopback.yml).

The tests share one stack and run in order: what the stack serves is checked against the
command line, then a worker is killed mid-job, then the API is restarted; the last test takes
the stack down and checks that nothing of it is left.
"""

from __future__ import annotations

import io
import json
import os
import socket
import subprocess
import sys
from pathlib import Path

import h5py
import httpx
import numpy as np
import pytest
from conftest import LONG_WORK, SECONDS_OF_WORK, report, running_again

from percussim.client import FINISHED
from percussim.solver.presets import preset_json
from percussim.testing.compose_stack import IMAGE, WORKERS, ComposeStack, docker, local_images, require_docker
from percussim.testing.live_stack import wait_for

pytestmark = pytest.mark.slow  # an image build and a stack of six containers

SWEEP = {"case": preset_json("fig5"), "parameters": {"striker.velocity": [3, 7], "contact.stiffness": [4e11, 8e11]}}
NUMBA_CACHE = "/var/cache/percussim/numba"
IMAGE_CPU = "generic"  # the image's NUMBA_CPU_NAME (docker/Dockerfile), checked against the built image
TIMES: dict[str, float] = {}


def interfaces() -> set[str]:
    return {name for _, name in socket.if_nameindex()}


@pytest.fixture(scope="module")
def stack():
    try:
        require_docker()
    except RuntimeError as error:
        pytest.fail(str(error))  # not a skip: scripts/test installs and starts what this needs
    TIMES["local images"] = local_images()
    before = (interfaces(), docker("network", "ls", "-q").split())
    # A short time limit, so that the job of a killed worker is delivered again within seconds;
    # a short grace, so that a worker stopped mid-job stops it within seconds.
    s = ComposeStack(
        {"PERCUSSIM_JOB_TIME_LIMIT": "10", "PERCUSSIM_REDELIVERY_SECONDS": "12", "PERCUSSIM_STOP_GRACE": "1"}
    )
    s.before = before
    s.stopped = False
    try:
        TIMES["build"] = s.build()
        TIMES["start"] = s.up()
        yield s
    except BaseException:
        print(s.logs())
        raise
    finally:
        if not s.stopped:
            s.down()


def submit(stack: ComposeStack, case: dict) -> str:
    answer = stack.client.post("/v1/jobs", json=case)
    assert answer.status_code == 202, answer.text
    return answer.json()["id"]


def wait_finished(stack: ComposeStack, job_id: str, timeout: float = 120) -> dict:
    def finished():
        record = stack.client.get(f"/v1/jobs/{job_id}").json()
        return record if record["status"] in FINISHED else None

    return wait_for(finished, timeout, f"job {job_id} finished", interval=0.3)


@pytest.fixture(scope="module")
def image_target(stack, tmp_path_factory) -> dict[str, str]:
    """The image's Numba CPU target, and the kernel the image compiled for it, copied out into a
    cache folder here (a cache is named by its sources, not by where they are): the CLI here runs
    the machine code the containers run. The image compiles for a generic CPU, so that no
    container compiles again; this machine's own target may contract multiplies and adds into
    FMAs and round differently in the last digits."""
    env = dict(e.split("=", 1) for e in stack.inspect(IMAGE)[0]["Config"]["Env"])
    assert env["NUMBA_CPU_NAME"] == IMAGE_CPU and env["NUMBA_CACHE_DIR"] == NUMBA_CACHE
    folder = tmp_path_factory.mktemp("numba")
    container = docker("create", IMAGE).strip()
    try:
        docker("cp", f"{container}:{NUMBA_CACHE}/.", str(folder))
    finally:
        docker("rm", container)
    return {"NUMBA_CPU_NAME": IMAGE_CPU, "NUMBA_CACHE_DIR": str(folder)}


def cli_run(case: dict, folder: Path, env: dict[str, str] | None = None) -> tuple[dict, Path]:
    """The summary and result file of `percussim run` on this machine, as a user runs it."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "case.json").write_text(json.dumps(case))
    subprocess.run(
        [sys.executable, "-m", "percussim", "run", "case.json", "--summary", "s.json", "--output", "r.h5"],
        cwd=folder,
        env=os.environ | (env or {}),
        check=True,
        capture_output=True,
        timeout=300,
    )
    return json.loads((folder / "s.json").read_text()), folder / "r.h5"


def test_every_service_is_on_loopback_alone(stack):
    containers = stack.containers()
    services = {c["Config"]["Labels"]["com.docker.compose.service"]: c for c in stack.inspect(*containers)}
    assert set(services) == {"redis", "postgres", "api", "worker", "worker-2", "flower"}
    for name, c in services.items():
        assert c["HostConfig"]["NetworkMode"] == "host", name
        addresses = [n.get("IPAddress") for n in c["NetworkSettings"]["Networks"].values()]
        assert set(c["NetworkSettings"]["Networks"]) == {"host"} and not any(addresses), (name, addresses)
    interfaces_before, networks_before = stack.before
    assert interfaces() == interfaces_before, "no bridge or veth interface was made"
    assert docker("network", "ls", "-q").split() == networks_before, "no network was made"
    # Every service listens on 127.0.0.1 alone, on its own port (the host's table: its network).
    listening = {}
    for table in ("/proc/net/tcp", "/proc/net/tcp6"):
        for line in Path(table).read_text().splitlines()[1:]:
            local, state = line.split()[1], line.split()[3]
            address, port = local.rsplit(":", 1)
            if state == "0A" and int(port, 16) in stack.ports.values():
                listening.setdefault(int(port, 16), set()).add(address)
    assert set(listening) == set(stack.ports.values()), (listening, stack.ports)
    assert all(addresses == {"0100007F"} for addresses in listening.values()), listening
    assert stack.url.startswith("http://127.0.0.1:") and stack.flower_url.startswith("http://127.0.0.1:")


def test_the_image_as_built(stack):
    """What the Dockerfile sets, read from the built image: an unprivileged user, the results and
    kernel cache folders it owns, the API's command, port and health check."""
    (image,) = stack.inspect(IMAGE)
    config = image["Config"]
    assert config["User"] not in ("", "root", "0"), config["User"]
    assert config["Cmd"] == ["percussim", "serve", "--host", "0.0.0.0", "--port", "8000"]
    assert "8000/tcp" in config["ExposedPorts"]
    assert "/healthz" in " ".join(config["Healthcheck"]["Test"])
    env = dict(e.split("=", 1) for e in config["Env"])
    assert env["PERCUSSIM_RESULTS_DIR"] == "/data" and env["NUMBA_CACHE_DIR"] == NUMBA_CACHE
    owners = docker("run", "--rm", "--network", "none", IMAGE, "stat", "-c", "%U", "/data", NUMBA_CACHE, "/opt/venv")
    assert owners.split() == [config["User"], config["User"], "root"], "the environment is read-only for the user"


def test_a_preset_gives_the_clis_summary_and_result(stack, image_target, tmp_path, record_property):
    job_id = submit(stack, preset_json("fig3"))
    record = wait_finished(stack, job_id)
    assert record["status"] == "succeeded", (record, stack.logs())
    summary = stack.client.get(f"/v1/jobs/{job_id}/summary").json()
    cli, result = cli_run(preset_json("fig3"), tmp_path / "image-target", image_target)
    assert summary == cli, "the stack's summary differs from `percussim run`'s"
    download = stack.client.get(f"/v1/jobs/{job_id}/result.h5")
    assert download.status_code == 200
    with h5py.File(io.BytesIO(download.content)) as served, h5py.File(result) as local:
        assert served.attrs["format"] == "percussim-result"
        for name in ("contact/force", "probes/stress"):
            np.testing.assert_array_equal(served[name][()], local[name][()])
    native, _ = cli_run(preset_json("fig3"), tmp_path / "native")
    peak = [s["peak_contact_force"]["value"] for s in (summary, cli, native)]
    report(
        record_property,
        f"\nfig3 peak force: {peak[0]!r} N in the containers, {peak[1]!r} N by `percussim run` here "
        f"for the image's CPU target ({image_target['NUMBA_CPU_NAME']}): every value of the summary equal; "
        f"{peak[2]!r} N for this CPU's own target (relative difference {abs(peak[2] / peak[0] - 1):.1e})",
    )


def test_a_sweep_gives_the_clis_summary_for_every_variant(stack, image_target, tmp_path, record_property):
    answer = stack.client.post("/v1/sweeps", json=SWEEP)
    assert answer.status_code == 202, answer.text
    sweep_id = answer.json()["id"]
    sweep = wait_for(
        lambda: (v := stack.client.get(f"/v1/sweeps/{sweep_id}").json())["finished"] and v, 180, "the sweep"
    )
    assert sweep["counts"] == {"succeeded": 4}, sweep
    for k, row in enumerate(sweep["rows"]):
        case = stack.client.get(f"/v1/jobs/{row['job']}/case").json()
        cli, _ = cli_run(case, tmp_path / str(k), image_target)
        assert stack.client.get(f"/v1/jobs/{row['job']}/summary").json() == cli, row["values"]
    report(
        record_property,
        f"sweep of {len(sweep['rows'])} variants over 2 workers: every summary equal to `percussim run`'s",
    )


def test_no_container_compiles_the_kernel(stack):
    """The kernel was compiled into the image's Numba cache at build time: after the jobs above,
    no worker has added or changed anything there."""
    for service in WORKERS:
        changed = [line for line in docker("diff", stack.container(service)).splitlines() if NUMBA_CACHE in line]
        assert not changed, (service, changed)
    check = (
        "from percussim.solver import kernel; from percussim.solver.controller import warm_up; warm_up(); "
        "s = kernel.advance.stats; print(sum(s.cache_hits.values()), sum(s.cache_misses.values()))"
    )
    out = docker("run", "--rm", "--network", "none", IMAGE, "python", "-c", check)
    assert out.split() == ["1", "0"], f"a new container's first run: {out}"


def a_job_running(stack: ComposeStack, case: dict = SECONDS_OF_WORK) -> tuple[str, str, str]:
    """A job of `case` submitted and running, a tenth done: its id, its worker and that worker's
    compose service."""
    job_id = submit(stack, case)
    wait_for(
        lambda: (r := stack.client.get(f"/v1/jobs/{job_id}").json())["status"] == "running" and r["progress"] > 0.1,
        60,
        "the job running",
        interval=0.1,
    )
    worker = stack.client.get(f"/v1/jobs/{job_id}").json()["worker"]
    return job_id, worker, {name: s for s, name in WORKERS.items()}[worker]


def test_a_worker_killed_mid_job_gets_it_delivered_again_and_it_succeeds_once(stack, record_property):
    job_id, victim, service = a_job_running(stack)
    docker("kill", stack.container(service))  # SIGKILL: the worker and its pool, no chance to clean up
    record = wait_finished(stack, job_id, timeout=120)
    assert record["status"] == "succeeded", (record, stack.logs())
    assert record["attempts"] == 2, record
    assert stack.client.get(f"/v1/jobs/{job_id}/summary").status_code == 200
    jobs = stack.client.get("/v1/jobs", params={"limit": 100}).json()["jobs"]
    assert [j["id"] for j in jobs].count(job_id) == 1
    report(
        record_property,
        f"killed {victim} mid-job: the job then {record['status']} on {record['worker']} "
        f"after {record['attempts']} attempts",
    )


def test_a_worker_container_stopped_mid_job_hands_the_job_back_and_exits_by_itself(stack, record_property):
    """`docker stop` of a worker mid-job: after its grace (`PERCUSSIM_STOP_GRACE`, 1 s here, 50 s
    in the compose file) the worker stops the job and exits by itself, status 0, long before
    Docker would kill it; the job goes back on the queue and the other worker takes it at once."""
    for service in WORKERS:  # both up, the one killed above too (a no-op for a running container)
        docker("start", stack.container(service))
    stack.wait_ready()
    job_id, stopped, service = a_job_running(stack, LONG_WORK)
    container = stack.container(service)
    docker("stop", "--time", "60", container)
    (state,) = stack.inspect(container)
    logs = subprocess.run(["docker", "logs", container], capture_output=True, text=True).stderr
    assert state["State"]["ExitCode"] == 0, (state["State"], logs[-3000:])
    assert f"the running job {job_id} outlasted PERCUSSIM_STOP_GRACE (1 s)" in logs, logs[-3000:]
    try:
        record = running_again(stack.client, job_id)
    except TimeoutError as error:  # what the broker and the containers saw, for the next one to read
        raise AssertionError(f"{error}; {stack.broker_state()}\n{stack.logs()}") from error
    assert record["worker"] != stopped, record
    assert stack.client.delete(f"/v1/jobs/{job_id}").status_code == 202
    assert wait_finished(stack, job_id)["status"] == "cancelled"
    docker("start", container)
    stack.wait_ready()
    report(
        record_property,
        f"docker stop of {stopped} mid-job: it exited with status 0 after its grace; the job then "
        f"ran again on {record['worker']}, attempt {record['attempts']}",
    )


def test_after_the_api_container_restarts_every_record_and_result_is_served(stack, record_property):
    ids = [j["id"] for j in stack.client.get("/v1/jobs", params={"limit": 100}).json()["jobs"]]
    ids = ids or [submit(stack, preset_json("fig3"))]
    for job_id in ids:
        wait_finished(stack, job_id)

    def served(job_id: str) -> tuple:
        record = stack.client.get(f"/v1/jobs/{job_id}").json()
        if record["status"] != "succeeded":
            return (record,)
        return (
            record,
            stack.client.get(f"/v1/jobs/{job_id}/summary").json(),
            stack.client.get(f"/v1/jobs/{job_id}/result.h5").content,
        )

    before = {job_id: served(job_id) for job_id in ids}
    api = stack.container("api")
    started = stack.inspect(api)[0]["State"]["StartedAt"]
    docker("restart", api)
    assert stack.inspect(api)[0]["State"]["StartedAt"] != started
    wait_for(lambda: stack.client.get("/healthz").status_code == 200, 60, "the restarted API", interval=0.3)
    for job_id, was in before.items():
        assert served(job_id) == was, job_id
    assert stack.client.get("/v1/jobs").json()["total"] == len(ids)
    report(record_property, f"API container restarted: {len(ids)} records, summaries and results served as before")


def test_metrics_and_flower(stack):
    metrics = stack.client.get("/metrics")
    assert metrics.status_code == 200 and metrics.headers["content-type"].startswith("text/plain")
    assert 'percussim_jobs{status="succeeded"}' in metrics.text
    assert "percussim_job_duration_seconds_count" in metrics.text
    assert httpx.get(f"{stack.flower_url}/healthcheck", timeout=10).text == "OK"


def test_down_removes_every_container_volume_and_network(stack, record_property):
    stack.down()
    stack.stopped = True
    assert stack.left_behind() == {"containers": [], "volumes": [], "networks": []}
    assert interfaces() == stack.before[0]
    report(
        record_property,
        f"compose stack: local images {TIMES['local images']:.1f} s, image build {TIMES['build']:.1f} s, "
        f"start to /readyz with 2 workers {TIMES['start']:.1f} s",
    )
