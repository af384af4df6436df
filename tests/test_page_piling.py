"""The pile studies on the job page, in Debian's Chromium: a bearing graph and a drivability started
from their forms end as a chart (the blow count, the stresses on a second axis) and a table holding
the API's numbers; a refusal is named under the form."""

from __future__ import annotations

import json

import pytest
from browser import drawn, fill_json, shown, shown_job
from playwright.sync_api import expect

from percussim.testing import merge
from percussim.testing.piles import PILE, SOIL

pytestmark = pytest.mark.slow  # a live stack and a browser


def test_a_bearing_graph_from_its_form_is_a_chart_and_a_table(page, stack):
    fill_json(page, json.dumps(PILE, indent=2))
    page.click("#bearing-panel summary")
    page.fill("#bearing-values", "1.5e6:2.4e6:3")
    page.click("#run-bearing")
    expect(page.locator("#job-status")).to_have_text("succeeded", timeout=120_000)
    graph = stack.client.get(f"/v1/bearing-graphs/{shown_job(page)}").json()
    traces = drawn(page, "pile")
    assert [t["name"] for t in traces] == ["blow count", "compressive stress", "tensile stress"]
    assert traces[0]["x"] == pytest.approx([1500.0, 1950.0, 2400.0])  # kN
    assert traces[0]["y"] == pytest.approx([row["blow_count"] for row in graph["rows"]])
    assert traces[1]["y"] == pytest.approx([row["max_compressive_stress"] / 1e6 for row in graph["rows"]])
    cells = page.locator("table.pile tbody tr")
    expect(cells).to_have_count(3)
    for k, row in enumerate(graph["rows"]):
        expect(cells.nth(k).locator("[data-column=blow_count]")).to_have_text(shown(row["blow_count"]))

    # an inspector's chart of a ram given its velocity, not a fall
    fill_json(page, json.dumps(merge(PILE, {"striker": {"stroke": None, "efficiency": None, "velocity": 3.6}})))
    page.select_option("#bearing-variable", "stroke")
    page.fill("#bearing-values", "0.5:1:2")
    page.click("#run-bearing")
    expect(page.locator("#bearing-errors td.field").first).to_have_text("case.striker.stroke")


def test_a_drivability_from_its_form_shows_the_depths_and_the_totals(page, stack):
    fill_json(page, json.dumps(PILE, indent=2))
    page.click("#drivability-panel summary")
    page.fill("#soil-json", json.dumps(merge(SOIL, {"depths": [3.0, 5.0, 7.0]})))
    page.click("#run-drivability")
    expect(page.locator("#job-status")).to_have_text("succeeded", timeout=120_000)
    driven = stack.client.get(f"/v1/drivability/{shown_job(page)}").json()
    traces = drawn(page, "pile")
    names = [t["name"] for t in traces]
    assert names == ["blow count", "restrike", "refusal", "compressive stress", "tensile stress"]
    assert traces[0]["y"] == [3.0, 5.0, 7.0]
    assert traces[0]["x"] == pytest.approx([row["blow_count"] for row in driven["rows"]])
    expect(page.locator("#study .pile-totals")).to_contain_text(f"Total blows {shown(driven['total_blows'])}")
    expect(page.locator("table.pile tbody tr")).to_have_count(3)

    page.fill("#soil-json", json.dumps(merge(SOIL, {"depths": [3.0, 16.0]})))
    page.click("#run-drivability")
    expect(page.locator("#drivability-errors td.field").first).to_have_text("soil.depths[1]")
