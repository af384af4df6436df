"""Worked example of the solver and its plots in Python: run a preset locally with stress fields
and probes kept, write its HDF5 result and draw every plot it can make (those it cannot, such as
the blows table of a case without blows, are listed with the reason).

    .venv/bin/python examples/plot_preset.py [--preset fig9] [--result out/fig9.h5] [--out out/fig9-plots]

The README's pictures are this script's output for the Fig. 9 preset (`--out docs/images`).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from percussim.solver.case import parse_case
from percussim.solver.io import write_result
from percussim.solver.plots import write_plots
from percussim.solver.presets import preset_json
from percussim.solver.simulate import simulate


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--preset", default="fig9")
    parser.add_argument("--result", help="the HDF5 result (default out/PRESET.h5)")
    parser.add_argument("--out", help="folder for the plots (default out/PRESET-plots)")
    args = parser.parse_args()

    case = preset_json(args.preset)
    # The stress along the tool and its space-time map need the fields, sampled here every 8 steps.
    case["outputs"] = {**case.get("outputs", {}), "fields": True, "field_stride": 8}
    result_path = write_result(simulate(parse_case(case)), args.result or f"out/{args.preset}.h5")
    written, skipped = write_plots(result_path, Path(args.out or f"out/{args.preset}-plots"), formats=("png",))
    for path in written:
        print(path)
    for name, reason in skipped.items():
        print(f"skipped {name}: {reason}")


if __name__ == "__main__":
    main()
