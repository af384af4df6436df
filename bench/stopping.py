"""How `percussim serve` (the embedded default: the API and a worker) stops, by the signal a
stop sends and to which processes, with jobs queued and one running.

    .venv/bin/python bench/stopping.py [--repeat 6]

Each time a fresh service gets 30 Fig. 3 jobs, and half a second later one of:
- SIGTERM to the service's process alone (`docker stop`, `kill PID`, systemd's KillMode=mixed);
- SIGINT to every process of its group at once (Ctrl-C in a terminal);
- SIGTERM to every process of its group at once (systemd's default KillMode=control-group).
Printed: the seconds until the service has exited, and how many times the running job was cut
(its pool process killed mid-job, which Celery logs; the queue hands the job out again).
"""

from __future__ import annotations

import argparse
import signal
import statistics
import tempfile
import time
from pathlib import Path

from percussim.solver.presets import preset_json
from percussim.testing.live_stack import Stack

WAYS = {
    "SIGTERM to the service alone": (signal.SIGTERM, False),
    "SIGINT to its whole group (Ctrl-C)": (signal.SIGINT, True),
    "SIGTERM to its whole group": (signal.SIGTERM, True),
}


def stop_once(sig: signal.Signals, group: bool) -> tuple[float, bool]:
    with tempfile.TemporaryDirectory() as folder:
        stack = Stack(Path(folder), None, workers=1)
        try:
            for _ in range(30):
                stack.client.post("/v1/jobs", json=preset_json("fig3"))
            time.sleep(0.5)
            start = time.monotonic()
            stack.processes[0].signal(sig, everyone=group)
            stack.processes[0].popen.wait(60)
            took = time.monotonic() - start
        finally:
            stack.stop()
        return took, "exited with 'signal" in (Path(folder) / "api.log").read_text()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=6)
    args = parser.parse_args()
    for way, (sig, group) in WAYS.items():
        runs = [stop_once(sig, group) for _ in range(args.repeat)]
        times = [t for t, _ in runs]
        cut = sum(c for _, c in runs)
        print(
            f"{way:36s} stopped in median {statistics.median(times):.2f} s (min {min(times):.2f}, "
            f"max {max(times):.2f}); the running job cut {cut} of {args.repeat} times"
        )


if __name__ == "__main__":
    main()
