"""The interactive plots' data of a long run: how large and how slow each answer is.

    .venv/bin/python bench/series.py [--duration 0.3125] [--field-stride 200] [--repeat 3]

The Fig. 9 preset (100 cells, τ = 3.125e-7 s) run for `--duration` (0.3125 s: 10^6 steps, every
one kept in the histories) with its four probes and the stress field every `--field-stride`
steps, streamed to a temporary HDF5 file. Then, through `solver/series.py` as the API calls it:
the JSON of `force` at the default 2000 points and at every sample (`points=0`), of `energy`
(stride-decimated), of `fields` at its defaults (300 frames × 400 stations at the most), and the
CSV of `force` and of `fields`, every sample. The size in bytes and the best of `--repeat` wall
times, each from opening the file to the last byte.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from percussim.solver.controller import warm_up
from percussim.solver.presets import preset_json
from percussim.solver.series import csv_chunks, dumps, series
from percussim.solver.simulate import simulate
from percussim.testing import merge


def best(make, repeat: int) -> tuple[int, float]:
    """(size in bytes, best wall time in s) of `make()`, which returns the answer's bytes."""
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        size = len(make())
        times.append(time.perf_counter() - start)
    return size, min(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=0.3125)
    parser.add_argument("--field-stride", type=int, default=200)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    case = merge(
        preset_json("fig9"),
        {"numerics": {"duration": args.duration}, "outputs": {"fields": True, "field_stride": args.field_stride}},
    )
    warm_up()
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "long.h5"
        start = time.perf_counter()
        simulate(case, result_path=path)
        print(f"run: {time.perf_counter() - start:.1f} s, {path.stat().st_size / 1e6:.1f} MB")
        rows = series(path, "force")["samples"]
        field = series(path, "fields", times=0, stations=0)["samples"]
        print(f"{rows} samples; fields {field['times']} frames × {field['stations']} stations")
        answers = {
            "force JSON, points=2000": lambda: dumps(series(path, "force")),
            "force JSON, points=0": lambda: dumps(series(path, "force", points=0)),
            "energy JSON, points=2000": lambda: dumps(series(path, "energy")),
            "fields JSON, defaults": lambda: dumps(series(path, "fields")),
            "force CSV": lambda: "".join(csv_chunks(path, "force")).encode(),
            "fields CSV": lambda: "".join(csv_chunks(path, "fields")).encode(),
        }
        print(f"{'answer':<26} {'bytes':>13} {'time (s)':>9}")
        for what, make in answers.items():
            size, wall = best(make, args.repeat)
            print(f"{what:<26} {size:>13,} {wall:>9.3f}")


if __name__ == "__main__":
    main()
