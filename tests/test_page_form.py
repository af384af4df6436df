"""The case form on the job page (service/static/form.js) in headless Chromium against the live stack:
exact unit conversions, the form and the case JSON following each other, the service's messages
next to their fields, the profile editor, the drawing, and the layout at a phone's width."""

from __future__ import annotations

import json
from decimal import Decimal

import pytest
from browser import KEY, case_in_page
from playwright.sync_api import Page, expect

pytestmark = pytest.mark.slow  # a live stack and a browser

POWERS = {
    "m": 0,
    "mm": -3,
    "cm": -2,
    "µs": -6,
    "ms": -3,
    "kN": 3,
    "MPa": 6,
    "GPa": 9,
    "g/cm³": 3,
    "mm²": -6,
    "cm²": -4,
    "kN/mm": 6,
    "%": -2,
    "t": 3,
    "g": -3,
}


def units(page: Page, function: str, *args) -> object:
    """`function` of `args` run in the page with the names of its units module (service/static/units.js)
    in scope: the module the page imported, as a module is only ever loaded once."""
    return page.evaluate(
        f"async (args) => {{ const {{ toSI, fromSI, shiftDecimal }} = await import('/static/units.js');"
        f" return ({function})(args); }}",
        list(args),
    )


def case_json(page: Page) -> dict:
    return json.loads(page.input_value("#case-json"))


def open_json(page: Page) -> None:
    page.evaluate("document.getElementById('json-panel').open = true")


def top(page: Page, selector: str) -> float:
    """Where an element is on the page (not in the viewport, which scrolls as fields are filled)."""
    return page.evaluate("(s) => document.querySelector(s).getBoundingClientRect().top + scrollY", selector)


@pytest.mark.parametrize(
    "text, unit",
    [
        ("3", "mm"),
        ("3.5", "mm"),
        ("7.85", "g/cm³"),
        ("2.1e5", "MPa"),
        ("0.83", "µs"),
        ("12.7", "mm"),
        ("0.1", "mm"),
        ("1", "%"),
        ("-0.25", "kN"),
        (".5", "cm²"),
        ("1e-3", "mm²"),
        ("206", "GPa"),
        ("60", "kN/mm"),
    ],
)
def test_a_unit_converts_exactly(page, text, unit):
    # The double nearest the decimal typed, as Python reads "3.5e-3": no 3.5 * 0.001 = 0.0035000000000000005.
    assert units(page, "([t, u]) => toSI(t, u)", text, unit) == float(Decimal(text).scaleb(POWERS[unit]))
    # ... and shown back in the unit as the same digits.
    assert units(page, "([t, u]) => fromSI(toSI(t, u), u)", text, unit) == units(
        page, "([t]) => shiftDecimal(t, 0)", text
    )


def test_typed_values_go_into_the_json_in_si_and_a_unit_change_keeps_them(page):
    case_in_page(page, "fig3")
    open_json(page)
    page.select_option("#f-tool-length + select", "mm")
    expect(page.locator("#f-tool-length")).to_have_value("1200")
    assert case_json(page)["tool"]["length"] == 1.2  # re-expressed, not changed
    page.fill("#f-tool-length", "1150.5")
    assert case_json(page)["tool"]["length"] == 1.1505
    page.select_option("#f-numerics-time_step + select", "µs")
    expect(page.locator("#f-numerics-time_step")).to_have_value("0.83")
    page.fill("#f-numerics-time_step", "0.83")
    assert '"time_step": 8.3e-7' in page.input_value("#case-json")
    page.select_option("#f-tool-youngs_modulus + select", "MPa")
    page.fill("#f-tool-youngs_modulus", "2.1e5")
    assert '"youngs_modulus": 210000000000' in page.input_value("#case-json")
    page.select_option("#f-tool-density + select", "g/cm³")
    page.fill("#f-tool-density", "7.85")
    assert case_json(page)["tool"]["density"] == 7850
    # Not a number: sent as typed, for the service to name; emptied: removed.
    page.fill("#f-striker-mass", "abc")
    assert case_json(page)["striker"]["mass"] == "abc"
    page.fill("#f-contact-damping", "")
    assert "damping" not in case_json(page)["contact"]


def test_every_preset_comes_back_from_the_form_unchanged(page, stack):
    names = [p["name"] for p in stack.client.get("/v1/presets").json()]
    assert len(names) >= 9
    for name in names:
        preset = case_in_page(page, name)
        # Every input read back as typed, then in another unit: the JSON is the preset's, to the bit.
        for unit_index in (0, -1):
            page.evaluate(
                """(last) => {
                for (const select of document.querySelectorAll("#case-fields select.unit")) {
                  if (select.closest("[hidden]")) continue;
                  select.selectedIndex = last ? select.options.length - 1 : 0;
                  select.dispatchEvent(new Event("change"));
                }
                for (const input of document.querySelectorAll("#case-fields input[type=text], #case-fields textarea")) {
                  if (!input.closest("[hidden]")) input.dispatchEvent(new Event("input"));
                }
            }""",
                unit_index == -1,
            )
            assert case_json(page) == preset, (name, unit_index)


def test_the_json_and_the_form_follow_each_other(page):
    case = case_in_page(page, "fig5")
    expect(page.locator("#f-striker-mass")).to_have_value("13")
    open_json(page)
    # The JSON edited: the form follows, fields the form does not know stay.
    case["striker"]["mass"] = 21.5
    case["tool"]["profile"] = {"x": [0, 0.3, 0.6], "area": [0.008, 0.008, 0.004]}
    del case["tool"]["area"]
    case["medium"] = {"kind": "smith", "ultimate_resistance": 1e6, "quake": 0.0025}
    case["extra"] = {"kept": True}
    page.fill("#case-json", json.dumps(case, indent=2))
    expect(page.locator("#f-striker-mass")).to_have_value("21.5")
    expect(page.locator("#f-tool-area")).to_be_hidden()
    expect(page.locator('[data-path="tool.profile"] input[data-row="2"][data-col="area"]')).to_have_value("0.004")
    expect(page.locator("#f-medium-quake")).to_be_visible()
    expect(page.locator("#f-medium-stiffness")).to_be_hidden()
    page.fill("#f-striker-mass", "22")
    after = case_json(page)
    assert after["striker"]["mass"] == 22 and after["extra"] == {"kept": True}
    # Text that does not parse: the form keeps the last case, and says so.
    page.fill("#case-json", '{"striker": {"mass": 5,}')
    expect(page.locator("#form-status")).to_contain_text("syntax error")
    expect(page.locator("#f-striker-mass")).to_have_value("22")
    # A preset loaded: the form shows it, the focus stays where it was.
    page.focus("#preset")
    case_in_page(page, "rock_drill")
    expect(page.locator("#f-striker-length")).to_have_value("0.3")
    expect(page.locator("#f-striker-mass")).to_be_hidden()
    assert page.evaluate("document.activeElement.id") == "preset"


def test_choices_reshape_the_case(page):
    case_in_page(page, "fig3")
    page.select_option("#f-striker-model", "rod")
    striker = case_json(page)["striker"]
    assert "mass" not in striker and striker["area"] == 0.014209 and striker["density"] == 7800.0
    assert abs(striker["length"] * 7800.0 * 0.014209 - 20.0) < 1e-4  # the same mass
    page.select_option("#f-striker-model", "lumped")
    assert case_json(page)["striker"] == {"velocity": 5.0, "mass": 20.0}
    page.select_option("#f-medium-kind", "bilinear")
    assert case_json(page)["medium"] == {"kind": "bilinear", "stiffness": 2e8, "damping": 1e3}
    page.select_option("#f-medium-kind", "none")
    assert "medium" not in case_json(page)
    page.select_option("#f-numerics-accuracy", "tolerance")
    assert case_json(page)["numerics"] == {"duration": 4e-3}
    page.select_option("#f-numerics-accuracy", "grid")
    assert case_json(page)["numerics"] == {"duration": 4e-3, "time_step": 8.3e-7, "cells": 100, "gamma": 0.5}
    page.click("details[data-group=anvil] summary")
    page.check("#f-anvil")
    assert case_json(page)["anvil"] == {"contact": {"stiffness": 1e11, "exponent": 0.5}}
    expect(page.locator("#f-anvil-mass")).to_be_visible()
    page.click("details[data-group=blows] summary")
    page.fill("#f-blows-count", "3")
    assert case_json(page)["blows"] == {"count": 3}
    page.fill("#f-blows-count", "")
    assert "blows" not in case_json(page)


def test_the_profile_editor(page):
    case_in_page(page, "fig8")
    table = page.locator('[data-path="tool.profile"]')
    cell = lambda row, col: table.locator(f'input[data-row="{row}"][data-col="{col}"]')  # noqa: E731
    expect(cell(2, "x")).to_have_value("0.5")
    # A station inserted with the keyboard, halfway: the shape is unchanged.
    table.get_by_role("button", name="add a station after station 0").focus()
    page.keyboard.press("Enter")
    profile = case_json(page)["tool"]["profile"]
    assert profile == {"x": [0.0, 0.125, 0.25, 0.5], "area": [2.8274e-3, 2.8274e-3, 2.8274e-3, 1.3854e-3]}
    expect(cell(1, "x")).to_be_focused()
    table.get_by_role("button", name="remove station 1").click()
    assert case_json(page)["tool"]["profile"]["x"] == [0.0, 0.25, 0.5]
    # The last station is the length: editing one moves the other.
    cell(2, "x").fill("0.55")
    assert case_json(page)["tool"]["length"] == 0.55
    page.fill("#f-tool-length", "0.5")
    assert case_json(page)["tool"]["profile"]["x"] == [0.0, 0.25, 0.5]
    # Diameters of a round section, in mm.
    table.get_by_label("diameters of a round section").check()
    table.get_by_role("combobox", name="unit of Ø d (stations)").select_option("mm")
    expect(cell(0, "area")).to_have_value("59.9996")  # from 2.8274e-3 m², to six digits
    cell(2, "area").fill("40")
    assert case_json(page)["tool"]["profile"]["area"][2] == pytest.approx(3.141592653589793 * 0.04**2 / 4, rel=1e-15)
    # Uniform: the mean area (the same mass); back to a profile: that area at both ends.
    page.select_option("#f-tool-shape", "uniform")
    tool = case_json(page)["tool"]
    mean = (2.8274e-3 * 0.25 + (2.8274e-3 + 3.141592653589793 * 0.04**2 / 4) / 2 * 0.25) / 0.5
    assert "profile" not in tool and tool["area"] == pytest.approx(mean, rel=1e-5)
    page.select_option("#f-tool-shape", "profile")
    assert case_json(page)["tool"]["profile"] == {"x": [0, 0.5], "area": [tool["area"], tool["area"]]}


def test_the_services_messages_are_shown_next_to_their_fields(page, stack):
    case = case_in_page(page, "fig8")
    page.fill("#f-striker-mass", "abc")
    page.fill("#f-contact-exponent", "0.9")
    sent = case_json(page)
    refused = {p["field"]: p["message"] for p in stack.client.post("/v1/jobs", json=sent).json()["detail"]}
    assert set(refused) == {"striker.mass", "contact.exponent"}
    expect(page.locator("#f-striker-mass-line")).to_have_text(refused["striker.mass"])
    expect(page.locator("#f-contact-exponent-line")).to_have_text(refused["contact.exponent"])
    expect(page.locator("#f-striker-mass")).to_have_attribute("aria-invalid", "true")
    assert "f-striker-mass-line" in page.get_attribute("#f-striker-mass", "aria-describedby")
    expect(page.locator("#form-status")).to_contain_text("2 problems")
    # Mended: the messages go, the hints come back.
    page.fill("#f-striker-mass", "13")
    page.fill("#f-contact-exponent", "0.5")
    expect(page.locator("#form-status")).to_contain_text("no problem")
    expect(page.locator("#f-striker-mass")).not_to_have_attribute("aria-invalid", "true")
    # A station out of order, in its table; a field the form does not have, in the box.
    open_json(page)
    case["tool"]["profile"]["x"] = [0.0, 0.3, 0.25, 0.5]
    case["tool"]["profile"]["area"] = [2.8274e-3, 2.8274e-3, 2.8274e-3, 1.3854e-3]
    case["frobnicate"] = 1
    page.fill("#case-json", json.dumps(case, indent=2))
    expect(page.locator("#f-tool-profile-line")).to_contain_text("must be strictly increasing")
    expect(page.locator("#case-errors")).to_contain_text("frobnicate")
    expect(page.locator("#case-errors")).not_to_contain_text("strictly increasing")
    # The last station against the length: at its cell.
    case["tool"]["profile"]["x"] = [0.0, 0.25, 0.3, 0.45]
    del case["frobnicate"]
    page.fill("#case-json", json.dumps(case, indent=2))
    expect(page.locator("#f-tool-profile-line")).to_contain_text(
        "x of station 3: the last station must equal tool.length = 0.5 m"
    )
    expect(page.locator('[data-path="tool.profile"] input[data-row="3"][data-col="x"]')).to_have_attribute(
        "aria-invalid", "true"
    )
    expect(page.locator("#case-errors")).to_be_hidden()


def test_a_refused_run_marks_the_fields_too(page, stack):
    case_in_page(page, "fig3")
    page.fill("#f-striker-mass", "-1")
    page.click("#submit")
    message = stack.client.post("/v1/jobs", json=case_json(page)).json()["detail"][0]["message"]
    expect(page.locator("#f-striker-mass-line")).to_have_text(message)
    expect(page.locator("#case-errors")).to_contain_text("striker.mass")


def test_the_drawing_follows_the_case_and_never_breaks(page):
    case_in_page(page, "pile")
    drawing = page.locator("#drawing svg")
    expect(drawing).to_have_attribute("data-radii", "10")  # a slender pile: its radii enlarged, and said
    expect(page.locator("#drawing")).to_contain_text("radii ×10")
    size = page.locator("#drawing").bounding_box()
    case_in_page(page, "fig8")
    expect(drawing).to_have_attribute("data-radii", "1")
    expect(page.locator("#drawing")).to_contain_text("tool L = 500 mm")
    page.fill("#f-tool-length", "0.4")
    expect(page.locator("#drawing")).to_contain_text("tool L = 400 mm")
    for junk in ("", "abc", "-1", "1e400"):
        page.fill("#f-tool-length", junk)
        page.fill("#f-striker-mass", junk)
    expect(page.locator("#drawing .guess")).not_to_have_count(0)
    after = page.locator("#drawing").bounding_box()
    assert (after["width"], after["height"]) == (size["width"], size["height"])  # the same size whatever it draws


def case_schema_fields(schemas: dict) -> dict[str, dict]:
    """Every field of the Case schema by its path, each its schema (a `null` alternative dropped);
    a union's fields (the force's kinds) are every variant's."""
    fields = {}

    def walk(node: dict, prefix: str) -> None:
        for variant in variants(schemas, node):
            for key, prop in variant["properties"].items():
                options = [deref(schemas, o) for o in prop.get("anyOf", [prop]) if o.get("type") != "null"]
                inner = {**options[0], **{k: v for k, v in prop.items() if k != "anyOf"}}
                if "properties" in inner or "oneOf" in inner:
                    walk(inner, f"{prefix}{key}.")
                else:
                    fields[f"{prefix}{key}"] = inner

    walk(schemas["Case"], "")
    return fields


def deref(schemas: dict, node: dict) -> dict:
    return schemas[node["$ref"].split("/")[-1]] if "$ref" in node else node


def variants(schemas: dict, node: dict) -> list[dict]:
    return [deref(schemas, variant) for variant in node.get("oneOf", [node])]


def option_values(page: Page, select: str) -> list[str]:
    return page.locator(select).locator("option").evaluate_all("els => els.map((o) => o.value)")


# The case's fields edited in the case JSON only, without an input in the form: the shaft's
# segments, until the form has a table of them, and a history driving the struck end (a record
# read from a file, not typed).
JSON_ONLY = {"shaft", "struck_end"}


def test_the_forms_fields_are_the_case_schemas(page, stack):
    """Every field of the case's schema, as /openapi.json publishes it, has its input in the form
    (but those of JSON_ONLY), with the schema's title, default, kinds and bounds."""
    schemas = stack.client.get("/openapi.json").json()["components"]["schemas"]
    fields = case_schema_fields(schemas)
    case_in_page(page, "fig3")
    tables = page.locator("#case-fields .field.table").evaluate_all("els => els.map((el) => el.dataset.path)")
    assert set(tables) == {"striker.profile", "tool.profile", "outputs.probes"}
    for path, field in fields.items():
        if path.split(".")[0] in JSON_ONLY or any(path == table or path.startswith(f"{table}.") for table in tables):
            continue
        if path.endswith(".kind"):  # a medium's or a force's kind: the choice that makes it
            expect(page.locator(f'[data-mode="{path}"]')).to_have_count(1)
            continue
        row = page.locator(f'[data-path="{path}"]')
        expect(row).to_have_count(1)
        assert field["title"].lower() in row.locator("label.name").text_content().lower(), path
        if type(field.get("default")) in (int, float):
            expect(row.locator("input")).to_have_attribute("placeholder", f"{field['default']:g}")
    # The kinds of a medium and of a force are the schema's.
    assert option_values(page, "#f-medium-kind") == ["none", *schemas["Medium"]["properties"]["kind"]["enum"]]
    force = schemas["Case"]["properties"]["force"]["anyOf"][0]
    kinds = [variant["properties"]["kind"]["const"] for variant in variants(schemas, force)]
    assert option_values(page, "#f-force-kind") == ["none", *kinds]
    # The bounds shown are the schema's.
    gamma, sigma = fields["numerics.gamma"], fields["numerics.sigma"]
    expect(page.locator("#f-numerics-gamma-line")).to_have_text(
        f"{gamma['minimum']:g} ≤ {gamma['symbol']} ≤ {gamma['maximum']:g}"
    )
    page.select_option("#f-numerics-scheme", '"sigma"')
    expect(page.locator("#f-numerics-sigma-line")).to_have_text(
        f"{sigma['minimum']:g} ≤ {sigma['symbol']} ≤ {sigma['maximum']:g}"
    )


def test_a_phone_shows_it_all_without_sideways_scrolling_or_jumps(browser, stack):
    context = browser.new_context(viewport={"width": 390, "height": 844})
    context.add_init_script(f"localStorage.setItem('percussim.apiKey', {json.dumps(KEY)})")
    page = context.new_page()
    errors = []
    page.on("pageerror", lambda error: errors.append(error))
    page.goto(stack.url + "/")
    case_in_page(page, "fig9")
    page.evaluate("document.querySelectorAll('#case-fields details').forEach((d) => { d.open = true; })")
    assert page.evaluate("document.documentElement.scrollWidth") <= 390
    below = top(page, "#f-contact-exponent")
    page.fill("#f-contact-stiffness", "-5")
    expect(page.locator("#f-contact-stiffness-line")).to_contain_text("must be ≥ 0")
    assert top(page, "#f-contact-exponent") == below  # the message took the room kept for it
    assert page.evaluate("document.documentElement.scrollWidth") <= 390
    context.close()
    assert not errors
