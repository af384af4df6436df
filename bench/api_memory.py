"""The API process's memory: what serving and validating JSON costs it, apart from the workers.

    .venv/bin/python bench/api_memory.py [--jobs 20]

Starts a real redis-server and `percussim serve --no-worker` (the API alone, as deployed) with
one worker on loopback, submits `--jobs` Fig. 3 jobs and as many invalid cases (each answered 422
naming its field), waits for the jobs, and prints the API process's resident set (VmRSS) and its
peak (VmHWM) from /proc, and whether Numba's compiled extensions are mapped into it (the kernel's
import) or not.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

from percussim.solver.presets import preset_json
from percussim.testing.live_stack import Stack, redis_server


def status_kb(pid: int, field: str) -> int:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith(field + ":"):
            return int(line.split()[1])
    raise KeyError(field)


def maps_numba(pid: int) -> bool:
    return any("/numba/" in line for line in Path(f"/proc/{pid}/maps").read_text().splitlines())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--jobs", type=int, default=20)
    args = parser.parse_args()
    case = preset_json("fig3")
    invalid = {**case, "striker": {**case["striker"], "mass": -1.0}}
    with tempfile.TemporaryDirectory() as tmp, redis_server(Path(tmp)) as broker_url:
        stack = Stack(Path(tmp), broker_url, workers=1)
        try:
            api = stack.processes[0].popen.pid
            before = status_kb(api, "VmRSS")
            ids = []
            for _ in range(args.jobs):
                ids.append(stack.client.post("/v1/jobs", json=case).json()["id"])
                refused = stack.client.post("/v1/jobs", json=invalid)
                assert refused.status_code == 422, refused.text
            for job_id in ids:
                stack.wait_status(job_id, ("succeeded",))
            print(f"API process (percussim serve --no-worker), pid {api}:")
            rows = [
                ("resident after start-up", f"{before / 1024:.1f} MB"),
                (
                    f"resident after {args.jobs} jobs and {args.jobs} refusals",
                    f"{status_kb(api, 'VmRSS') / 1024:.1f} MB",
                ),
                ("peak resident (VmHWM)", f"{status_kb(api, 'VmHWM') / 1024:.1f} MB"),
                ("Numba's extensions mapped", "yes" if maps_numba(api) else "no"),
            ]
            for label, value in rows:
                print(f"  {label:<42}{value:>10}")
        finally:
            stack.stop()


if __name__ == "__main__":
    main()
