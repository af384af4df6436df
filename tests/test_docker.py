"""The container files: docker/Dockerfile, docker/docker-compose.yml and .dockerignore, without
a Docker engine.

The image is built and the stack run for real in tests/test_compose.py, which covers what this
file used to read out of the Dockerfile by hand (its stages, user, copied paths, kernel cache,
command). What stays here: the public images are the defaults, the compose file as YAML (always)
and as `docker-compose config` resolves it (needs docker-compose, or the `docker compose`
plugin; the suite's setup installs it in CI, elsewhere that one test is skipped), the settings
the compose file suggests, and the health check commands run for real against a stand-in.
"""

from __future__ import annotations

import http.server
import json
import os
import re
import shlex
import socket
import subprocess
import sys
import threading
import tomllib
from fnmatch import fnmatch
from pathlib import Path

import pytest
import yaml

from percussim.testing.compose_stack import compose_command

ROOT = Path(__file__).resolve().parents[1]
DOCKERFILE = ROOT / "docker" / "Dockerfile"
COMPOSE = ROOT / "docker" / "docker-compose.yml"
DOCKERIGNORE = ROOT / ".dockerignore"
# The images users get unless they name others (the compose file's variables).
DEFAULT_IMAGES = {
    "BASE_IMAGE": "python:3.11-slim",
    "REDIS_IMAGE": "redis:7-alpine",
    "POSTGRES_IMAGE": "postgres:16-alpine",
    "FLOWER_IMAGE": "mher/flower:2.0",
}


def default(value: str) -> str:
    """A compose value with its `${NAME:-default}` variables replaced by their defaults."""
    return re.sub(r"\$\{[A-Z_]+:-([^}]*)\}", r"\1", value)


# ---------------------------------------------------------------------------------------------
# The Dockerfile


def test_the_base_image_is_a_build_argument_defaulting_to_the_slim_python_image():
    text = DOCKERFILE.read_text()
    assert f"\nARG BASE_IMAGE={DEFAULT_IMAGES['BASE_IMAGE']}\n" in text
    froms = re.findall(r"^FROM\s+(\S+)(?:\s+AS\s+(\S+))?", text, flags=re.MULTILINE | re.IGNORECASE)
    assert len(froms) >= 2 and all(base == "${BASE_IMAGE}" for base, _ in froms), froms


def test_a_non_editable_install_carries_the_job_page_and_the_presets():
    """`pip install .` copies only Python modules unless package data names the rest."""
    data = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["package-data"]
    for package, folder in (
        ("percussim.service", ROOT / "service"),
        ("percussim.solver.presets", ROOT / "solver" / "presets"),
    ):
        files = [
            p.relative_to(folder).as_posix()
            for p in folder.rglob("*")
            if p.is_file() and p.suffix != ".py" and "__pycache__" not in p.parts
        ]
        assert files and all(any(fnmatch(f, pattern) for pattern in data[package]) for f in files), (package, files)


def test_dockerignore_keeps_the_local_state_out():
    patterns = {p.strip().removeprefix("**/").rstrip("/") for p in DOCKERIGNORE.read_text().splitlines()}
    assert {".venv", "out", ".git", "__pycache__", "*.h5", "percussim-data"} <= patterns


# ---------------------------------------------------------------------------------------------
# The compose file


def as_list(command) -> list[str]:
    return shlex.split(command) if isinstance(command, str) else [str(w) for w in command]


def environment(service: dict) -> dict[str, str]:
    env = service.get("environment") or {}
    if isinstance(env, list):
        env = dict(item.split("=", 1) if "=" in item else (item, None) for item in env)
    return {k: (None if v is None else str(v)) for k, v in env.items()}


def mounts(service: dict) -> dict[str, str]:
    """Container path -> source of each volume."""
    out = {}
    for v in service.get("volumes") or []:
        if isinstance(v, str):
            source, target = v.split(":")[:2]
        else:
            source, target = v.get("source"), v["target"]
        out[target] = source
    return out


def published(service: dict) -> list[tuple[str, str]]:
    out = []
    for p in service.get("ports") or []:
        if isinstance(p, dict):
            out.append((str(p.get("published")), str(p["target"])))
        else:
            host, _, container = str(p).rpartition(":")
            out.append((host.rpartition(":")[2], container.split("/")[0]))
    return out


def depends(service: dict) -> dict[str, str]:
    d = service.get("depends_on") or {}
    if isinstance(d, list):
        return {name: "service_started" for name in d}
    return {name: (spec or {}).get("condition", "service_started") for name, spec in d.items()}


def healthcheck_test(service: dict) -> list[str]:
    test = (service.get("healthcheck") or {}).get("test")
    if isinstance(test, str):
        return ["CMD-SHELL", test]
    return [str(w) for w in test or []]


def check_stack(config: dict) -> None:
    services = config["services"]
    assert {"redis", "postgres", "api", "worker", "flower"} <= set(services)
    redis, api, worker = services["redis"], services["api"], services["worker"]
    declared = set(config.get("volumes") or {})
    assert {"results", "redis-data", "postgres-data"} <= declared

    # PostgreSQL: the job records, in a named volume, health-checked.
    postgres = services["postgres"]
    assert default(postgres["image"]) == DEFAULT_IMAGES["POSTGRES_IMAGE"]
    assert mounts(postgres).get("/var/lib/postgresql/data") == "postgres-data"
    assert "pg_isready" in " ".join(healthcheck_test(postgres))
    database = environment(postgres)["POSTGRES_DB"]

    # Flower, for the Celery side, on the same broker.
    flower = services["flower"]
    assert default(flower["image"]) == DEFAULT_IMAGES["FLOWER_IMAGE"] and ("5555", "5555") in published(flower)
    assert str(environment(flower)["CELERY_BROKER_URL"]).startswith("redis://redis:6379/")

    # Redis: persistent (append-only file in a named volume) and health-checked.
    assert default(redis["image"]) == DEFAULT_IMAGES["REDIS_IMAGE"]
    command = as_list(redis.get("command") or [])
    assert "--appendonly" in command and command[command.index("--appendonly") + 1] == "yes", command
    assert mounts(redis).get("/data") == "redis-data"
    test = " ".join(healthcheck_test(redis))
    assert "redis-cli" in test and "ping" in test

    # The API alone (workers are separate services), on port 8000.
    command = as_list(api["command"])
    assert command[:2] == ["percussim", "serve"] and "--no-worker" in command
    assert command[command.index("--host") + 1] == "0.0.0.0" and command[command.index("--port") + 1] == "8000"
    assert ("8000", "8000") in published(api)
    assert any(path in " ".join(healthcheck_test(api)) for path in ("/healthz", "/readyz"))

    # Workers: scalable replicas.
    command = as_list(worker["command"])
    assert command[:2] == ["percussim", "worker"]
    for key in ("container_name", "ports", "hostname"):
        assert key not in worker, f"worker.{key} stops `--scale worker=N`"
    test = healthcheck_test(worker)
    assert test and test[0] != "NONE" and "healthz" not in " ".join(test), (
        "the worker replaces the image's HTTP health check (a worker serves no HTTP)"
    )

    # API and workers: one image, one results volume, one broker.
    for name in ("api", "worker"):
        service = services[name]
        assert default(service["build"]["args"]["BASE_IMAGE"]) == DEFAULT_IMAGES["BASE_IMAGE"], name
        assert depends(service).get("redis") == "service_healthy", f"{name} waits for a healthy redis"
        assert depends(service).get("postgres") == "service_healthy", f"{name} waits for a healthy postgres"
        assert service.get("restart") in ("unless-stopped", "always", "on-failure"), f"{name}.restart"
        env = environment(service)
        url = str(env.get("PERCUSSIM_DATABASE_URL", ""))
        assert url.startswith("postgresql+psycopg://") and url.endswith(f"@postgres:5432/{database}"), name
        assert str(env.get("PERCUSSIM_BROKER_URL", "")).startswith("redis://redis:6379/"), name
        assert env.get("PERCUSSIM_RESULTS_DIR", "/data") == "/data", name
        assert mounts(service).get("/data") == "results", f"{name} mounts the results volume at /data"
    assert api.get("image") == worker.get("image")
    assert environment(api)["PERCUSSIM_BROKER_URL"] == environment(worker)["PERCUSSIM_BROKER_URL"]
    assert redis.get("restart")


def test_compose_file_structure():
    """The file as written (anchors and merge keys resolved by the YAML loader)."""
    check_stack(yaml.safe_load(COMPOSE.read_text()))


def test_docker_compose_config_accepts_and_resolves_the_file():
    command = compose_command()
    if command is None:
        if os.environ.get("CI", "").lower() in ("true", "1"):
            pytest.fail("docker-compose is missing in CI: the test setup installs it (apt-get install docker-compose)")
        pytest.skip(
            "docker-compose is not installed (apt-get install docker-compose); "
            "test_compose_file_structure still checks the file as YAML"
        )
    env = {
        k: v for k, v in os.environ.items() if not k.startswith(("COMPOSE_", "PERCUSSIM_")) and k not in DEFAULT_IMAGES
    }
    done = subprocess.run(
        [*command, "-f", str(COMPOSE), "config"], cwd=ROOT, env=env, capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 0, done.stderr
    config = yaml.safe_load(done.stdout)
    check_stack(config)
    for name in ("api", "worker"):
        build = config["services"][name]["build"]
        context = Path(build["context"])
        assert context.resolve() == ROOT, "the build context is the repository root"
        assert (context / build.get("dockerfile", "Dockerfile")).resolve() == DOCKERFILE
    limit = environment(config["services"]["worker"]).get("PERCUSSIM_JOB_TIME_LIMIT")
    assert limit is None or float(limit) > 0


def test_the_settings_the_compose_file_suggests_are_accepted():
    """The values commented out in the file, uncommented, as `percussim worker` reads them."""
    suggested = dict(re.findall(r'^\s*#\s*(PERCUSSIM_[A-Z_]+):\s*"([^"]*)"', COMPOSE.read_text(), flags=re.MULTILINE))
    assert "PERCUSSIM_MAX_NODE_STEPS" in suggested, suggested
    code = "from percussim.common.settings import settings; print(settings().model_dump_json())"
    env = {k: v for k, v in os.environ.items() if not k.startswith("PERCUSSIM_")} | suggested
    done = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    read = json.loads(done.stdout)
    for name, value in suggested.items():
        assert read[name.removeprefix("PERCUSSIM_").lower()] == float(value), name


# ---------------------------------------------------------------------------------------------
# The health checks, run against stand-ins


class _Health(http.server.BaseHTTPRequestHandler):
    status = 200

    def do_GET(self):  # noqa: N802
        self.send_response(self.status if self.path in ("/healthz", "/readyz") else 404)
        self.end_headers()

    def log_message(self, *args):
        pass


@pytest.fixture
def api_stand_in():
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), _Health)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    yield server
    server.shutdown()
    server.server_close()


def run_check(code: str, port: int | None = None, env: dict | None = None) -> int:
    if port is not None:
        assert "127.0.0.1:8000" in code
        code = code.replace("127.0.0.1:8000", f"127.0.0.1:{port}")
    return subprocess.run(
        [sys.executable, "-c", code], cwd=ROOT, capture_output=True, timeout=60, env={**os.environ, **(env or {})}
    ).returncode


def http_checks() -> list[str]:
    """The image's HEALTHCHECK command and the compose file's for the API."""
    text = DOCKERFILE.read_text().replace("\\\n", "")
    (check,) = re.findall(r"^HEALTHCHECK .* CMD (\[.*\])$", text, flags=re.MULTILINE)
    words = json.loads(check)
    assert words[:2] == ["python", "-c"]
    compose_api = healthcheck_test(yaml.safe_load(COMPOSE.read_text())["services"]["api"])
    assert compose_api[:3] == ["CMD", "python", "-c"]
    return [words[2], compose_api[3]]


def test_the_http_health_checks_pass_on_200_and_fail_otherwise(api_stand_in, monkeypatch):
    port = api_stand_in.server_address[1]
    for code in http_checks():
        monkeypatch.setattr(_Health, "status", 200)
        assert run_check(code, port) == 0
        monkeypatch.setattr(_Health, "status", 503)
        assert run_check(code, port) != 0


def test_the_worker_health_check_follows_its_heartbeat(tmp_path):
    from percussim.common.store import WorkerRegistry

    test = healthcheck_test(yaml.safe_load(COMPOSE.read_text())["services"]["worker"])
    assert test[:3] == ["CMD", "python", "-c"]
    env = {"PERCUSSIM_RESULTS_DIR": str(tmp_path)}
    assert run_check(test[3], env=env) != 0, "no heartbeat yet: unhealthy"
    # The worker's default name (worker/main.py), as `percussim worker` runs in the container.
    WorkerRegistry(tmp_path).beat(f"percussim@{socket.gethostname()}")
    assert run_check(test[3], env=env) == 0
    WorkerRegistry(tmp_path).beat("percussim@another-replica")
    (tmp_path / "workers" / f"percussim@{socket.gethostname()}.json").unlink()
    assert run_check(test[3], env=env) != 0, "another replica's heartbeat does not count"
