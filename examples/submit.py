"""Worked example: submit a preset to a running percussim service and print its pulse summary.

    .venv/bin/python examples/submit.py [--url http://127.0.0.1:8000] [--preset fig3] [--output fig3.h5]
"""

from __future__ import annotations

import argparse
import json
import time

import httpx


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--url", default="http://127.0.0.1:8000")
    parser.add_argument("--preset", default="fig3")
    parser.add_argument("--output", help="also download the HDF5 result here")
    args = parser.parse_args()

    with httpx.Client(base_url=args.url, timeout=30) as api:
        case = api.get(f"/v1/presets/{args.preset}").raise_for_status().json()
        job = api.post("/v1/jobs", json=case).raise_for_status().json()
        print(f"submitted {args.preset} as job {job['id']}")
        while job["status"] in ("queued", "running"):
            time.sleep(0.2)
            job = api.get(f"/v1/jobs/{job['id']}").raise_for_status().json()
            print(f"  {job['status']:9s} {100 * job['progress']:5.1f} %")
        if job["status"] != "succeeded":
            raise SystemExit(f"job {job['status']}: {job['error']}")
        summary = api.get(f"/v1/jobs/{job['id']}/summary").raise_for_status().json()
        print(json.dumps({k: summary[k] for k in (
            "co_impact_time", "peak_contact_force", "max_compressive_stress", "max_tensile_stress",
            "striker_rebound_velocity", "energy", "warnings")}, indent=2))
        if args.output:
            with open(args.output, "wb") as f:
                f.write(api.get(f"/v1/jobs/{job['id']}/result.h5").raise_for_status().content)
            print(f"result written to {args.output}")


if __name__ == "__main__":
    main()
