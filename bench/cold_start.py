"""Cold start: how soon a fresh process gives its first result, with the kernel in Numba's cache
(`percussim warmup`, run by scripts/bootstrap and the image build, puts it there).

    .venv/bin/python bench/cold_start.py [--repeat 5]

1. A fresh `percussim run fig3`: wall time of the whole process, and inside a
   fresh interpreter the time to import the solver, the first run (which loads the kernel from the
   cache) and a second one.
2. A fresh `percussim worker` (Redis, the API running): the worker process is started, a Fig. 3
   job is submitted once the worker is ready, and the job's own record gives the time from the
   worker taking it to its result being stored; also from the worker's launch to that result.
3. Compiling the kernel into an empty cache (after any change to the solver's sources), once in
   one process and once with the flight compiled in a second (`percussim warmup` on two cores).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from datetime import datetime
from pathlib import Path

from percussim.solver.controller import warm_up
from percussim.solver.presets import preset_json
from percussim.testing.live_stack import Stack, redis_server, wait_for

ROOT = Path(__file__).resolve().parents[1]

PROBE = """
import json, time
start = time.perf_counter()
from percussim.solver.presets import load_preset
from percussim.solver.simulate import simulate
imported = time.perf_counter()
case = load_preset("fig3")
simulate(case)
first = time.perf_counter()
simulate(case)
second = time.perf_counter()
print(json.dumps({"import": imported - start, "first run": first - imported, "second run": second - first}))
"""


def line(label: str, values: list[float]) -> str:
    return f"  {label:34s} best {min(values) * 1e3:7.1f} ms   median {statistics.median(values) * 1e3:7.1f} ms"


def fresh_process(repeat: int) -> None:
    walls, phases = [], []
    for _ in range(repeat):
        start = time.perf_counter()
        subprocess.run([sys.executable, "-m", "percussim", "run", "fig3"], cwd=ROOT, check=True, capture_output=True)
        walls.append(time.perf_counter() - start)
        phases.append(
            json.loads(
                subprocess.run(
                    [sys.executable, "-c", PROBE], cwd=ROOT, check=True, capture_output=True, text=True
                ).stdout
            )
        )
    print("A fresh process (percussim run fig3):")
    print(line("whole process, wall", walls))
    for phase in phases[0]:
        print(line(phase, [p[phase] for p in phases]))


def fresh_worker(repeat: int) -> None:
    took, from_launch = [], []
    with tempfile.TemporaryDirectory() as tmp, redis_server(Path(tmp) / "redis") as url:
        stack = Stack(Path(tmp), url, workers=1)
        try:
            for k in range(repeat):
                old = stack.processes.pop()
                old.stop()
                launched = time.time()
                stack.add_worker(f"fresh{k}")
                name = f"fresh{k}@percussim"
                wait_for(
                    lambda: name in stack.client.get("/readyz").json().get("workers", []),
                    60,
                    "the fresh worker",
                    interval=0.02,
                )
                job = stack.client.post("/v1/jobs", json=preset_json("fig3")).json()
                record = stack.wait_status(job["id"], ("succeeded", "failed"))
                assert record["status"] == "succeeded" and record["worker"] == name, record
                started, finished = (datetime.fromisoformat(record[k]).timestamp() for k in ("started", "finished"))
                took.append(finished - started)
                from_launch.append(finished - launched)
        finally:
            stack.stop()
    print("A fresh worker (percussim worker, Redis), its first job, Fig. 3:")
    print(line("taken to stored", took))
    print(line("worker launched to job stored", from_launch))


def compiling() -> None:
    print("Compiling the kernel into an empty cache (warm_up):")
    for processes in (1, 2):
        with tempfile.TemporaryDirectory() as cache:
            start = time.perf_counter()
            subprocess.run(
                [sys.executable, "-c", f"from percussim.solver.controller import warm_up; warm_up({processes})"],
                cwd=ROOT,
                env={**os.environ, "NUMBA_CACHE_DIR": cache},
                check=True,
            )
            print(f"  {processes} process{'es' if processes > 1 else '':2s}  {time.perf_counter() - start:6.1f} s")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    warm_up()  # the cache as after install
    fresh_process(args.repeat)
    fresh_worker(args.repeat)
    compiling()


if __name__ == "__main__":
    main()
