"""Whether a change to the solver left its results bit-identical: every output of 42 runs hashed.

    .venv/bin/python bench/bit_identity.py --write before.json   # on the code before
    .venv/bin/python bench/bit_identity.py --against before.json # on the code after

The runs:
- the nine presets;
- fig3, fig8 and fig9 under the paper, sigma and explicit schemes on 150 cells, with a probe and
  fields;
- three blows of the rock drill, two of the pile;
- an anvil (the explicit scheme on 300 cells).

Each runs twice: with the controller's own chunks, and in chunks of 500 node-steps (many calls of
`advance`). A run's hash covers its summary (less what measures time), its histories and its
probes, to the last bit. Prints each run that differs, or that all are identical.
"""

from __future__ import annotations

import argparse
import hashlib
import json
from pathlib import Path

import numpy as np

from percussim.solver import controller
from percussim.solver.case import parse_case
from percussim.solver.presets import preset_json, preset_names
from percussim.solver.simulate import simulate
from percussim.testing import closed_forms as CF

SMALL_CHUNKS = 500  # node-steps a call of advance


def cases() -> dict[str, dict]:
    found = {name: preset_json(name) for name in preset_names()}
    for name in ("fig3", "fig8", "fig9"):
        for scheme in ("paper", "sigma", "explicit"):
            case = preset_json(name)
            case["numerics"] = {"duration": case["numerics"]["duration"], "scheme": scheme, "cells": 150}
            case["outputs"] = {"probes": [0.1], "fields": True, "field_stride": 50}
            found[f"{name}-{scheme}"] = case
    found["rock_drill-blows"] = preset_json("rock_drill") | {"blows": {"count": 3}}
    found["pile-blows"] = preset_json("pile") | {"blows": {"count": 2}}
    found["anvil"] = CF.anvil_case(
        1.0, {"scheme": "explicit", "cells": 300}, anvil_contact={"stiffness": 5e9, "exponent": 0.0}
    )
    for case in found.values():
        case.pop("description", None)
    return found


def digest(result) -> str:
    summary = {key: value for key, value in result.summary.items() if key != "seconds"}
    parts = [json.dumps(summary, sort_keys=True).encode()]
    parts += [name.encode() + np.ascontiguousarray(values).tobytes() for name, values in sorted(result.history.items())]
    if result.probe_stress is not None:
        parts.append(np.ascontiguousarray(result.probe_stress).tobytes())
    return hashlib.sha256(b"\0".join(parts)).hexdigest()


def run_all() -> dict[str, str]:
    hashes = {}
    default = controller.CHUNK_NODE_STEPS
    try:
        for chunks in (default, SMALL_CHUNKS):
            controller.CHUNK_NODE_STEPS = chunks
            for name, case in cases().items():
                hashes[f"{name}, chunks of {chunks} node-steps"] = digest(simulate(parse_case(case)))
    finally:
        controller.CHUNK_NODE_STEPS = default
    return hashes


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    which = parser.add_mutually_exclusive_group(required=True)
    which.add_argument("--write", metavar="FILE", help="write the hashes of this code's runs")
    which.add_argument("--against", metavar="FILE", help="compare this code's runs with those written")
    args = parser.parse_args()
    hashes = run_all()
    if args.write:
        Path(args.write).write_text(json.dumps(hashes, indent=1))
        print(f"{len(hashes)} runs hashed into {args.write}")
        return
    before = json.loads(Path(args.against).read_text())
    differ = [name for name in before if hashes.get(name) != before[name]]
    for name in differ:
        print(f"differs: {name}")
    print(f"{len(before) - len(differ)} of {len(before)} runs bit-identical")


if __name__ == "__main__":
    main()
