"""The job page's fixtures: a live stack with an API key, Debian's Chromium through playwright, and a
page opened with the key stored; helpers that read numbers as the page writes them."""

from __future__ import annotations

import json
import math
import shutil
from decimal import ROUND_HALF_UP, Decimal
from pathlib import Path

import pytest
from playwright.sync_api import Page, expect, sync_playwright

from percussim.testing.live_stack import Stack

KEY = "page-test-key"
HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"
CHROMIUM_ARGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    # Without these Chromium reaches for the internet at start-up.
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]
# A job of a few seconds: long enough to watch it run and cancel it.
LONG = {
    "numerics": {"duration": 1.5, "cells": 600, "time_step": 8.3e-7},
    "outputs": {"history_stride": 100, "probes": []},
}


def chromium() -> str:
    path = "/usr/bin/chromium" if Path("/usr/bin/chromium").exists() else shutil.which("chromium")
    if path is None:
        pytest.fail("Chromium is not installed: scripts/test installs it (Debian's chromium package)")
    return path


def shown(value: float, digits: int = 4) -> str:
    """A number as the page writes it: `digits` significant digits, an exponent below 0.001 and
    from 1e6 up (as JavaScript's toExponential: 8.014e+11, 4.682e-13)."""
    if value == 0:
        return "0"
    if abs(value) < 1e-3 or abs(value) >= 1e6:
        mantissa, exponent = f"{value:.{digits - 1}e}".split("e")
        return f"{mantissa}e{int(exponent):+d}"
    decimals = max(digits - 1 - math.floor(math.log10(abs(value))), 0)
    # JavaScript's toFixed rounds the exact binary value, a tie away from zero (606.25 -> 606.3).
    return str(Decimal(value).quantize(Decimal(1).scaleb(-decimals), rounding=ROUND_HALF_UP))


@pytest.fixture(scope="module")
def stack(tmp_path_factory):
    s = Stack(tmp_path_factory.mktemp("page"), None, workers=1, env={"PERCUSSIM_API_KEYS": KEY})
    s.client.headers["X-API-Key"] = KEY
    yield s
    s.stop()


@pytest.fixture(scope="module")
def browser():
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=chromium(), args=CHROMIUM_ARGS)
        yield browser
        browser.close()


@pytest.fixture
def open_page(browser, stack):
    """Opens the page in a fresh 1280×800 context, with `key` stored or none; a script error
    on any page, or a request anywhere but the service, fails the test."""
    contexts, errors, elsewhere = [], [], []

    def open_(key: str | None) -> Page:
        context = browser.new_context(viewport={"width": 1280, "height": 800}, accept_downloads=True)
        context.set_default_timeout(20_000)
        contexts.append(context)
        if key:
            context.add_init_script(f"localStorage.setItem('percussim.apiKey', {json.dumps(key)})")
        page = context.new_page()
        page.on("pageerror", lambda error: errors.append(error))
        page.on(
            "request",
            lambda request: (
                request.url.startswith((stack.url + "/", "data:", "blob:")) or elsewhere.append(request.url)
            ),
        )
        page.goto(stack.url + "/")
        return page

    yield open_
    for context in contexts:
        context.close()
    assert not errors, errors
    assert not elsewhere, elsewhere


@pytest.fixture
def page(open_page):
    return open_page(KEY)


def case_in_page(page: Page, preset: str) -> dict:
    """The preset chosen, once its case is in the JSON (the last one's may still be there)."""
    page.select_option("#preset", preset)
    page.wait_for_function(
        "(name) => { try { return JSON.parse(document.getElementById('case-json').value).name === name; }"
        " catch { return false; } }",
        arg=preset,
    )
    return json.loads(page.input_value("#case-json"))


def shown_job(page: Page) -> str:
    page.wait_for_url("**/#job=*")
    return page.url.split("#job=")[1]


def fill_json(page: Page, text: str) -> None:
    """Type a case into the JSON view (opened if closed): the form follows it."""
    if not page.locator("#json-panel").evaluate("el => el.open"):
        page.click("#json-panel summary")
    page.fill("#case-json", text)


def drawn(page: Page, chart: str) -> list[dict]:
    """The traces Plotly drew in the chart named `chart`, once it has drawn them."""
    area = page.locator(f"figure[data-chart={chart}] .plot-area")
    expect(area.locator(".main-svg").first).to_be_attached()
    return area.evaluate("el => el.data.map(t => ({name: t.name, x: Array.from(t.x || []), y: Array.from(t.y || [])}))")
