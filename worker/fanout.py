"""A study's batches of runs spread over the workers: the evaluator of the studies run as jobs
(calibrations, optimisations, bearing graphs, drivability).

A batch is cut into parts (`parts_of`: a variant a part where each is solved to its own
accuracy), each a file in the study's folder (`JobStore.batches`), and a
`percussim.evaluate_part` message is published for each. Whoever creates a part's claim file
first (an exclusive create: atomic on one file system) runs it and writes its answer: any idle
worker, on any machine sharing the results store, and the study's own worker, which works
through the parts too instead of waiting. So a study never waits for a free worker, and a part
whose claimer died (no answer after `STALE_FACTOR` times the expected time) is run again by the
study. A batch of a few milliseconds costs less here than a message: it runs in the study's
process unless it would take `LocalEvaluator.SPREAD_SECONDS` or more (the first batch runs here,
to learn what a run costs). The study says how many of a batch's cases are answered as their
parts' answers come in (its progress, and its chance to be cancelled).
"""

from __future__ import annotations

import json
import os
import shutil
import time
from collections.abc import Callable
from pathlib import Path

from percussim.common.store import write_atomic
from percussim.solver.evaluate import Answered, Batch, LocalEvaluator, evaluate_batch, parts_of

PARTS_PER_WORKER = 2  # parts a batch is cut into, per worker that may take one
POLL_SECONDS = 0.02
STALE_FACTOR = 10.0  # a claimed part with no answer after this × its expected time runs again
MIN_STALE_SECONDS = 30.0


def claim(part: Path) -> bool:
    """Claim `part` (a part's file): True for the one caller that creates its claim first."""
    try:
        os.close(os.open(part.with_suffix(".claim"), os.O_CREAT | os.O_EXCL | os.O_WRONLY))
    except FileExistsError:
        return False
    except FileNotFoundError:  # the study has finished and removed its batches
        return False
    return True


def run_part(part: Path) -> None:
    """Run a claimed part and write its answer beside it."""
    batch = json.loads(part.read_text())
    write_atomic(part.with_suffix(".answer"), json.dumps(evaluate_batch(batch)).encode())


def take_part(folder: Path, index: int) -> bool:
    """A worker's side: run part `index` of the batch in `folder` unless someone has claimed it
    or the study is over. True if it ran it."""
    part = folder / f"{index}.json"
    if not part.is_file() or not claim(part):
        return False
    try:
        run_part(part)
    except FileNotFoundError:  # the study finished meanwhile (it ran the part itself)
        return False
    return True


class QueueEvaluator:
    """Batches of one study: cut, published and claimed as the module's docstring says."""

    def __init__(self, folder: Path, publish: Callable[[int, int], None], workers: int):
        """`folder`: the study's batches; `publish(batch, part)` sends a part's message."""
        self.folder, self.publish = folder, publish
        self.parts = max(1, PARTS_PER_WORKER * workers)
        self.here = LocalEvaluator(1)
        self.batch = 0
        self.runs = {"here": 0, "other_workers": 0}  # how the runs were spread

    def close(self) -> None:
        shutil.rmtree(self.folder, ignore_errors=True)

    def __call__(self, batch: Batch, answered: Answered | None = None) -> list[dict]:
        if not self.here.worth_spreading(batch):
            self.runs["here"] += len(batch["cases"])
            return self.here(batch, answered)
        number, self.batch = self.batch, self.batch + 1
        folder = self.folder / str(number)
        folder.mkdir(parents=True)
        parts = parts_of(batch, self.parts)
        paths = [folder / f"{k}.json" for k in range(len(parts))]
        for path, part in zip(paths, parts):
            write_atomic(path, json.dumps(part).encode())
        for k in range(1, len(paths)):  # the first is the study's own
            self.publish(number, k)
        mine, found = set(), {}

        def collect() -> None:
            """Read the answers written since last time, and say how many cases are answered."""
            fresh = [k for k, path in enumerate(paths) if k not in found and path.with_suffix(".answer").is_file()]
            for k in fresh:
                found[k] = json.loads(paths[k].with_suffix(".answer").read_text())
            if fresh and answered is not None:
                answered(sum(map(len, found.values())))

        for k, path in enumerate(paths):
            if claim(path):
                started = time.perf_counter()
                run_part(path)
                mine.add(k)
                # what a run costs, learnt from the parts run here too (a batch always spread has no other)
                per_run = (time.perf_counter() - started) / len(parts[k]["cases"])
                self.here.run_seconds = max(self.here.run_seconds, per_run)
                collect()
        expected = self.here.run_seconds * max(len(p["cases"]) for p in parts)
        stale = max(MIN_STALE_SECONDS, STALE_FACTOR * expected)
        waited = time.monotonic()
        while True:
            collect()
            missing = [k for k in range(len(paths)) if k not in found]
            if not missing:
                break
            if time.monotonic() - waited > stale:
                run_part(paths[missing[0]])  # its claimer is gone
                mine.add(missing[0])
            else:
                time.sleep(POLL_SECONDS)
        shutil.rmtree(folder, ignore_errors=True)
        for k, part in enumerate(parts):
            self.runs["here" if k in mine else "other_workers"] += len(part["cases"])
        return [answer for k in range(len(paths)) for answer in found[k]]
