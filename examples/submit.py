"""Worked example of the Python client: run a preset on a running percussim service, print its
pulse summary, read its full histories as arrays and download the HDF5 result.

    .venv/bin/python examples/submit.py [--url http://127.0.0.1:8000] [--preset fig3] [--output fig3.h5]

`PERCUSSIM_API_KEY` is sent as the API key when set. The same in a few lines:

    from percussim.client import Client

    with Client("http://127.0.0.1:8000") as api:
        summary = api.run(api.preset("fig3"))
"""

from __future__ import annotations

import argparse
import json
import os

from percussim.client import Client


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--url", default="http://127.0.0.1:8000")
    parser.add_argument("--preset", default="fig3")
    parser.add_argument("--output", help="also download the HDF5 result here")
    args = parser.parse_args()

    with Client(args.url, api_key=os.environ.get("PERCUSSIM_API_KEY")) as api:
        job = api.submit(api.preset(args.preset))
        print(f"submitted {args.preset} as job {job['id']}")
        # Raises JobFailed, with the job's error, if the job fails or is cancelled.
        api.wait(job["id"], progress=lambda fraction, record: print(f"  {record['status']:9s} {100 * fraction:5.1f} %"))
        summary = api.summary(job["id"])
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
                        "warnings",
                    )
                },
                indent=2,
            )
        )

        # The full histories, as NumPy arrays under their HDF5 paths: the same Result a local run gives.
        result = api.result(job["id"])
        time, force = result.history["time"], result.history["contact/force"]
        peak = force.argmax()
        print(
            f"/contact/force: {len(force)} samples, the largest {force[peak]:.6g} N at t = {time[peak]:.6g} s; "
            f"the summary's peak, refined between samples: {summary['peak_contact_force']['value']:.6g} N"
        )

        if args.output:
            print(f"result written to {api.download(job['id'], args.output)}")


if __name__ == "__main__":
    main()
