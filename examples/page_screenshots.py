"""Screenshots of the job page, as a designer uses it: the case form with the drawing of the tool,
a job's interactive plots, a comparison of two jobs and a sweep, at 1280 px and on a 390-px phone.

    .venv/bin/python examples/page_screenshots.py [--out docs/images] [--full-page]

It starts `percussim serve` (embedded worker) on a free port with an empty results folder, runs
the Fig. 9 case and a faster striker, and a sweep of the striker's velocity, then drives Debian's
Chromium (playwright) over the page. Each picture is what the window shows (the whole page with
--full-page). The README's pictures of the page are this script's output.
"""

from __future__ import annotations

import argparse
import os
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import httpx
from playwright.sync_api import Page, expect, sync_playwright

from percussim.solver.presets import preset_json

WIDTHS = {"1280": {"width": 1280, "height": 900}, "390": {"width": 390, "height": 844}}
CHROMIUM = "/usr/bin/chromium"
ARGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def wait_until(check, what: str, timeout: float = 60.0):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            value = check()
            if value:
                return value
        except httpx.HTTPError:
            pass
        time.sleep(0.2)
    sys.exit(f"gave up waiting for {what}")


def run_jobs(client: httpx.Client) -> tuple[list[str], str]:
    """The Fig. 9 case with its fields, the same with a striker at 8 m/s, and a sweep of W1."""
    base = preset_json("fig9")
    base["outputs"] = {**base.get("outputs", {}), "fields": True, "field_stride": 8}
    faster = {**base, "name": "fig9, W1 = 8 m/s", "striker": {**base["striker"], "velocity": 8.0}}
    jobs = [client.post("/v1/jobs", json=case).json()["id"] for case in (base, faster)]
    sweep = client.post(
        "/v1/sweeps", json={"case": preset_json("fig9"), "parameters": {"striker.velocity": [3.0, 4.5, 6.0, 7.5, 9.0]}}
    ).json()["id"]
    wait_until(lambda: all(client.get(f"/v1/jobs/{j}").json()["status"] == "succeeded" for j in jobs), "the jobs")
    wait_until(lambda: client.get(f"/v1/sweeps/{sweep}").json()["finished"], "the sweep")
    return jobs, sweep


def settle(page: Page) -> None:
    """Every chart drawn, nothing still loading."""
    page.wait_for_function("() => !document.querySelector('.plot-area.loading')")
    page.wait_for_timeout(300)


def shoot(page: Page, out: Path, name: str, width: str, full_page: bool) -> None:
    path = out / f"page-{name}-{width}.png"
    page.screenshot(path=path, full_page=full_page)
    print(path)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", default="docs/images", help="folder for the PNGs (default docs/images)")
    parser.add_argument("--full-page", action="store_true", help="the whole page, not only the window")
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    port = free_port()
    url = f"http://127.0.0.1:{port}"
    with tempfile.TemporaryDirectory() as results:
        env = {k: v for k, v in os.environ.items() if not k.startswith("PERCUSSIM_")} | {
            "PERCUSSIM_RESULTS_DIR": results
        }
        server = subprocess.Popen(
            [sys.executable, "-m", "percussim", "serve", "--port", str(port)],
            env=env,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            start_new_session=True,
        )
        try:
            with httpx.Client(base_url=url, timeout=30) as client:
                wait_until(lambda: client.get("/readyz").status_code == 200, "the service")
                jobs, sweep = run_jobs(client)
            with sync_playwright() as playwright:
                browser = playwright.chromium.launch(executable_path=CHROMIUM, args=ARGS)
                for width, viewport in WIDTHS.items():
                    page = browser.new_page(viewport=viewport)
                    # The case form beside a job's summary and plots.
                    page.goto(f"{url}/#job={jobs[0]}")
                    expect(page.locator("[data-quantity=peak_contact_force]")).to_be_visible()
                    settle(page)
                    page.select_option("#preset", "fig8")  # a stepped tool, drawn to scale
                    expect(page.locator("#drawing svg")).to_be_visible()
                    page.evaluate("() => document.getElementById('case-panel').scrollIntoView()")
                    shoot(page, out, "form", width, args.full_page)
                    page.evaluate("() => document.getElementById('plots').scrollIntoView()")
                    shoot(page, out, "job", width, args.full_page)
                    page.goto(f"{url}/#compare={','.join(jobs)}")
                    page.reload()
                    expect(page.locator("#comparison table").first).to_be_visible()
                    settle(page)
                    shoot(page, out, "compare", width, args.full_page)
                    page.goto(f"{url}/#sweep={sweep}")
                    page.reload()
                    expect(page.locator("#sweep-view .sweep-status")).to_have_text("succeeded")
                    settle(page)
                    shoot(page, out, "sweep", width, args.full_page)
                    page.close()
                browser.close()
        finally:
            os.killpg(server.pid, 15)
            server.wait(timeout=30)


if __name__ == "__main__":
    main()
