"""Signal matching on the job page, in Debian's Chromium: a pile's head record chosen on disk,
matched over the pile in the editor (its hammer left out, as the form says), ends as the capacity
table and four charts holding the API's numbers; a record the service refuses is named by its line
in the file."""

from __future__ import annotations

import json
import math

import pytest
from browser import drawn, fill_json, shown, shown_job
from playwright.sync_api import expect
from test_signal_match import RESISTANCES, guessed

from percussim.testing.pile_records import head_record, pile

pytestmark = pytest.mark.slow  # a live stack and a browser


def record_csv(record: dict) -> str:
    """The record as CSV, velocity before force (either order is read)."""
    rows = (f"{t!r},{v!r},{f!r}" for t, f, v in zip(record["time"], record["force"], record["velocity"]))
    return "# a pile driving analyser's export\ntime,velocity@0,force@0\n" + "\n".join(rows)


def test_a_record_chosen_on_disk_is_matched_to_its_capacity_and_charts(page, stack, tmp_path):
    record = head_record(pile())
    # the pile as a hammer's case: the form leaves out what the record takes the place of
    fill_json(page, json.dumps(guessed() | {"striker": {"mass": 4536.0, "velocity": 3.6}}))
    page.click("#match-panel summary")
    (tmp_path / "head.csv").write_text(record_csv(record) + "\n")
    page.set_input_files("#match-record-file", str(tmp_path / "head.csv"))
    expect(page.locator("#match-record-info")).to_contain_text(
        f"{len(record['time'])} samples of force and velocity at x = 0 m"
    )
    page.click("#run-match")
    expect(page.locator("#job-status")).to_have_text("succeeded", timeout=240_000)
    study = stack.client.get(f"/v1/signal-matches/{shown_job(page)}").json()
    match = study["match"]
    # the worker drew the plot the API serves: the four panels the command line draws
    assert stack.client.get(study["links"]["plot_png"]).content[:8] == b"\x89PNG\r\n\x1a\n"
    assert (
        "striker" not in match["case"] and len(match["parameters"]) == 6
    )  # the default unknowns: 3 for the shaft, 3 for the toe
    assert abs(match["capacity"]["value"] - 8e5) <= 3 * match["capacity"]["standard_error"]
    rows = page.locator("#study table.capacity tbody tr")
    expect(rows.first).to_contain_text(shown(match["capacity"]["value"] / 1e3))
    assert page.locator("#study table.capacity tbody th").all_inner_texts() == ["Total (static)", "shaft.0", "toe"]

    force = drawn(page, "match-force")
    assert [t["name"] for t in force] == ["measured", "computed"]
    assert force[0]["x"] == pytest.approx([t * 1e3 for t in match["series"]["time"]])  # ms
    assert force[1]["y"] == pytest.approx([f / 1e3 for f in match["series"]["model"]])  # kN
    waves = drawn(page, "match-waves")
    assert [t["name"] for t in waves] == ["down, measured", "down, computed", "up, measured", "up, computed"]
    assert waves[3]["y"] == pytest.approx([w / 1e3 for w in match["waves"]["computed"]["up"]])
    # the waves add up to the force they are made of, and differ by Z·v
    z = 0.01 * math.sqrt(2.1e11 * 7850.0)
    for k in (10, 60, 120):
        assert waves[0]["y"][k] + waves[2]["y"][k] == pytest.approx(force[0]["y"][k])
        assert (waves[0]["y"][k] - waves[2]["y"][k]) * 1e3 == pytest.approx(z * record["velocity"][k], rel=1e-9)
    (bars,) = drawn(page, "match-resistance")
    assert bars["x"] == pytest.approx([row["resistance"] / 1e3 for row in match["resistance_distribution"]])
    assert bars["y"] == pytest.approx([6.5, 10.0 + 10.0 / 60])  # the shaft's 3–10 m, the toe just below its end
    (load,) = drawn(page, "match-load-test")
    assert load["x"][-1] == pytest.approx(match["capacity"]["value"] / 1e3, rel=1e-5)
    assert load["y"] == pytest.approx([s * 1e3 for s in match["static_load_test"]["settlement"]])  # mm

    # unknowns of one's own: the resistances alone, the quakes and damping factors kept as guessed
    first = shown_job(page)
    for path, (low, high) in RESISTANCES.items():
        page.click("[data-add=match-parameters]")
        cells = page.locator("#match-parameters tbody tr").last.locator("input")
        for cell, text in zip(cells.all(), (path, str(low), str(high))):
            cell.fill(text)
    page.click("#run-match")
    page.wait_for_url(lambda url: first not in url)
    second = shown_job(page)
    stack.wait_status(second, ("succeeded",), timeout=240)
    fitted = stack.client.get(f"/v1/signal-matches/{second}").json()["match"]["parameters"]
    assert set(fitted) == set(RESISTANCES)
    expect(page.locator("#study table.fit tbody tr")).to_have_count(2)

    # a sample that is not a number: the service names it, the page adds its line in the file
    lines = record_csv(record).splitlines()
    lines[7] = "nan,1,2"  # sample 5: a comment and the header above it
    (tmp_path / "nan.csv").write_text("\n".join(lines) + "\n")
    page.set_input_files("#match-record-file", str(tmp_path / "nan.csv"))
    page.click("#run-match")
    expect(page.locator("#match-errors td.field").first).to_have_text("record.time[5] (line 8)")
    (tmp_path / "calibration.csv").write_text("time,contact_force\n0,1\n")
    page.set_input_files("#match-record-file", str(tmp_path / "calibration.csv"))
    expect(page.locator("#match-errors")).to_contain_text("calibration.csv is not a pile's head record")
