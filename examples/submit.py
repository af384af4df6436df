"""Worked example of the Python client: run a preset on a running percussim service at the default
accuracy (1%, every quantity with its estimated error), print its pulse summary beside the same
case on the paper's own numerics (what they cost and what they lose), read the full histories as
arrays and download the HDF5 result.

    .venv/bin/python examples/submit.py [--url http://127.0.0.1:8000] [--preset fig3] [--output fig3.h5]

`PERCUSSIM_API_KEY` is sent as the API key when set. The same in a few lines:

    from percussim.client import Client

    with Client("http://127.0.0.1:8000") as api:
        paper = api.preset("fig3")
        summary = api.run({**paper, "numerics": {"duration": paper["numerics"]["duration"]}})
"""

from __future__ import annotations

import argparse
import json
import os
from datetime import datetime

from percussim.client import Client

# (label, where in the summary, unit, scale, its name in error_estimate)
QUANTITIES = (
    ("co-impact time", ("co_impact_time",), "µs", 1e6, "co_impact_time"),
    ("peak contact force", ("peak_contact_force", "value"), "kN", 1e-3, "peak_contact_force"),
    ("max compressive stress", ("max_compressive_stress", "value"), "MPa", 1e-6, "max_compressive_stress"),
    ("max tensile stress", ("max_tensile_stress", "value"), "MPa", 1e-6, "max_tensile_stress"),
    ("energy to the medium", ("energy", "to_medium"), "J", 1.0, "energy.to_medium"),
    ("striker rebound velocity", ("striker_rebound_velocity",), "m/s", 1.0, "striker_rebound_velocity"),
)


def at_default_accuracy(case: dict) -> dict:
    """The case with its grid, time step and scheme left out: the solver chooses the grid that
    meets the default accuracy, 1%, and estimates every quantity's error."""
    return {**case, "numerics": {"duration": case["numerics"]["duration"]}}


def solved(api: Client, case: dict, label: str) -> tuple[str, dict, float]:
    """`case` run on the service: its job's id, its summary and its running time (s)."""
    job = api.submit(case)
    print(f"submitted {case['name']} ({label}) as job {job['id']}")
    # Raises JobFailed, with the job's error, if the job fails or is cancelled.
    api.wait(job["id"], progress=lambda fraction, record: print(f"  {record['status']:9s} {100 * fraction:5.1f} %"))
    record = api.job(job["id"])
    seconds = (datetime.fromisoformat(record["finished"]) - datetime.fromisoformat(record["started"])).total_seconds()
    return job["id"], api.summary(job["id"]), seconds


def value(summary: dict, path: tuple[str, ...]) -> float:
    for key in path:
        summary = summary[key]
    return summary


def side_by_side(trusted: tuple[str, dict, float], paper: tuple[str, dict, float]) -> str:
    """Each quantity at the default accuracy and on the paper's numerics, with each one's
    estimated error; then what each cost (node-steps, the job's time) and the energy the scheme lost."""

    def cell(summary: dict, path: tuple[str, ...], scale: float, estimated: str) -> str:
        estimate = (summary["error_estimate"] or {}).get(estimated)
        shown = f"{value(summary, path) * scale:.4g}"
        return f"{shown:>8s} ± {100 * estimate:.2g}%" if estimate is not None else f"{shown:>8s} (not estimated)"

    def work(summary: dict) -> str:
        return f"{sum((r['cells'] + 1) * (r['steps'] + 1) for r in summary['runs']) / 1e6:.2f}M node-steps"

    def grids(summary: dict) -> str:
        return ", ".join(str(r["cells"]) for r in summary["runs"])

    def lost(summary: dict) -> str:
        energy = summary["energy"]
        return f"{energy['numerical']:.3g} J ({100 * energy['numerical'] / energy['initial']:.2g}%)"

    rows = [("", "default accuracy (1%)", "paper numerics")]
    rows += [
        (f"{label} ({unit})", cell(trusted[1], path, scale, estimated), cell(paper[1], path, scale, estimated))
        for label, path, unit, scale, estimated in QUANTITIES
    ]
    rows += [
        ("work", work(trusted[1]), work(paper[1])),
        ("grids (cells)", grids(trusted[1]), grids(paper[1])),
        ("job time", f"{trusted[2] * 1e3:.0f} ms", f"{paper[2] * 1e3:.0f} ms"),
        ("energy lost by the scheme", lost(trusted[1]), lost(paper[1])),
    ]
    return "\n".join(f"{a:32s} {b:24s} {c}" for a, b, c in rows)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--url", default="http://127.0.0.1:8000")
    parser.add_argument("--preset", default="fig3")
    parser.add_argument("--output", help="also download the HDF5 result here")
    args = parser.parse_args()

    with Client(args.url, api_key=os.environ.get("PERCUSSIM_API_KEY")) as api:
        paper_case = api.preset(args.preset)
        trusted = solved(api, at_default_accuracy(paper_case), "the default accuracy")
        job_id, summary, _ = trusted
        print(
            json.dumps(
                {
                    k: summary[k]
                    for k in (
                        "co_impact_time",
                        "peak_contact_force",
                        "max_compressive_stress",
                        "max_tensile_stress",
                        "striker_rebound_velocity",
                        "energy",
                        "error_estimate",
                        "warnings",
                    )
                },
                indent=2,
            )
        )
        # The preset as the paper solved it (its own grid, time step and γ), for comparison.
        paper = solved(api, paper_case, "the paper's numerics")
        print(side_by_side(trusted, paper))
        print("the paper's numerics warn:", *paper[1]["warnings"], sep="\n  ")

        # The full histories, as NumPy arrays under their HDF5 paths: the same Result a local run gives.
        result = api.result(job_id)
        time, force = result.history["time"], result.history["contact/force"]
        peak = force.argmax()
        print(
            f"/contact/force: {len(force)} samples, the largest {force[peak]:.6g} N at t = {time[peak]:.6g} s; "
            f"the summary's peak, refined between samples: {summary['peak_contact_force']['value']:.6g} N"
        )

        if args.output:
            print(f"result written to {api.download(job_id, args.output)}")


if __name__ == "__main__":
    main()
