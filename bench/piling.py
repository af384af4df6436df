"""The pile studies' wall time: a 10-capacity bearing graph and a 40-depth drivability, each variant
driven until its set settles and solved to the default accuracy (1%), on 2 processes here and as a
job on the service (Redis and 2 workers).

    .venv/bin/python bench/piling.py [--repeats 3]

The pile is the tests' (`percussim.testing.piles`: the pile preset with 1.8 MN of resistance, a
third at the toe and the rest over the shaft's lower 10 m); the bearing graph runs its capacity
from 1.2 to 3.9 MN. The drivability drives it from 0.375 to 15 m
through sand over dense sand, the dense sand's shaft resistance gaining 30% over a pause (so every
depth is also restruck: 80 variants), and once without the setup (40 variants). Times are wall
clock, the kernel compiled beforehand, the best of `--repeats`: here around `bearing_graph` and
`drivability` (a pool of 2 processes, started by each call), on the service from the POST to the
GET that shows the job succeeded (polled every 20 ms).
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from percussim.solver.controller import warm_up
from percussim.solver.pile_studies import bearing_graph, drivability
from percussim.testing import merge
from percussim.testing.live_stack import Stack, redis_server, wait_for
from percussim.testing.piles import LAYER, PILE
from percussim.testing.piles import SOIL as TEST_SOIL

CAPACITIES = [1.2e6 + 3e5 * k for k in range(10)]
SOIL = merge(
    TEST_SOIL,
    {
        "layers": [
            TEST_SOIL["layers"][0],
            {"from": 6.0, "to": 20.0, "shaft_resistance": 5e4, "toe_resistance": 1.2e6, "setup_factor": 1.3, **LAYER},
        ],
        "depths": [0.375 * (k + 1) for k in range(40)],
        "refusal": 250.0,
    },
)
NO_SETUP = merge(SOIL, {"layers": [SOIL["layers"][0], merge(SOIL["layers"][1], {"setup_factor": 1.0})]})
STUDIES = {
    "bearing graph, 10 capacities": ("/v1/bearing-graphs", bearing_graph, {"case": PILE, "capacity": CAPACITIES}),
    "drivability, 40 depths and restrikes": ("/v1/drivability", drivability, {"case": PILE, "soil": SOIL}),
    "drivability, 40 depths": ("/v1/drivability", drivability, {"case": PILE, "soil": NO_SETUP}),
}


def through_service(stack: Stack, route: str, request: dict) -> tuple[dict, float]:
    start = time.perf_counter()
    answer = stack.client.post(route, json=request)
    assert answer.status_code == 202, answer.text
    url = answer.json()["links"]["self"]
    done = wait_for(lambda: (v := stack.client.get(url).json())["status"] == "succeeded" and v, 600, route, 0.02)
    return done, time.perf_counter() - start


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    warm_up()
    with tempfile.TemporaryDirectory() as tmp, redis_server(Path(tmp) / "redis") as url:
        stack = Stack(Path(tmp), url, workers=2)
        try:
            for label, (route, study, request) in STUDIES.items():
                here, served = [], []
                for _ in range(args.repeats):
                    start = time.perf_counter()
                    answer = study(request, processes=2)
                    here.append(time.perf_counter() - start)
                    done, seconds = through_service(stack, route, request)
                    served.append(seconds)
                rows = answer["rows"]
                blows = sum(row["blows"] for row in rows)
                worst = max(row["error_estimate"] or 0.0 for row in rows)
                print(f"\n{label}: {len(rows)} rows, {blows} blows run at accuracy, worst estimated error {worst:.2g}")
                print(f"  here, 2 processes            {min(here):6.2f} s")
                print(f"  service, Redis, 2 workers    {min(served):6.2f} s  (runs spread {done['runs_spread']})")
                if "total_blows" in answer:
                    print(
                        f"  total blows {answer['total_blows']:.4g} to {answer['driven_to']:g} m, driving time "
                        f"{answer['driving_time'] / 60:.3g} min, refusal depth {answer['refusal_depth']}"
                    )
        finally:
            stack.stop()


if __name__ == "__main__":
    main()
