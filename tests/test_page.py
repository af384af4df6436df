"""The job page in headless Chromium against the live stack (real API, real embedded worker).

The service runs with an API key, so every image and the HDF5 are seen to come through `fetch()`
with the key: a plain `<img src>` or link would get 401.
"""

from __future__ import annotations

import json
import math
import shutil
from decimal import ROUND_HALF_UP, Decimal
from pathlib import Path

import pytest
from playwright.sync_api import Page, expect, sync_playwright

from conftest import merge
from live_stack import Stack
from percussim.solver.presets import preset_json
from closed_forms import drilling

pytestmark = pytest.mark.slow  # a live stack, a browser or the solver's full reports

KEY = "page-test-key"
HDF5_SIGNATURE = b"\x89HDF\r\n\x1a\n"
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                 # Without these Chromium reaches for the internet at start-up.
                 "--disable-background-networking", "--disable-component-update", "--disable-sync"]
# A job of a few seconds: long enough to watch it run and cancel it.
LONG = {"numerics": {"duration": 1.5, "cells": 600, "time_step": 8.3e-7},
        "outputs": {"history_stride": 100, "probes": []}}


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
    on any page fails the test."""
    contexts, errors = [], []

    def open_(key: str | None) -> Page:
        context = browser.new_context(viewport={"width": 1280, "height": 800}, accept_downloads=True)
        context.set_default_timeout(20_000)
        contexts.append(context)
        if key:
            context.add_init_script(f"localStorage.setItem('percussim.apiKey', {json.dumps(key)})")
        page = context.new_page()
        page.on("pageerror", lambda error: errors.append(error))
        page.goto(stack.url + "/")
        return page

    yield open_
    for context in contexts:
        context.close()
    assert not errors, errors


@pytest.fixture
def page(open_page):
    return open_page(KEY)


def _case_in_page(page: Page, preset: str) -> dict:
    page.select_option("#preset", preset)
    expect(page.locator("#case-json")).not_to_be_empty()
    return json.loads(page.input_value("#case-json"))


def _shown_job(page: Page) -> str:
    page.wait_for_url("**/#job=*")
    return page.url.split("#job=")[1]


def test_without_a_key_the_page_asks_for_one_then_works(open_page):
    page = open_page(None)
    expect(page.locator("#key-needed")).to_contain_text("needs an API key")
    page.fill("#api-key", KEY)
    page.click("#key-form button")
    expect(page.locator("#key-needed")).to_be_hidden()
    expect(page.locator("#preset option[value=fig9]")).to_have_count(1)
    assert page.evaluate("localStorage.getItem('percussim.apiKey')") == KEY


def test_a_preset_runs_to_its_summary_plots_and_hdf5(page, stack):
    _case_in_page(page, "fig9")
    page.click("#submit")
    row = page.locator("[data-quantity=peak_contact_force]")
    expect(row).to_be_visible()
    job_id = _shown_job(page)
    summary = stack.client.get(f"/v1/jobs/{job_id}/summary").json()

    def cells(quantity: str) -> list[str]:
        return [t.strip() for t in page.locator(f"[data-quantity={quantity}] td").all_inner_texts()]

    peak, compressive = summary["peak_contact_force"], summary["max_compressive_stress"]
    estimate = summary["error_estimate"]

    def error(quantity: str) -> str:
        return f"±{shown(100 * estimate[quantity], 2)}%"

    assert cells("co_impact_time")[:3] == [shown(summary["co_impact_time"] * 1e6), "µs",
                                           error("co_impact_time")]
    assert cells("peak_contact_force") == [shown(peak["value"] / 1e3), "kN", error("peak_contact_force"),
                                           "", shown(peak["time"] * 1e6)]
    assert cells("max_compressive_stress") == [shown(compressive["value"] / 1e6), "MPa",
                                               error("max_compressive_stress"),
                                               shown(compressive["x"] * 1e3), shown(compressive["time"] * 1e6)]
    assert cells("striker_rebound_velocity")[:2] == [shown(summary["striker_rebound_velocity"]), "m/s"]
    # the preset keeps the paper's own numerics, whose errors are over 1%: marked, and said
    over = [q for q, e in estimate.items() if q != "worst" and e > 0.01]
    assert over and page.locator("td.error.over").count() == len(over)
    expect(page.locator("#summary .banner.warning")).to_contain_text("estimated errors over 1%")
    to_medium = page.locator("[data-energy=to_medium] .value").inner_text()
    assert to_medium == shown(summary["energy"]["to_medium"])

    plots = stack.client.get(f"/v1/jobs/{job_id}/plots").json()["plots"]
    available = [p["name"] for p in plots if p["available"]]
    assert available, plots
    for plot in plots:
        figure = page.locator(f"figure[data-plot={plot['name']}]")
        if plot["available"]:
            image = figure.locator("img")
            expect(image).to_be_visible()
            assert image.evaluate("img => img.complete && img.naturalWidth > 0"), plot["name"]
        else:
            expect(figure).to_contain_text(plot["reason"])
    page.click(f"figure[data-plot={available[0]}] img")  # full size, the SVG
    enlarged = page.locator("#lightbox img")
    expect(enlarged).to_be_visible()
    page.wait_for_function("() => document.querySelector('#lightbox img').naturalWidth > 0")
    page.keyboard.press("Escape")
    expect(enlarged).to_be_hidden()

    with page.expect_download() as download:
        page.click("#download")
    assert download.value.suggested_filename == f"fig9-{job_id}.h5"
    assert Path(download.value.path()).read_bytes()[:8] == HDF5_SIGNATURE


def test_a_refused_case_shows_every_field_and_message(page, stack):
    case = merge(_case_in_page(page, "fig9"), {"striker": {"mass": -1.0}, "contact": {"exponent": 0.9}})
    refused = stack.client.post("/v1/jobs", json=case)
    assert refused.status_code == 422
    page.fill("#case-json", json.dumps(case, indent=2))
    page.click("#submit")
    problems = page.locator("#case-errors tbody tr")
    expect(problems).to_have_count(len(refused.json()["detail"]))
    rows = [dict(zip(("field", "message"), r.locator("td").all_inner_texts())) for r in problems.all()]
    assert rows == refused.json()["detail"]
    assert "striker.mass" in [r["field"] for r in rows]

    # A syntax error is reported where it is, and nothing is sent.
    before = stack.client.get("/v1/jobs").json()["total"]
    page.fill("#case-json", '{"name": "x",\n  "striker": {"mass": 1,}\n}')
    page.click("#submit")
    expect(page.locator("#case-errors")).to_contain_text("not valid JSON")
    expect(page.locator("#case-errors td").first).to_have_text("line 2, column 25")
    assert stack.client.get("/v1/jobs").json()["total"] == before


def test_a_running_job_shows_progress_can_be_cancelled_and_reopened(page, stack):
    page.fill("#case-json", json.dumps(merge(preset_json("fig3"), LONG)))
    page.click("#submit")
    expect(page.locator("#job-status")).to_have_text("running")
    page.wait_for_function("() => parseFloat(document.querySelector('#progress-bar').style.width) > 0")
    job_id = _shown_job(page)
    page.click("#cancel")
    expect(page.locator("#job-status")).to_have_text("cancelled")
    assert stack.client.get(f"/v1/jobs/{job_id}").json()["status"] == "cancelled"

    # An earlier job, opened from the recent jobs list, shows its summary.
    done = stack.client.post("/v1/jobs", json=preset_json("fig3")).json()["id"]
    stack.wait_status(done, ("succeeded",))
    page.click("#refresh-jobs")
    page.click(f"[data-job='{done}']")
    expect(page.locator("[data-quantity=co_impact_time]")).to_be_visible()
    assert _shown_job(page) == done


def test_stress_along_the_tool_is_redrawn_at_the_times_asked(page, stack):
    case = merge(_case_in_page(page, "fig9"), {"outputs": {"fields": True, "field_stride": 16}})
    page.fill("#case-json", json.dumps(case, indent=2))
    page.click("#submit")
    figure = page.locator("figure[data-plot=stress_along]")
    image = figure.locator("img")
    expect(image).to_be_visible()
    first = image.get_attribute("src")
    figure.locator("input").fill("50, 100, 150")
    figure.locator("button").click()
    expect(image).not_to_have_attribute("src", first)
    page.wait_for_function(
        "() => document.querySelector('figure[data-plot=stress_along] img').naturalWidth > 0")
    # A time outside the run is named by the service, shown under the plot.
    figure.locator("input").fill("1e9")
    figure.locator("button").click()
    expect(figure.locator(".times-error")).to_contain_text("outside the run's fields")


def test_a_run_of_blows_shows_its_table_penetration_and_plots(page, stack):
    """An elastic piston drilling rock, three blows: the blows table row by row, the penetration
    among the pulse's figures, an energy audit that closes with the terms these models add, and
    the blows and force–penetration plots (the energy budget over time says why it is not drawn)."""
    case = {**drilling(3, {"scheme": "explicit", "cells": 100}), "name": "drilling"}
    page.fill("#case-json", json.dumps(case, indent=2))
    page.click("#submit")
    rows = page.locator("table.blows tbody tr")
    expect(rows).to_have_count(3)
    job_id = _shown_job(page)
    summary = stack.client.get(f"/v1/jobs/{job_id}/summary").json()
    for row, blow in zip(rows.all(), summary["blows"]):
        assert [t.strip() for t in row.locator("th, td").all_inner_texts()][1:] == [
            shown(blow["peak_contact_force"] / 1e3), shown(blow["max_compressive_stress"] / 1e6),
            shown(blow["to_medium"]), shown(100 * blow["transfer_efficiency"]),
            shown(blow["permanent_penetration"] * 1e3), shown(blow["set"] * 1e3)]
    assert rows.nth(2).get_attribute("data-blow") == "3"

    def value(quantity: str) -> str:
        return page.locator(f'[data-quantity="{quantity}"] .value').inner_text()

    assert value("medium_penetration.permanent") == shown(summary["medium_penetration"]["permanent"] * 1e3)
    assert value("medium_penetration.max") == shown(summary["medium_penetration"]["max"] * 1e3)
    assert value("energy.transfer_efficiency") == shown(100 * summary["energy"]["transfer_efficiency"])
    energy = summary["energy"]
    for term in ("medium_plastic", "striker_withdrawn"):
        assert energy[term] > 0
        assert page.locator(f"[data-energy={term}] .value").inner_text() == shown(energy[term])
    # every term the input ends as is listed: what is left over is none
    expect(page.locator("table.energy tr.total").last.locator("td").first).to_have_text("0")

    # the energy budget too: the history records what each relaunch brings and takes away
    for name in ("blows", "force_penetration", "energy"):
        image = page.locator(f"figure[data-plot={name}] img")
        expect(image).to_be_visible()
        assert image.evaluate("img => img.complete && img.naturalWidth > 0"), name


def test_a_calibration_from_an_uploaded_record_shows_its_fit(page, stack, tmp_path):
    """A CSV record chosen from disk, the form's two stiffnesses: the page shows the service's fit
    (values, standard errors, bounds, correlation, the overlay plot) and loads the fitted case; a
    record's bad sample is named with its line in the file, a file that is no record is not sent."""
    from percussim.solver.record import parse_record, record_to_csv
    from test_calibrate import BOUNDS, other_setting_record, start_case

    names = ("contact.stiffness", "medium.stiffness")
    page.fill("#case-json", json.dumps(start_case(names), indent=2))
    page.click("#calibration-panel summary")
    record = other_setting_record("stress")
    (tmp_path / "record.csv").write_text(record_to_csv(parse_record(record)))
    page.set_input_files("#record-file", str(tmp_path / "record.csv"))
    expect(page.locator("#record-info")).to_contain_text(f"{len(record['time'])} samples of stress at x = 0.3000 m")
    starting = {}  # the form's rows: field, low, high
    for row in page.locator("#fit-parameters tbody tr").all():
        field, low, high = (c.input_value() for c in row.locator("input").all())
        starting[field] = [float(low), float(high)]
    assert starting == {name: BOUNDS[name] for name in names}
    page.click("#fit")
    expect(page.locator("#job-status")).to_have_text("succeeded", timeout=60_000)
    study = stack.client.get(f"/v1/calibrations/{_shown_job(page)}").json()
    fit = study["fit"]
    for name in names:
        cells = [t.strip() for t in page.locator(f"[data-parameter='{name}'] td").all_inner_texts()]
        p = fit["parameters"][name]
        assert cells == [shown(p["value"]), shown(p["standard_error"]),
                         shown(100 * p["standard_error"] / p["value"], 2), shown(p["low"]), shown(p["high"])]
    correlation = page.locator("table.correlation tbody td").all_inner_texts()
    assert correlation == [shown(r, 3) for row in fit["correlation"] for r in row]
    expect(page.locator(".fit-figures")).to_contain_text(f"{fit['evaluations']} model runs")
    expect(page.locator("#study")).to_contain_text("No warnings." if not fit["warnings"] else fit["warnings"][0])
    image = page.locator("figure[data-plot=calibration] img")
    expect(image).to_be_visible()
    assert image.evaluate("img => img.complete && img.naturalWidth > 0")
    assert page.locator("#download").is_hidden()  # a study has no HDF5 result
    page.get_by_role("button", name="Load the fitted case").click()
    assert json.loads(page.input_value("#case-json")) == fit["case"]

    # A sample that is not a number: the service names it, the page adds its line in the file.
    lines = record_to_csv(parse_record(record)).splitlines()
    lines[6] = lines[6].split(",")[0] + ",nan"  # sample 5: the header is line 1
    (tmp_path / "nan.csv").write_text("\n".join(lines) + "\n")
    page.set_input_files("#record-file", str(tmp_path / "nan.csv"))
    page.click("#fit")
    problems = page.locator("#calibration-errors td.field")
    expect(problems.first).to_have_text("record.values[5] (line 7)")
    (tmp_path / "plain.csv").write_text("t;force\n0;1\n")
    before = stack.client.get("/v1/jobs").json()["total"]
    page.set_input_files("#record-file", str(tmp_path / "plain.csv"))
    expect(page.locator("#calibration-errors")).to_contain_text("plain.csv is not a record")
    expect(problems.first).to_have_text("line 1")
    page.click("#fit")
    expect(page.locator("#calibration-errors")).to_contain_text("Choose the record's CSV file first")
    assert stack.client.get("/v1/jobs").json()["total"] == before


def test_an_optimisation_shows_its_progress_and_best_design(page, stack):
    """The rock drill's piston length and speed for the most energy into the rock within a stress
    limit: the progress bar moves while it runs, then the best design, its limit, every run and
    the convergence plot are those of the API's answer; an unknown quantity is named."""
    case = preset_json("rock_drill")
    page.fill("#case-json", json.dumps(case, indent=2))
    page.click("#optimization-panel summary")
    page.fill("#variables tbody tr:first-child td:nth-child(1) input", "striker.length")
    page.get_by_role("button", name="add a field").click()
    second = page.locator("#variables tbody tr").nth(1).locator("input")
    for cell, text in zip(second.all(), ("striker.velocity", "5", "20")):
        cell.fill(text)
    page.select_option("#goal", "maximize")
    page.fill("#objective", "energy.to_medium")
    page.get_by_role("button", name="add a limit").click()
    limit = page.locator("#limits tbody tr").first
    limit.locator("input").first.fill("max_compressive_stress")
    limit.locator("select").select_option("max")
    limit.locator("input").last.fill("250e6")
    page.fill("#evaluations", "300")
    # Every (status, progress) the page shows, as it shows it.
    page.evaluate("""() => {
        window.seen = [];
        new MutationObserver(() => window.seen.push([document.querySelector('#job-status').textContent,
            parseFloat(document.querySelector('#progress-bar').style.width)]))
          .observe(document.querySelector('#progress-bar'), {attributes: true, childList: true});
    }""")
    page.click("#optimize")
    expect(page.locator("#job-status")).to_have_text("succeeded", timeout=120_000)
    seen = page.evaluate("window.seen")
    assert any(status == "running" and 0 < width < 100 for status, width in seen), seen
    optimum = stack.client.get(f"/v1/optimizations/{_shown_job(page)}").json()["optimum"]
    assert optimum["quantities"]["max_compressive_stress"] <= 250e6
    for path in ("striker.length", "striker.velocity"):
        value = page.locator(f"table.optimum [data-variable='{path}'] .value")
        expect(value).to_have_text(shown(optimum["values"][path]))
    for name in ("energy.to_medium", "max_compressive_stress"):
        value = page.locator(f"table.optimum [data-quantity='{name}'] .value")
        expect(value).to_have_text(shown(optimum["quantities"][name]))
    expect(page.locator("#study .stopped")).to_contain_text(optimum["stopped"])
    page.click("#study details.history summary")
    expect(page.locator("table.history tbody tr")).to_have_count(optimum["evaluations"])
    expect(page.locator("#study table.pulse")).to_be_visible()  # the best design's pulse summary
    image = page.locator("figure[data-plot=optimization] img")
    expect(image).to_be_visible()
    assert image.evaluate("img => img.complete && img.naturalWidth > 0")
    with page.expect_download() as download:
        page.get_by_role("button", name="Download the runs (CSV)").click()
    assert len(Path(download.value.path()).read_text().splitlines()) == optimum["evaluations"] + 1

    page.fill("#objective", "energy.to_rock")
    page.click("#optimize")
    expect(page.locator("#optimization-errors td.field").first).to_have_text("objective.maximize")
