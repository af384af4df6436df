"""The service under load: jobs per second sustained and latency, through Redis with 2 workers, and
what writing the HDF5 result costs a job.

    .venv/bin/python bench/load.py [--latency-jobs 50] [--burst-jobs 500] [--postgresql]

Starts a real redis-server, `percussim serve --no-worker` and two `percussim worker` processes on
loopback, all on this machine (the client too); the job records in the SQLite file of the results
folder, or with --postgresql in a real PostgreSQL server started here. Small case: the Fig. 3 preset (100 cells, 4820
steps, a history row every step and 4 probes in its HDF5 result).

- Latency, one job at a time: from the POST to the first GET that shows it succeeded (polled
  every 2 ms); p50 and p95.
- Sustained: a burst of jobs submitted as fast as one client can, jobs per second from the first
  submission to the last success, every job accounted for; p50 and p95 of each job's time from its
  submission to its `finished` timestamp (queueing included).
- The job's parts, in this process: the solve alone and the solve streaming its HDF5 result, best
  of many.
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
from contextlib import nullcontext
from datetime import datetime
from pathlib import Path

from percussim.solver.controller import warm_up
from percussim.solver.presets import load_preset, preset_json
from percussim.solver.simulate import simulate
from percussim.testing.live_stack import Stack, postgres_server, redis_server

FINISHED = ("succeeded", "failed", "cancelled")


def percentiles(values: list[float]) -> str:
    values = sorted(values)
    p95 = values[min(len(values) - 1, round(0.95 * len(values)) - 1)]
    return f"p50 {statistics.median(values) * 1e3:.1f} ms, p95 {p95 * 1e3:.1f} ms"


def wait_finished(stack: Stack, job_id: str) -> dict:
    while True:
        record = stack.client.get(f"/v1/jobs/{job_id}").json()
        if record["status"] in FINISHED:
            return record
        time.sleep(0.002)


def best(action, seconds: float = 1.0) -> float:
    times, deadline = [], time.perf_counter() + seconds
    while time.perf_counter() < deadline or len(times) < 5:
        start = time.perf_counter()
        action()
        times.append(time.perf_counter() - start)
    return min(times)


def job_parts() -> None:
    case = load_preset("fig3")
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "result.h5"
        solve = best(lambda: simulate(case))
        solve_and_write = best(lambda: simulate(case, result_path=path))
        size = path.stat().st_size
    print(
        f"a Fig. 3 job's parts in one process: solve {solve * 1e3:.2f} ms; solve streaming its HDF5 "
        f"result {solve_and_write * 1e3:.2f} ms, so writing {(solve_and_write - solve) * 1e3:.2f} ms "
        f"({size / 1e6:.2f} MB)"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--latency-jobs", type=int, default=50)
    parser.add_argument("--burst-jobs", type=int, default=500)
    parser.add_argument("--postgresql", action="store_true", help="the job records in PostgreSQL")
    args = parser.parse_args()
    warm_up()
    job_parts()
    case = preset_json("fig3")
    with (
        tempfile.TemporaryDirectory() as tmp,
        redis_server(Path(tmp) / "redis") as url,
        postgres_server() if args.postgresql else nullcontext() as postgres,
    ):
        env = {"PERCUSSIM_DATABASE_URL": postgres.database()} if postgres else {}
        print(f"job records in {'PostgreSQL' if postgres else 'SQLite'}")
        stack = Stack(Path(tmp), url, workers=2, env=env)
        try:
            latencies = []
            for _ in range(args.latency_jobs):
                start = time.perf_counter()
                job = stack.client.post("/v1/jobs", json=case).json()
                assert wait_finished(stack, job["id"])["status"] == "succeeded"
                latencies.append(time.perf_counter() - start)
            print(f"latency, one job at a time ({args.latency_jobs} jobs): {percentiles(latencies)}")

            start, submitted = time.perf_counter(), {}
            for _ in range(args.burst_jobs):
                answer = stack.client.post("/v1/jobs", json=case)
                assert answer.status_code == 202, answer.text
                submitted[answer.json()["id"]] = time.time()
            posting = time.perf_counter() - start
            records = [wait_finished(stack, job_id) for job_id in submitted]
            elapsed = time.perf_counter() - start
            outcomes = [r["status"] for r in records]
            counts = {s: outcomes.count(s) for s in sorted(set(outcomes))}
            in_service = [datetime.fromisoformat(r["finished"]).timestamp() - submitted[r["id"]] for r in records]
            running = [
                datetime.fromisoformat(r["finished"]).timestamp() - datetime.fromisoformat(r["started"]).timestamp()
                for r in records
            ]
            print(
                f"sustained, a burst of {args.burst_jobs} jobs on 2 workers: posted in {posting:.2f} s, "
                f"all finished after {elapsed:.2f} s: {args.burst_jobs / elapsed:.1f} jobs/s; "
                f"outcomes {counts} ({args.burst_jobs - len(records)} unaccounted for)"
            )
            print(f"  submission to finished: {percentiles(in_service)}; in the worker: {percentiles(running)}")
        finally:
            stack.stop()


if __name__ == "__main__":
    main()
