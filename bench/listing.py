"""`GET /v1/jobs` latency with 1,000, 10,000 and 100,000 jobs in the database, on SQLite (the
embedded default) and on PostgreSQL. The requirement: p95 ≤ 50 ms for the first page of 20 at
100,000 jobs.

    .venv/bin/python bench/listing.py [--databases sqlite,postgresql] [--sizes 1000,10000,100000]
                                      [--requests 200]

For each database a real `percussim serve` (embedded, no worker) on a loopback port, with its
records in an SQLite file in its results folder or in a database of a real PostgreSQL server
started here (the system's package). The rows are written straight into the `jobs` table with
bulk inserts (SQLAlchemy Core, batches of 5000), not through the API, which would make a folder
per job: the listing reads only the records. They look like the store's own: ~50 case names,
mostly succeeded (80%; failed 8%, cancelled 5%, queued 4%, running 3%), a second apart in
creation time, 10% of them variants of ~N/100 sweeps. The same database grows from 1k to 10k to
100k jobs (the difference inserted each time), then PostgreSQL gets `VACUUM ANALYZE jobs`, as its
autovacuum would after such an insert.

Measured through HTTP with one keep-alive client on this machine, after 10 warm-up calls, each
query `--requests` times, p50 and p95 in ms; each answer's `total` is printed beside it:

- first page: `?limit=20` (its `total` is checked to be N);
- page 50 by cursor: the page reached by following `next` 49 times from the first, requested by
  its cursor;
- last page by cursor and by offset (`offset=N-20`): the cursor's cost does not grow with the
  depth, the offset's does;
- filters: `status=failed`, `name=case 7`, `sweep=<a sweep's id>`, each `limit=20`.

Then, in this process on the same database, the first page without HTTP: `JobStore.list` itself
and its two statements apart, the `COUNT(*)` of `total` and the page's `SELECT`, to show which
one grows with N and how much of a request is the HTTP service's own.
"""

from __future__ import annotations

import argparse
import random
import statistics
import tempfile
import time
from contextlib import ExitStack
from datetime import timedelta
from pathlib import Path
from urllib.parse import urlencode

from sqlalchemy import and_, func, insert, select, text, true

from percussim.common.database import database
from percussim.common.database import jobs as JOBS
from percussim.common.settings import Settings
from percussim.common.store import JobStore, new_id, now
from percussim.testing.live_stack import Stack, postgres_server

DATABASES = ("sqlite", "postgresql")
SIZES = (1000, 10_000, 100_000)
PAGE = 20
DEPTH = 50  # pages in, by cursor
BATCH = 5000  # rows an insert
NAMES = 50
STATUSES = (("succeeded", 0.80), ("failed", 0.08), ("cancelled", 0.05), ("queued", 0.04), ("running", 0.03))
SWEEP_SHARE = 0.10  # of jobs, variants of a sweep; one sweep per block of 100 jobs
WARM_UP = 10
REQUIREMENT_MS = 50.0


def percentiles(values: list[float]) -> tuple[float, float]:
    """(p50, p95) in ms."""
    values = sorted(values)
    p95 = values[min(len(values) - 1, round(0.95 * len(values)) - 1)]
    return statistics.median(values) * 1e3, p95 * 1e3


class Rows:
    """Job rows like `JobStore._new` makes, then as the workers leave them; row k is created k
    seconds after `base`, so newest first is one well-defined order."""

    def __init__(self, base, seed: int = 0):
        self.base = base
        self.rng = random.Random(seed)
        self.sweeps: dict[int, str] = {}  # a sweep id per block of 100 rows
        self.statuses, self.weights = zip(*STATUSES)

    def row(self, k: int) -> dict:
        rng = self.rng
        status = rng.choices(self.statuses, self.weights)[0]
        created = self.base + timedelta(seconds=k)
        started = None if status == "queued" else created + timedelta(seconds=rng.uniform(0.01, 30))
        finished = None
        if status in ("succeeded", "failed"):
            finished = started + timedelta(seconds=rng.uniform(0.1, 60))
        elif status == "cancelled":
            started = None if rng.random() < 0.5 else started
            finished = (started or created) + timedelta(seconds=rng.uniform(0.1, 10))
        progress = {"succeeded": 1.0, "queued": 0.0, "cancelled": 0.0}.get(status, rng.random())
        sweep = None
        if rng.random() < SWEEP_SHARE:
            sweep = self.sweeps.setdefault(k // 100, new_id())
        return {
            "id": new_id(),
            "owner": None,
            "name": f"case {rng.randrange(NAMES)}",
            "kind": "run",
            "status": status,
            "progress": progress,
            "created": created,
            "started": started,
            "finished": finished,
            "error": "the solver diverged: the time step exceeds the stable one" if status == "failed" else None,
            "attempts": 0 if started is None else 1,
            "worker": None if started is None else "percussim1@bench",
            "sweep": sweep,
            "cancel_requested": status == "cancelled",
            "result_bytes": rng.randrange(200_000, 2_000_000) if status == "succeeded" else None,
        }


def fill(engine, rows: Rows, start: int, stop: int) -> float:
    """Insert rows start..stop-1 in batches; returns the seconds it took."""
    began = time.perf_counter()
    with engine.begin() as connection:
        for first in range(start, stop, BATCH):
            connection.execute(insert(JOBS), [rows.row(k) for k in range(first, min(stop, first + BATCH))])
    if engine.dialect.name == "postgresql":
        with engine.connect().execution_options(isolation_level="AUTOCOMMIT") as connection:
            connection.execute(text("VACUUM ANALYZE jobs"))
    return time.perf_counter() - began


def timed(client, path: str, requests: int) -> tuple[float, float, dict]:
    """(p50 ms, p95 ms, the last answer) of GET `path`."""
    for _ in range(WARM_UP):
        answer = client.get(path)
        assert answer.status_code == 200, (path, answer.status_code, answer.text[:500])
    times = []
    for _ in range(requests):
        start = time.perf_counter()
        answer = client.get(path)
        times.append(time.perf_counter() - start)
        assert answer.status_code == 200, (path, answer.status_code, answer.text[:500])
    p50, p95 = percentiles(times)
    return p50, p95, answer.json()


def in_process(call, requests: int) -> tuple[float, float]:
    """(p50 ms, p95 ms) of `call()` in this process."""
    times = []
    for k in range(WARM_UP + requests):
        start = time.perf_counter()
        call()
        if k >= WARM_UP:
            times.append(time.perf_counter() - start)
    return percentiles(times)


def statement(engine, query):
    """A call running `query` on a connection from the engine's pool."""

    def run():
        with engine.connect() as connection:
            connection.execute(query).all()

    return run


def measure(
    kind: str, stack: Stack, settings: Settings, engine, rows: Rows, size: int, requests: int
) -> dict[str, float]:
    """Print a line per query; returns each query's p95."""
    client = stack.client
    first = client.get("/v1/jobs", params={"limit": PAGE}).json()
    assert first["total"] == size, f"{kind}: total {first['total']}, expected {size}"
    print(f"  row count check: first page's total {first['total']} = {size}")

    path, page, followed = f"/v1/jobs?limit={PAGE}", first, 0
    while followed < DEPTH - 1 and page["next"] and (followed + 1) * PAGE < size:
        path = page["next"]
        page = client.get(path).json()
        followed += 1
    deep = page
    before_last = client.get("/v1/jobs", params={"offset": size - 2 * PAGE, "limit": PAGE}).json()
    sweep = rows.sweeps[min(rows.sweeps, key=lambda block: abs(block - size // 200))]
    queries = {
        "first page": f"/v1/jobs?limit={PAGE}",
        f"page {followed + 1} by cursor": path,
        "last page by cursor": before_last["next"],
        "last page by offset": f"/v1/jobs?offset={size - PAGE}&limit={PAGE}",
        "status=failed": f"/v1/jobs?{urlencode({'status': 'failed', 'limit': PAGE})}",
        "name=case 7": f"/v1/jobs?{urlencode({'name': 'case 7', 'limit': PAGE})}",
        "sweep=<one>": f"/v1/jobs?{urlencode({'sweep': sweep, 'limit': PAGE})}",
    }

    results = {}
    for label, path in queries.items():
        p50, p95, answer = timed(client, path, requests)
        if label.startswith("page ") and followed:
            assert answer["jobs"] == deep["jobs"], "the cursor's page changed"
        results[label] = p95
        print(
            f"  {kind:10s} N={size:<7d} {label:22s} p50 {p50:6.2f} ms  p95 {p95:6.2f} ms  "
            f"(total {answer['total']}, {len(answer['jobs'])} jobs)"
        )

    # The statements as `JobStore.list` builds them: with no filter its condition is `true`, which
    # SQLite cannot answer from its b-tree's own count as it does a bare COUNT(*).
    everything = and_(true())
    count = in_process(statement(engine, select(func.count()).select_from(JOBS).where(everything)), requests)
    selecting = in_process(
        statement(
            engine,
            select(JOBS).where(everything).order_by(JOBS.c.created.desc(), JOBS.c.id.desc()).offset(0).limit(PAGE),
        ),
        requests,
    )
    store = JobStore(settings)
    listing = in_process(lambda: store.list(0, PAGE), requests)
    print(
        f"  {kind:10s} N={size:<7d} in this process, the first page: JobStore.list p50 {listing[0]:.2f} ms "
        f"p95 {listing[1]:.2f} ms; its COUNT(*) alone p50 {count[0]:.2f} ms p95 {count[1]:.2f} ms, "
        f"its SELECT alone p50 {selecting[0]:.2f} ms p95 {selecting[1]:.2f} ms"
    )
    return results


def run(kind: str, sizes: list[int], requests: int, outcome: dict) -> None:
    with tempfile.TemporaryDirectory() as tmp, ExitStack() as resources:
        folder = Path(tmp)
        env, settings = {}, Settings(results_dir=folder / "results", database_url=None)
        if kind == "postgresql":
            server = resources.enter_context(postgres_server())
            url = server.database()
            env = {"PERCUSSIM_DATABASE_URL": url}
            settings = Settings(results_dir=folder / "results", database_url=url)
        # The API first, on the empty database: started on a full one, the embedded service would
        # queue again every queued job it finds.
        stack = Stack(folder, None, workers=0, env=env)
        resources.callback(stack.stop)
        engine = database(settings)
        rows = Rows(now() - timedelta(seconds=max(sizes) + 3600))
        filled = 0
        for size in sizes:
            seconds = fill(engine, rows, filled, size)
            print(f"{kind}: filled {filled} → {size} jobs ({size - filled} rows inserted) in {seconds:.2f} s")
            filled = size
            outcome[(kind, size)] = measure(kind, stack, settings, engine, rows, size, requests)
        engine.dispose()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument(
        "--databases", default=",".join(DATABASES), help="comma-separated: sqlite, postgresql (default both)"
    )
    parser.add_argument(
        "--sizes",
        default=",".join(map(str, SIZES)),
        help="comma-separated numbers of jobs, growing (default 1000,10000,100000)",
    )
    parser.add_argument("--requests", type=int, default=200, help="timed requests per query")
    args = parser.parse_args()
    kinds = [k.strip() for k in args.databases.split(",") if k.strip()]
    if unknown := set(kinds) - set(DATABASES):
        parser.error(f"unknown databases {sorted(unknown)}: choose among {', '.join(DATABASES)}")
    sizes = sorted({int(s) for s in args.sizes.split(",") if s.strip()})
    if not sizes or sizes[0] < 2 * PAGE:
        parser.error(f"sizes must be at least {2 * PAGE}")

    began = time.perf_counter()
    outcome: dict[tuple[str, int], dict[str, float]] = {}
    for kind in kinds:
        run(kind, sizes, args.requests, outcome)
    largest = sizes[-1]
    for kind in kinds:
        p95 = outcome[(kind, largest)]["first page"]
        verdict = "meets" if p95 <= REQUIREMENT_MS else "MISSES"
        print(
            f"{kind}: first page of {PAGE} at {largest} jobs, p95 {p95:.2f} ms: {verdict} p95 ≤ {REQUIREMENT_MS:.0f} ms"
        )
    print(f"bench time {time.perf_counter() - began:.0f} s")


if __name__ == "__main__":
    main()
