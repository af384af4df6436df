"""Starts the real thing for the live tests: redis-server, PostgreSQL, `percussim worker`s,
`percussim serve`.

Every process runs in its own process group on loopback ports, and is stopped with its children.
"""

from __future__ import annotations

import glob
import os
import pwd
import secrets
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from contextlib import contextmanager
from pathlib import Path

import httpx
import redis

ROOT = Path(__file__).resolve().parents[2]  # the repository, where the processes start


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def wait_for(check, timeout: float, what: str, interval: float = 0.1):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            value = check()
            if value:
                return value
        except (httpx.HTTPError, redis.RedisError, OSError):
            pass
        time.sleep(interval)
    raise TimeoutError(f"{what} not ready within {timeout} s")


def children(pid: int) -> list[int]:
    """The processes `pid` started (Linux: /proc/PID/task/PID/children)."""
    try:
        return [int(c) for c in Path(f"/proc/{pid}/task/{pid}/children").read_text().split()]
    except FileNotFoundError:  # it has exited
        return []


def command_line(pid: int) -> str:
    return Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")


class Process:
    def __init__(self, args: list[str], env: dict, log: Path):
        self.log = log
        self.popen = subprocess.Popen(
            args, env=env, cwd=ROOT, stdout=log.open("wb"), stderr=subprocess.STDOUT, start_new_session=True
        )

    def stop(self, sig=signal.SIGTERM, timeout: float = 15.0, everyone: bool = False) -> None:
        self.signal(sig, everyone)
        self.wait(timeout)

    def signal(self, sig=signal.SIGTERM, everyone: bool = False) -> None:
        """`sig` to the process, which stops what it started in its own order (`docker stop`,
        systemd's `KillMode=mixed`); with `everyone`, or SIGKILL (a crash), to every process it
        started too, at once (systemd's default)."""
        if self.popen.poll() is None:
            try:
                if sig == signal.SIGKILL or everyone:
                    os.killpg(self.popen.pid, sig)
                else:
                    self.popen.send_signal(sig)
            except ProcessLookupError:
                pass

    def wait(self, timeout: float = 15.0) -> None:
        """Until it has exited; killed, with what it started, after `timeout` s. Whatever it
        started and left running is killed then too."""
        try:
            self.popen.wait(timeout)
        except subprocess.TimeoutExpired:
            pass
        try:
            os.killpg(self.popen.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        self.popen.wait()


class RedisServer:
    """A real redis-server on a loopback port, with append-only persistence in `folder`: stopped
    and started again on the same port and data, it has every queued message back."""

    def __init__(self, folder: Path):
        self.binary = shutil.which("redis-server")
        if self.binary is None:
            raise RuntimeError("redis-server is not installed: run the tests with scripts/test")
        self.folder = folder
        self.folder.mkdir(parents=True, exist_ok=True)
        self.port = free_port()
        self.url = f"redis://127.0.0.1:{self.port}/0"
        self.process: Process | None = None

    def start(self) -> None:
        self.process = Process(
            [
                self.binary,
                "--port",
                str(self.port),
                "--bind",
                "127.0.0.1",
                "--dir",
                str(self.folder),
                "--appendonly",
                "yes",
                "--save",
                "",
            ],
            dict(os.environ),
            self.folder / "redis.log",
        )
        wait_for(lambda: redis.Redis.from_url(self.url, socket_timeout=0.5).ping(), 15, "redis-server")

    def stop(self) -> None:
        if self.process is not None:
            self.process.stop()  # SIGTERM: redis writes its append-only file out before it exits


@contextmanager
def redis_server(folder: Path):
    """A running `RedisServer`'s URL for the block."""
    server = RedisServer(folder)
    server.start()
    try:
        yield server.url
    finally:
        server.stop()


class PostgresServer:
    """A real PostgreSQL server (the system's package: initdb and pg_ctl) on a loopback port, its
    data in a folder of its own; trust authentication on loopback. As root the server runs as the
    package's `postgres` user, since PostgreSQL refuses to run as root. `database()` makes a new,
    empty database and returns its URL."""

    def __init__(self):
        found = sorted(glob.glob("/usr/lib/postgresql/*/bin/initdb"), key=lambda path: int(Path(path).parts[-3]))
        if not found:
            raise RuntimeError("PostgreSQL is not installed: run the tests with scripts/test")
        self.bin = Path(found[-1]).parent
        self.folder = Path(tempfile.mkdtemp(prefix="percussim-postgres-"))  # not under a private tmp
        self.as_user: list[str] = []
        if os.geteuid() == 0:
            user = pwd.getpwnam("postgres")
            os.chown(self.folder, user.pw_uid, user.pw_gid)
            self.as_user = ["runuser", "-u", "postgres", "--"]
        self.data = self.folder / "data"
        self.port = free_port()
        self._run("initdb", "-D", str(self.data), "-U", "postgres", "-A", "trust", "-E", "UTF8", "--no-sync")

    def _run(self, program: str, *args: str) -> None:
        subprocess.run([*self.as_user, str(self.bin / program), *args], check=True, capture_output=True)

    def url(self, database: str = "postgres") -> str:
        return f"postgresql+psycopg://postgres@127.0.0.1:{self.port}/{database}"

    def start(self) -> None:
        options = f"-p {self.port} -k {self.folder} -c listen_addresses=127.0.0.1 -c fsync=off"
        self._run("pg_ctl", "-D", str(self.data), "-o", options, "-l", str(self.folder / "postgres.log"), "-w", "start")

    def stop(self, mode: str = "fast") -> None:
        """`fast`: connections cut, a clean shutdown; `immediate`: as a crash, recovered at the next start."""
        self._run("pg_ctl", "-D", str(self.data), "-m", mode, "-w", "stop")

    def database(self) -> str:
        import psycopg

        name = f"percussim_{secrets.token_hex(4)}"
        with psycopg.connect(
            f"host=127.0.0.1 port={self.port} user=postgres dbname=postgres", autocommit=True
        ) as connection:
            connection.execute(f"CREATE DATABASE {name}")
        return self.url(name)

    def remove(self) -> None:
        try:
            self.stop()
        except subprocess.CalledProcessError:
            pass  # already stopped
        shutil.rmtree(self.folder, ignore_errors=True)


@contextmanager
def postgres_server():
    """A running `PostgresServer` for the block, removed afterwards."""
    server = PostgresServer()
    server.start()
    try:
        yield server
    finally:
        server.remove()


class Stack:
    """The API and its workers, sharing one results folder (and a broker, if given)."""

    def __init__(
        self,
        folder: Path,
        broker_url: str | None,
        workers: int = 1,
        worker_env: dict | None = None,
        env: dict | None = None,
    ):
        self.folder = folder
        self.env = {k: v for k, v in os.environ.items() if not k.startswith("PERCUSSIM_")}
        self.env["PERCUSSIM_RESULTS_DIR"] = str(folder / "results")
        self.env |= env or {}  # for the API and the workers
        self.worker_env = worker_env or {}
        if broker_url:
            self.env["PERCUSSIM_BROKER_URL"] = broker_url
        self.port = free_port()
        self.url = f"http://127.0.0.1:{self.port}"
        self.processes: list[Process] = []
        self.workers: dict[str, Process] = {}  # by Celery node name
        serve = [sys.executable, "-m", "percussim", "serve", "--port", str(self.port)]
        self.serve_api = [*serve, "--no-worker"]
        if broker_url:  # the API alone, workers as separate processes
            self.processes.append(Process(self.serve_api, self.env, folder / "api.log"))
            for k in range(workers):
                self.add_worker(f"w{k}")
        else:  # embedded: serve starts its own workers
            self.serve_embedded = [*serve, "--workers", str(workers)]
            self.processes.append(Process(self.serve_embedded, self.env, folder / "api.log"))
        self.client = httpx.Client(base_url=self.url, timeout=30)
        wait_for(
            lambda: len(self.client.get("/readyz").json().get("workers", [])) >= workers,
            60,
            f"the API and {workers} worker(s)",
        )

    def add_worker(self, name: str) -> Process:
        worker = Process(
            [sys.executable, "-m", "percussim", "worker", "--name", f"{name}@percussim"],
            self.env | self.worker_env,
            self.folder / f"worker-{name}.log",
        )
        self.processes.append(worker)
        self.workers[f"{name}@percussim"] = worker
        return worker

    def restart_api(self) -> None:
        """Stop the API (Redis mode: the first process) and start a new one on the same port."""
        self.processes[0].stop()
        self.processes[0] = Process(self.serve_api, self.env, self.folder / "api-restarted.log")
        wait_for(lambda: self.client.get("/healthz").status_code == 200, 60, "the restarted API")

    def restart(self, sig=signal.SIGKILL, while_down=lambda: None, timeout: float = 15.0) -> None:
        """Embedded mode: `sig` to the service and its workers at once (SIGKILL: a crash or a power
        cut; SIGTERM: a stop by systemd's default), wait up to `timeout` s for them to exit, call
        `while_down`, then start the service again on the same port and folder."""
        self.processes[0].stop(sig, timeout, everyone=True)
        while_down()
        self.processes[0] = Process(self.serve_embedded, self.env, self.folder / "api-restarted.log")
        wait_for(lambda: self.client.get("/readyz").status_code == 200, 60, "the restarted service")

    def wait_status(self, job_id: str, statuses: tuple[str, ...], timeout: float = 120) -> dict:
        def status():
            record = self.client.get(f"/v1/jobs/{job_id}").json()
            return record if record["status"] in statuses else None

        return wait_for(status, timeout, f"job {job_id} in {statuses}")

    def logs(self) -> str:
        return "\n".join(f"--- {p.log.name}\n{p.log.read_text(errors='replace')[-3000:]}" for p in self.processes)

    def stop(self) -> None:
        """Every process told to stop at once, then waited for: each stops in its own time."""
        self.client.close()
        for p in self.processes:
            p.signal()
        for p in self.processes:
            p.wait()
