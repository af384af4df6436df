"""Builds the image and starts docker/docker-compose.yml for real, on the host's network
(docker/docker-compose.loopback.yml): every service on its own free loopback port, the base
images made by scripts/local-images from Debian's packages.

The two files are resolved by `compose config` into one, less the published ports: on the host's
network they mean nothing and Compose 1.x (Debian's) refuses them, yet cannot unset a list from
an override file.

Needs a running dockerd and Compose (`docker compose` or `docker-compose`); scripts/test installs
and starts both.
"""

from __future__ import annotations

import json
import os
import secrets
import shutil
import subprocess
import tempfile
import time
from functools import cache

import httpx
import yaml

from percussim.testing.live_stack import ROOT, free_port, wait_for

COMPOSE_FILES = [ROOT / "docker" / "docker-compose.yml", ROOT / "docker" / "docker-compose.loopback.yml"]
IMAGE = "percussim:test"  # not percussim:latest, which a user's `docker compose up` builds
FLOWER_IMAGE = "percussim-flower:local"  # docker/docker-compose.loopback.yml builds it on IMAGE
LOCAL_IMAGES = {
    "BASE_IMAGE": "percussim-base:local",
    "REDIS_IMAGE": "percussim-redis:local",
    "POSTGRES_IMAGE": "percussim-postgres:local",
}
WORKERS = {"worker": "percussim@percussim-worker-1", "worker-2": "percussim@percussim-worker-2"}


@cache
def compose_command() -> list[str] | None:
    """`docker compose` (the plugin) if there is one, else `docker-compose`, else None."""
    if shutil.which("docker") and subprocess.run(["docker", "compose", "version"], capture_output=True).returncode == 0:
        return ["docker", "compose"]
    if shutil.which("docker-compose"):
        return ["docker-compose"]
    return None


def docker(*args: str, timeout: float = 120, check: bool = True) -> str:
    done = subprocess.run(["docker", *args], capture_output=True, text=True, timeout=timeout)
    if check and done.returncode != 0:
        raise RuntimeError(f"docker {' '.join(args)}: exit {done.returncode}\n{done.stderr[-3000:]}")
    return done.stdout


def require_docker() -> None:
    """Fails, saying what to do, unless a dockerd answers and Compose is installed."""
    if shutil.which("docker") is None or compose_command() is None:
        raise RuntimeError("docker and Compose are not installed: run the tests with scripts/test, which installs them")
    if subprocess.run(["docker", "info"], capture_output=True, timeout=60).returncode != 0:
        raise RuntimeError(
            "no dockerd answers on /var/run/docker.sock: run the tests with scripts/test, which starts one"
        )


def local_images() -> float:
    """Makes (or finds) the local base, Redis and PostgreSQL images; the seconds it took."""
    start = time.monotonic()
    subprocess.run([str(ROOT / "scripts" / "local-images")], check=True, timeout=900)
    return time.monotonic() - start


class ComposeStack:
    """One Compose project on loopback ports: built, started, stopped and removed whole."""

    def __init__(self, env: dict[str, str] | None = None):
        self.project = f"percussim-test-{secrets.token_hex(4)}"
        self.ports = {name: free_port() for name in ("API_PORT", "REDIS_PORT", "POSTGRES_PORT", "FLOWER_PORT")}
        self.env = {k: v for k, v in os.environ.items() if not k.startswith(("COMPOSE_", "PERCUSSIM_", "DOCKER_"))}
        self.env |= LOCAL_IMAGES | {k: str(v) for k, v in self.ports.items()} | {"PERCUSSIM_IMAGE": IMAGE}
        self.env |= env or {}
        self.url = f"http://127.0.0.1:{self.ports['API_PORT']}"
        self.flower_url = f"http://127.0.0.1:{self.ports['FLOWER_PORT']}"
        self.client = httpx.Client(base_url=self.url, timeout=30)
        self.folder = tempfile.mkdtemp(prefix="percussim-compose-")
        config = yaml.safe_load(self.compose("config", files=COMPOSE_FILES))
        for service in config["services"].values():
            service.pop("ports", None)
        self.file = os.path.join(self.folder, "docker-compose.yml")
        with open(self.file, "w") as f:
            yaml.safe_dump(config, f)

    def compose(self, *args: str, timeout: float = 600, files=None) -> str:
        named = [word for path in files or [self.file] for word in ("-f", str(path))]
        done = subprocess.run(
            [*compose_command(), "-p", self.project, *named, *args],
            cwd=ROOT,
            env=self.env,
            capture_output=True,
            text=True,
            timeout=timeout,
        )
        if done.returncode != 0:
            raise RuntimeError(f"compose {' '.join(args)}: exit {done.returncode}\n{done.stderr[-5000:]}")
        return done.stdout

    def build(self, no_cache: bool = False) -> float:
        """Builds percussim's image, then Flower's on it; the seconds percussim's took. The image
        it replaces is removed, so that repeated builds leave no unnamed image behind."""
        before = {image: docker("images", "-q", image).strip() for image in (IMAGE, FLOWER_IMAGE)}
        start = time.monotonic()
        self.compose("build", *(["--no-cache"] if no_cache else []), "api", timeout=1800)
        seconds = time.monotonic() - start
        self.compose("build", "flower")
        for image, was in before.items():
            if was and was != docker("images", "-q", image).strip():
                docker("rmi", was, check=False)  # still in use by a container: kept
        return seconds

    def up(self, timeout: float = 180) -> float:
        """Starts every service and waits for /readyz with both workers; the seconds it took."""
        start = time.monotonic()
        self.compose("up", "-d", "--no-build", timeout=timeout)
        self.wait_ready(timeout)
        return time.monotonic() - start

    def wait_ready(self, timeout: float = 120) -> dict:
        def ready():
            answer = self.client.get("/readyz")
            return (
                answer.status_code == 200 and set(WORKERS.values()) <= set(answer.json()["workers"]) and answer.json()
            )

        return wait_for(ready, timeout, f"{self.url}/readyz with {len(WORKERS)} workers", interval=0.5)

    def containers(self, service: str | None = None) -> list[str]:
        labels = [f"label=com.docker.compose.project={self.project}"]
        if service:
            labels.append(f"label=com.docker.compose.service={service}")
        return docker("ps", "-a", "-q", "--no-trunc", *(w for label in labels for w in ("--filter", label))).split()

    def container(self, service: str) -> str:
        (container,) = self.containers(service)
        return container

    def inspect(self, *containers: str) -> list[dict]:
        return json.loads(docker("inspect", *containers))

    def left_behind(self) -> dict[str, list[str]]:
        """What of this project is still there: containers, volumes, networks."""
        label = f"label=com.docker.compose.project={self.project}"
        return {
            "containers": self.containers(),
            "volumes": docker("volume", "ls", "-q", "--filter", label).split(),
            "networks": docker("network", "ls", "-q", "--filter", label).split(),
        }

    def broker_state(self) -> str:
        """The queue's length, the messages delivered and not acknowledged, and the time left on
        the lock a worker holds while it puts overdue ones back: where a lost job may be."""
        script = (
            "return {redis.call('llen','celery'), redis.call('hlen','unacked'), redis.call('pttl','unacked_mutex')}"
        )
        try:
            found = docker("exec", self.container("redis"), "redis-cli", "eval", script, "0", timeout=30).split()
        except (RuntimeError, subprocess.SubprocessError, ValueError) as error:
            return f"the broker's state unread: {error}"
        return "queued {}, unacknowledged {}, restore lock's ms left {}".format(*found)

    def logs(self) -> str:
        try:
            return self.compose("logs", "--no-color", "--tail", "60", timeout=60)
        except (RuntimeError, subprocess.TimeoutExpired) as error:
            return str(error)

    def down(self) -> None:
        self.client.close()
        self.compose("down", "-v", "--remove-orphans", "--timeout", "20", timeout=300)
        shutil.rmtree(self.folder, ignore_errors=True)
