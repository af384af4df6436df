"""The container files: docker/Dockerfile, docker/docker-compose.yml and .dockerignore.

No Docker engine is needed. The compose file is checked twice: as YAML (always) and as
`docker-compose config` resolves it (needs docker-compose, or the `docker compose` plugin; the
suite's setup installs it in CI, elsewhere that one test is skipped). The Dockerfile is read
statically: its stages, user, paths and commands against the repository. The health check
commands of the image and of the compose services are run for real against a stand-in.
"""

from __future__ import annotations

import http.server
import json
import os
import shlex
import shutil
import socket
import subprocess
import sys
import threading
import tomllib
from dataclasses import dataclass, field
from fnmatch import fnmatch
from pathlib import Path

import pytest
import yaml

ROOT = Path(__file__).resolve().parents[1]
DOCKERFILE = ROOT / "docker" / "Dockerfile"
COMPOSE = ROOT / "docker" / "docker-compose.yml"
DOCKERIGNORE = ROOT / ".dockerignore"
BASE_IMAGE = "python:3.11-slim"
SERVE = ["percussim", "serve", "--host", "0.0.0.0", "--port", "8000"]


# ---------------------------------------------------------------------------------------------
# The Dockerfile, read as Docker reads it


@dataclass
class Stage:
    base: str
    name: str | None
    instructions: list[tuple[str, str]] = field(default_factory=list)

    def all(self, keyword: str) -> list[str]:
        return [args for kw, args in self.instructions if kw == keyword]


def parse_dockerfile(text: str) -> list[Stage]:
    """The stages of a Dockerfile, each with its instructions (continuations joined as Docker
    joins them: the backslash and the newline removed; comment lines inside skipped)."""
    instructions, current = [], None
    for line in text.splitlines():
        stripped = line.strip()
        if stripped.startswith("#") or (current is None and not stripped):
            continue
        line = line.rstrip()
        if line.endswith("\\"):
            current = (current or "") + line[:-1]
            continue
        current = (current or "") + line
        keyword, _, args = current.strip().partition(" ")
        instructions.append((keyword.upper(), args.strip()))
        current = None
    assert current is None, "the Dockerfile ends inside a continued line"
    stages: list[Stage] = []
    for keyword, args in instructions:
        if keyword == "FROM":
            words = args.split()
            words = [w for w in words if not w.startswith("--")]
            name = words[2] if len(words) == 3 and words[1].lower() == "as" else None
            stages.append(Stage(base=words[0], name=name))
        elif keyword != "ARG" or stages:  # an ARG before the first FROM belongs to no stage
            stages[-1].instructions.append((keyword, args))
    return stages


def split_args(args: str) -> tuple[list[str], list[str]]:
    """(flags, words) of an instruction's arguments, in exec (JSON) or shell form."""
    flags = []
    while args.startswith("--"):
        flag, _, args = args.partition(" ")
        flags.append(flag)
        args = args.strip()
    words = json.loads(args) if args.startswith("[") else shlex.split(args)
    return flags, words


def env_of_stage(stage: Stage) -> dict[str, str]:
    env = {}
    for args in stage.all("ENV"):
        words = shlex.split(args)
        if words and "=" not in words[0]:  # legacy form: ENV KEY value
            env[words[0]] = " ".join(words[1:])
        else:
            env.update(w.split("=", 1) for w in words)
    return env


@pytest.fixture(scope="module")
def stages() -> list[Stage]:
    return parse_dockerfile(DOCKERFILE.read_text())


@pytest.fixture(scope="module")
def final(stages) -> Stage:
    return stages[-1]


def effective_users(stage: Stage) -> list[tuple[str, str, str]]:
    """(instruction, arguments, user it runs as) for every instruction of the stage."""
    user, out = "root", []
    for keyword, args in stage.instructions:
        if keyword == "USER":
            user = args.split(":")[0].strip()
        out.append((keyword, args, user))
    return out


def is_root(user: str) -> bool:
    return user in ("root", "0")


def test_two_stages_on_the_slim_python_image(stages):
    assert len(stages) >= 2, "a builder stage and a runtime stage"
    assert all(s.base == BASE_IMAGE for s in stages), [s.base for s in stages]
    names = [s.name for s in stages[:-1]]
    # The final stage takes the environment built earlier, by an earlier stage's name.
    froms = [split_args(a)[0] for a in stages[-1].all("COPY")]
    sources = [f.split("=", 1)[1] for flags in froms for f in flags if f.startswith("--from=")]
    assert sources and all(s in names for s in sources), (sources, names)


def test_the_builder_installs_the_project_not_editable(stages):
    builder = stages[0]
    pyproject = tomllib.loads((ROOT / "pyproject.toml").read_text())
    needed = {
        "pyproject.toml",
        pyproject["project"]["readme"],
        *pyproject["tool"]["setuptools"]["package-dir"].values(),
    }
    copied = {Path(src).as_posix() for args in builder.all("COPY") for src in split_args(args)[1][:-1]}
    assert needed <= copied, f"`pip install .` needs {sorted(needed - copied)} in the builder"
    installs = [a for a in builder.all("RUN") if "pip install" in a and " ." in a]
    assert installs, "the builder runs `pip install .`"
    assert not any(" -e " in a or "--editable" in a for a in installs), "not an editable install"


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


def test_the_runtime_user_is_not_root(final):
    users = effective_users(final)
    assert final.all("USER"), "the final stage sets a USER"
    last_user = users[-1][2]
    assert not is_root(last_user), f"the container runs as {last_user}"
    assert any("useradd" in a for a in final.all("RUN")), "the user is created in the image"


def test_the_kernel_cache_is_warmed_as_the_runtime_user(final):
    warmups = [(args, user) for kw, args, user in effective_users(final) if kw == "RUN" and "percussim warmup" in args]
    assert warmups, "a RUN step runs `percussim warmup`"
    assert all(not is_root(user) for _, user in warmups), "warmed up as the runtime user, not root"
    env = env_of_stage(final)
    cache = env.get("NUMBA_CACHE_DIR")
    assert cache and cache.startswith("/"), "NUMBA_CACHE_DIR is a fixed folder"
    prepared = [a for a in final.all("RUN") if cache in a and "chown" in a]
    assert prepared, f"{cache} is created and given to the runtime user"


def test_healthcheck_port_and_default_command(final):
    (check,) = final.all("HEALTHCHECK")
    assert "/healthz" in check and "python" in check
    assert "curl" not in check and "wget" not in check, "the slim image has neither"
    ports = {p.split("/")[0] for args in final.all("EXPOSE") for p in args.split()}
    assert "8000" in ports
    assert split_args(final.all("CMD")[-1])[1] == SERVE


def test_every_copied_path_exists_and_reaches_the_build_context(stages):
    ignored = [p.strip() for p in DOCKERIGNORE.read_text().splitlines() if p.strip() and not p.startswith(("#", "!"))]
    for stage in stages:
        for args in stage.all("COPY") + stage.all("ADD"):
            flags, words = split_args(args)
            if any(f.startswith("--from=") for f in flags):
                continue
            for src in words[:-1]:
                path = (ROOT / src).resolve()
                assert path.is_relative_to(ROOT), f"{src} is outside the build context"
                assert path.exists(), f"COPY {src}: no such path in the repository"
                if src.endswith("/"):
                    assert path.is_dir(), f"COPY {src}: not a folder"
                rel = path.relative_to(ROOT).as_posix()
                parts = rel.split("/")
                for pattern in ignored:
                    for k in range(1, len(parts) + 1):
                        prefix = "/".join(parts[:k])
                        assert not fnmatch(prefix, pattern.removeprefix("**/")), (
                            f"COPY {src}: excluded from the build context by .dockerignore {pattern!r}"
                        )


def test_the_image_environment(final):
    env = env_of_stage(final)
    assert env.get("PERCUSSIM_RESULTS_DIR") == "/data"
    assert "PERCUSSIM_PRESETS" not in env, "the presets ship in the package"
    assert any("/data" in a and "chown" in a for a in final.all("RUN")), (
        "/data is owned by the runtime user, so a new named volume mounted there is writable"
    )


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
    assert str(postgres["image"]).startswith("postgres:")
    assert mounts(postgres).get("/var/lib/postgresql/data") == "postgres-data"
    assert "pg_isready" in " ".join(healthcheck_test(postgres))
    database = environment(postgres)["POSTGRES_DB"]

    # Flower, for the Celery side, on the same broker.
    flower = services["flower"]
    assert "flower" in str(flower["image"]) and ("5555", "5555") in published(flower)
    assert str(environment(flower)["CELERY_BROKER_URL"]).startswith("redis://redis:6379/")

    # Redis: persistent (append-only file in a named volume) and health-checked.
    assert str(redis["image"]).startswith("redis:7")
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
        assert service.get("build"), f"{name} builds the image"
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


def compose_command() -> list[str] | None:
    if shutil.which("docker-compose"):
        return ["docker-compose"]
    if shutil.which("docker") and subprocess.run(["docker", "compose", "version"], capture_output=True).returncode == 0:
        return ["docker", "compose"]
    return None


def test_docker_compose_config_accepts_and_resolves_the_file():
    command = compose_command()
    if command is None:
        if os.environ.get("CI", "").lower() in ("true", "1"):
            pytest.fail("docker-compose is missing in CI: the test setup installs it (apt-get install docker-compose)")
        pytest.skip(
            "docker-compose is not installed (apt-get install docker-compose); "
            "test_compose_file_structure still checks the file as YAML"
        )
    env = {k: v for k, v in os.environ.items() if not k.startswith(("COMPOSE_", "PERCUSSIM_"))}
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


def http_checks(final: Stage) -> list[str]:
    flags, words = split_args(final.all("HEALTHCHECK")[0].split(" CMD ", 1)[1])
    assert words[:2] == ["python", "-c"]
    compose_api = healthcheck_test(yaml.safe_load(COMPOSE.read_text())["services"]["api"])
    assert compose_api[:3] == ["CMD", "python", "-c"]
    return [words[2], compose_api[3]]


def test_the_http_health_checks_pass_on_200_and_fail_otherwise(final, api_stand_in, monkeypatch):
    port = api_stand_in.server_address[1]
    for code in http_checks(final):
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
