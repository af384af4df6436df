"""The job page's interactive charts and the comparison of jobs, in headless Chromium against the
live stack: the charts' data against the API's series and summary, zoom, hover, the time slider,
the exports (CSV from the service, SVG drawn in the browser at full resolution), and two jobs'
curves overlaid with their summaries side by side."""

from __future__ import annotations

import csv
import io
import json
import re
from pathlib import Path

import pytest
from browser import case_in_page, shown
from playwright.sync_api import Page, expect

from percussim.solver.presets import preset_json
from percussim.testing import merge

pytestmark = pytest.mark.slow  # a live stack and a browser

FIELDS = {"outputs": {"fields": True, "field_stride": 16}}
# The summary's peak force lies between two samples (its time is not a step's), a little above
# the greatest sample: by 1.2e-5 of it in the faster fig9.
PEAK = 1e-4
AGREEMENT = 0.005  # the page's: a difference counted as real when neither job estimates its error


def run(stack, case: dict) -> str:
    job_id = stack.client.post("/v1/jobs", json=case).json()["id"]
    stack.wait_status(job_id, ("succeeded",))
    return job_id


def open_job(page: Page, job_id: str) -> None:
    page.click("#refresh-jobs")
    page.click(f"[data-job='{job_id}']")


def drawn(page: Page, chart: str) -> None:
    page.wait_for_function(f"() => (document.querySelector('[data-chart={chart}] .plot-area')?.data || []).length > 0")


def x_range(page: Page, chart: str) -> list[float]:
    return page.evaluate(f"() => document.querySelector('[data-chart={chart}] .plot-area').layout.xaxis.range")


def plot_box(page: Page, chart: str) -> dict:
    """The plot area's box on the page, in px: the axes' rectangle, not the whole figure."""
    return page.evaluate(f"""() => {{
        const el = document.querySelector('[data-chart={chart}] .plot-area');
        const box = el.getBoundingClientRect(), xa = el._fullLayout.xaxis, ya = el._fullLayout.yaxis;
        return {{x: box.x + xa._offset, y: box.y + ya._offset, width: xa._length, height: ya._length}};
    }}""")


def test_a_jobs_charts_zoom_hover_slide_and_export(page, stack):
    job_id = run(stack, merge(preset_json("fig9"), FIELDS))
    summary = stack.client.get(f"/v1/jobs/{job_id}/summary").json()
    open_job(page, job_id)
    for chart in ("force", "displacements", "probes", "stress_along", "spacetime", "energy", "force_penetration"):
        drawn(page, chart)

    # The peak on screen is every sample's (min–max decimation keeps it), to the JSON's 6 digits,
    # and the summary's, which is found between the samples.
    peak_kn = page.evaluate("() => Math.max(...document.querySelector('[data-chart=force] .plot-area').data[0].y)")
    every = stack.client.get(f"/v1/jobs/{job_id}/series/force?points=0").json()["series"]
    assert peak_kn * 1e3 == pytest.approx(max(every[0]["y"]), rel=1e-12)
    assert peak_kn * 1e3 == pytest.approx(summary["peak_contact_force"]["value"], rel=PEAK)
    expect(page.locator("[data-chart=force] .xtitle")).to_have_text("time t (ms)")  # a 4-ms run
    expect(page.locator("[data-chart=force] .ytitle")).to_have_text("force (kN)")

    # Hover on the peak: its value with its unit (the chart brought into view first, as drawing
    # the charts below it scrolled the page past it).
    page.locator("[data-chart=force]").scroll_into_view_if_needed()
    box = plot_box(page, "force")
    at = page.evaluate("""() => {
        const el = document.querySelector('[data-chart=force] .plot-area'), y = el.data[0].y;
        const k = y.indexOf(Math.max(...y));
        return {x: el._fullLayout.xaxis.l2p(el.data[0].x[k]), y: el._fullLayout.yaxis.l2p(y[k])};
    }""")
    page.mouse.move(box["x"] + at["x"], box["y"] + at["y"])
    hover = page.locator("[data-chart=force] .hoverlayer .hovertext")
    expect(hover).to_have_count(1)
    said = re.search(r"([\d.]+) kN at ([\d.]+) ms", hover.text_content())
    assert said, hover.text_content()
    assert float(said[1]) == pytest.approx(peak_kn, rel=1e-3)
    assert float(said[2]) == pytest.approx(summary["peak_contact_force"]["time"] * 1e3, rel=1e-3)

    # A box dragged over the middle third zooms in on it; the toolbar zooms further and resets.
    whole = x_range(page, "force")
    page.mouse.move(box["x"] + box["width"] / 3, box["y"] + box["height"] / 2)
    page.mouse.down()
    page.mouse.move(box["x"] + box["width"] / 2, box["y"] + box["height"] / 2 + 30, steps=5)
    page.mouse.move(box["x"] + 2 * box["width"] / 3, box["y"] + box["height"] / 2 + 60, steps=5)
    page.mouse.up()
    page.wait_for_function(
        f"() => document.querySelector('[data-chart=force] .plot-area').layout.xaxis.range[1]"
        f" - document.querySelector('[data-chart=force] .plot-area').layout.xaxis.range[0]"
        f" < {(whole[1] - whole[0]) / 2}"
    )
    dragged = x_range(page, "force")
    assert whole[0] < dragged[0] < dragged[1] < whole[1]
    page.click("[data-chart=force] [data-action=zoom-in]")
    page.wait_for_function(
        f"() => {{ const r = document.querySelector('[data-chart=force] .plot-area').layout.xaxis.range;"
        f" return r[1] - r[0] < {0.6 * (dragged[1] - dragged[0])}; }}"
    )
    page.click("[data-chart=force] [data-action=reset]")
    page.wait_for_function(
        f"() => document.querySelector('[data-chart=force] .plot-area').layout.xaxis.range[1] >= {whole[1] - 1e-9}"
    )

    # The slider redraws the stress along the tool at another frame's time.
    slider = page.locator("[data-chart=stress_along] input[type=range]")
    before = page.locator("[data-chart=stress_along] output").inner_text()
    curve = page.evaluate("() => document.querySelector('[data-chart=stress_along] .plot-area').data[0].y")
    slider.focus()
    page.keyboard.press("End")
    expect(page.locator("[data-chart=stress_along] output")).not_to_have_text(before)
    assert re.fullmatch(r"t = [\d.]+ ms", page.locator("[data-chart=stress_along] output").inner_text())
    assert page.evaluate("() => document.querySelector('[data-chart=stress_along] .plot-area').data[0].y") != curve
    fields = stack.client.get(f"/v1/jobs/{job_id}/series/fields").json()
    assert slider.get_attribute("max") == str(len(fields["times"]) - 1)

    # CSV: the service's, every sample; SVG: drawn here from every sample.
    samples = stack.client.get(f"/v1/jobs/{job_id}/series/force?points=10").json()["samples"]
    with page.expect_download() as download:
        page.click("[data-chart=force] [data-action=csv]")
    rows = list(csv.reader(io.StringIO(Path(download.value.path()).read_text())))
    assert len(rows) == 1 + samples and rows[0][0] == "time t (s)"
    with page.expect_download() as download:
        page.click("[data-chart=force] [data-action=svg]")
    assert download.value.suggested_filename == f"fig9-{job_id}-force.svg"
    svg = Path(download.value.path()).read_text()
    assert svg.startswith("<svg") and "force (kN)" in svg
    expect(page.locator("[data-chart=force] .chart-message")).to_be_hidden()


def test_a_comparison_overlays_two_jobs_and_highlights_what_differs(page, stack):
    slow = run(stack, preset_json("fig9"))
    fast = run(stack, merge(preset_json("fig9"), {"name": "fig9-fast", "striker": {"velocity": 6.5}}))
    summaries = [stack.client.get(f"/v1/jobs/{job_id}/summary").json() for job_id in (slow, fast)]
    page.click("#refresh-jobs")
    page.check(f"[data-pick='{slow}']")  # the first ticked is the reference
    page.check(f"[data-pick='{fast}']")
    page.click("#compare")
    page.wait_for_url(f"**/#compare={slow},{fast}")
    drawn(page, "compare-force")
    drawn(page, "compare-probes")

    traces = page.evaluate(
        "() => document.querySelector('[data-chart=compare-force] .plot-area').data"
        ".map((t) => [t.name, Math.max(...t.y)])"
    )
    assert [name for name, _ in traces] == [f"fig9 · {slow[:6]}", f"fig9-fast · {fast[:6]}"]
    for (_, peak_kn), summary in zip(traces, summaries):
        assert peak_kn * 1e3 == pytest.approx(summary["peak_contact_force"]["value"], rel=PEAK)
    assert page.evaluate("() => document.querySelector('[data-chart=compare-probes] .plot-area').data.length") == 2

    quantities = {
        "co_impact_time": lambda s: s["co_impact_time"] * 1e6,
        "peak_contact_force": lambda s: s["peak_contact_force"]["value"] / 1e3,
        "max_compressive_stress": lambda s: s["max_compressive_stress"]["value"] / 1e6,
        "striker_rebound_velocity": lambda s: s["striker_rebound_velocity"],
        "energy.to_medium": lambda s: s["energy"]["to_medium"],
        "energy.transfer_efficiency": lambda s: 100 * s["energy"]["transfer_efficiency"],
    }
    highlighted = []
    for quantity, value in quantities.items():
        row = page.locator(f"table.compare tr[data-quantity='{quantity}']")
        ref, other = (value(s) for s in summaries)
        cells = [row.locator(f"td[data-job='{job_id}']") for job_id in (slow, fast)]
        assert [c.locator(".number").inner_text() for c in cells] == [shown(ref), shown(other)], quantity
        errors = [s["error_estimate"][quantity] for s in summaries]
        differs = abs(other - ref) / abs(ref) > max(errors or [AGREEMENT])
        assert "differs" not in (cells[0].get_attribute("class") or "")
        assert ("differs" in cells[1].get_attribute("class")) == differs, quantity
        if differs:
            sign = "+" if other > ref else "−"
            expect(cells[1].locator(".diff")).to_have_text(f"{sign}{abs(100 * (other - ref) / ref):.1f}%")
            highlighted.append(quantity)
    # A faster striker hits harder, beyond the estimates' reach; some differences are within it.
    assert "peak_contact_force" in highlighted and len(highlighted) < len(quantities)

    # The cases differ in their name and the striker's velocity, nothing else.
    differing = page.locator("table.case-diff tbody tr")
    expect(differing).to_have_count(2)
    assert [r.get_attribute("data-field") for r in differing.all()] == ["name", "striker.velocity"]
    velocity = page.locator("table.case-diff tr[data-field='striker.velocity'] td")
    assert velocity.all_inner_texts() == ["5", "6.5"]
    assert "differs" in velocity.nth(1).get_attribute("class")

    # Each column's head opens its job.
    page.click("table.compare th.compare-head button:has-text('fig9-fast')")
    page.wait_for_url(f"**/#job={fast}")


def test_a_hammer_at_work_set_in_the_form_runs_and_draws_its_cycle(page, stack):
    """The form's work cycle section writes the drive and its cycles (in place of blows), in SI
    from the units shown; the job shows the cycle's card and its charts: the drive's pressures
    within the gas law's bounds, the striker's velocity, and each blow's impact velocity, energy
    and stroke as the summary gives them."""
    case_in_page(page, "fig3")
    page.click("details[data-group=blows] summary")
    page.fill("#f-blows-count", "3")
    page.click("details[data-group=drive] summary")
    page.select_option("#f-drive-kind", "hydraulic")
    case = json.loads(page.input_value("#case-json"))
    assert case["drive"] == {"kind": "hydraulic"} and case["cycles"] == {"count": 10} and "blows" not in case
    expect(page.locator("#f-blows-count")).to_be_hidden()
    page.fill("#f-cycles-count", "4")
    for field, unit, value in (
        ("drive-supply_pressure", "MPa", "15"),
        ("drive-front_area", "cm²", "10"),
        ("drive-rear_area", "cm²", "30"),
        ("drive-stroke", "mm", "50"),
    ):
        page.select_option(f"#f-{field} + select", unit)
        page.fill(f"#f-{field}", value)
    expect(page.locator("#f-drive-accumulator-volume")).to_be_hidden()
    page.check("#f-drive-accumulator")
    page.select_option("#f-drive-accumulator-volume + select", "L")
    page.fill("#f-drive-accumulator-volume", "0.5")
    page.select_option("#f-drive-accumulator-precharge + select", "MPa")
    page.fill("#f-drive-accumulator-precharge", "8")
    page.select_option("#f-drive-control-kind", "adaptive")
    assert json.loads(page.input_value("#case-json"))["drive"]["control"] == {"kind": "adaptive"}
    page.select_option("#f-drive-control-kind", "none")
    page.select_option("#f-numerics-accuracy", "tolerance")  # cycles are solved under a tolerance
    case = json.loads(page.input_value("#case-json"))
    assert case["cycles"] == {"count": 4}
    assert case["drive"] == {
        "kind": "hydraulic",
        "supply_pressure": 15e6,
        "front_area": 0.001,
        "rear_area": 0.003,
        "stroke": 0.05,
        "accumulator": {"volume": 5e-4, "precharge": 8e6},
    }
    job_id = run(stack, case)
    summary = stack.client.get(f"/v1/jobs/{job_id}/summary").json()
    cycle = summary["cycle"]
    open_job(page, job_id)
    frequency = page.locator("table.cycle tr[data-quantity='cycle.frequency'] td.value")
    assert float(frequency.text_content()) == pytest.approx(cycle["frequency"], rel=1e-3)
    for chart in ("pressures", "striker_velocity", "cycles"):
        drawn(page, chart)

    def traces(chart: str) -> list[dict]:
        return page.evaluate(
            f"() => document.querySelector('[data-chart={chart}] .plot-area').data.map((t) => ({{name: t.name, y: t.y}}))"
        )

    pressures = {trace["name"]: trace["y"] for trace in traces("pressures")}
    supply = pressures["supply p_s"]
    # the supply between the gas at the precharge and the relief at the supply pressure (MPa)
    assert 8.0 <= min(supply) and max(supply) <= 15.0 * (1 + 1e-9) and max(pressures["rear chamber p_r"]) > 8.0
    (velocity,) = traces("striker_velocity")
    assert max(velocity["y"]) == pytest.approx(max(cycle["impact_velocity"]), rel=2e-2)
    bars = {trace["name"]: trace["y"] for trace in traces("cycles")}
    assert bars["impact velocity"] == pytest.approx(cycle["impact_velocity"], rel=1e-12)
    assert bars["stroke"] == pytest.approx([1e3 * s for s in cycle["stroke"]], rel=1e-12)  # mm
    mass = 20.0
    assert bars["impact energy"] == pytest.approx([0.5 * mass * v * v for v in cycle["impact_velocity"]], rel=1e-9)
