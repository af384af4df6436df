"""End-to-end latency and sustained throughput of the service, through Redis and 2 workers.

    .venv/bin/python bench/service_latency.py [--latency-jobs 50] [--burst-jobs 200]

Starts a real redis-server, `percussim serve --no-worker` and two `percussim worker` processes
on loopback. Latency: one job at a time, from POST to the first GET that shows it succeeded
(polled every 2 ms), for the Fig. 3 preset. Throughput: a burst of jobs submitted at once,
jobs per second from the first submission to the last success; every job is accounted for.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

from live_stack import Stack, redis_server  # noqa: E402
from solver.presets import preset_json  # noqa: E402


def wait_succeeded(stack: Stack, job_id: str) -> str:
    while True:
        status = stack.client.get(f"/v1/jobs/{job_id}").json()["status"]
        if status in ("succeeded", "failed", "cancelled"):
            return status
        time.sleep(0.002)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--latency-jobs", type=int, default=50)
    parser.add_argument("--burst-jobs", type=int, default=200)
    args = parser.parse_args()
    case = preset_json("fig3")

    with tempfile.TemporaryDirectory() as tmp, redis_server(Path(tmp) / "redis") as url:
        stack = Stack(Path(tmp), url, workers=2)
        try:
            latencies = []
            for _ in range(args.latency_jobs):
                start = time.perf_counter()
                job = stack.client.post("/v1/jobs", json=case).json()
                assert wait_succeeded(stack, job["id"]) == "succeeded"
                latencies.append(time.perf_counter() - start)
            latencies.sort()
            p95 = latencies[min(len(latencies) - 1, round(0.95 * len(latencies)) - 1)]
            print(f"latency, Fig. 3 preset, one job at a time ({args.latency_jobs} jobs): "
                  f"p50 {statistics.median(latencies) * 1e3:.1f} ms, p95 {p95 * 1e3:.1f} ms")

            start = time.perf_counter()
            ids = [stack.client.post("/v1/jobs", json=case).json()["id"] for _ in range(args.burst_jobs)]
            submitted = time.perf_counter() - start
            outcomes = [wait_succeeded(stack, job_id) for job_id in ids]
            elapsed = time.perf_counter() - start
            counts = {s: outcomes.count(s) for s in sorted(set(outcomes))}
            print(f"burst of {args.burst_jobs} jobs, 2 workers: submitted in {submitted:.2f} s, "
                  f"all finished after {elapsed:.2f} s: {args.burst_jobs / elapsed:.1f} jobs/s; "
                  f"outcomes {counts}")
        finally:
            stack.stop()


if __name__ == "__main__":
    main()
