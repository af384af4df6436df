"""Invalid cases are refused with the field path and a reason an engineer reads."""

import json
import multiprocessing

import pytest
from conftest import BASE_CASE, merge

from percussim.solver.case import CaseError, parse_case
from percussim.solver.grid import resolve_numerics
from percussim.solver.limits import Limits, check_limits

PROFILE = {"area": None, "profile": {"x": [0.0, 0.5, 1.0, 1.2], "area": [0.01, 0.01, 0.005, 0.004]}}


def _refusal(changes: dict) -> dict[str, str]:
    with pytest.raises(CaseError) as caught:
        parse_case(merge(BASE_CASE, changes))
    return {e.field: e.message for e in caught.value.errors}


def test_a_refusal_raised_in_a_pools_worker_comes_back_whole():
    """A process pool hands a worker's exception back pickled; rebuilt from its message, a
    refusal broke the pool's result thread and left its caller waiting forever (here, a timeout)."""
    with multiprocessing.Pool(1) as pool:
        with pytest.raises(CaseError) as caught:
            pool.apply_async(parse_case, (merge(BASE_CASE, {"striker": {"mass": -1.0}}),)).get(timeout=60)
    assert [(e.field, e.message) for e in caught.value.errors] == [("striker.mass", "must be > 0.0")]


@pytest.mark.parametrize(
    "changes, field, words",
    [
        ({"striker": {"mass": -1.0}}, "striker.mass", "must be > 0"),
        ({"tool": {"area": 0.0}}, "tool.area", "must be > 0"),
        (
            {"tool": {**PROFILE, "profile": {"x": [0, 0.5, 1.0, 1.2], "area": [0.01, 0.01, -0.005, 0.004]}}},
            "tool.profile.area[2]",
            "must be > 0",
        ),
        (
            {"tool": {**PROFILE, "profile": {"x": [0, 0.7, 0.5, 1.2], "area": [0.01, 0.01, 0.005, 0.004]}}},
            "tool.profile.x",
            "strictly increasing: x[2]",
        ),
        (
            {"tool": {**PROFILE, "profile": {"x": [0, 0.5, 1.0], "area": [0.01, 0.01, 0.005, 0.004]}}},
            "tool.profile.area",
            "one area per station",
        ),
        (
            {"tool": {**PROFILE, "profile": {"x": [0, 0.5, 1.0, 1.3], "area": [0.01, 0.01, 0.005, 0.004]}}},
            "tool.profile.x[3]",
            "must equal tool.length",
        ),
        ({"tool": {"profile": PROFILE["profile"]}}, "tool.area", "exactly one"),
        ({"contact": {"exponent": 0.7}}, "contact.exponent", "must be ≤ 0.5"),
        ({"contact": {"exponent": -0.1}}, "contact.exponent", "must be ≥ 0"),
        ({"contact": {"tension_stiffness": -1.0}}, "contact.tension_stiffness", "must be ≥ 0"),
        ({"medium": {"damping": -5.0}}, "medium.damping", "must be ≥ 0"),
        ({"numerics": {"gamma": 0.3}}, "numerics.gamma", "must be ≥ 0.5"),
        ({"numerics": {"duration": None}}, "numerics.duration", "is required"),
        ({"numerics": {"cells": 10.5}}, "numerics.cells", "whole number"),
        ({"outputs": {"probes": [0.1, 1.5]}}, "outputs.probes[1]", "must lie on the tool"),
        ({"striker": {"speed": 5.0}}, "striker.speed", "not a known field"),
        ({"force": {"kind": "square", "amplitude": 1.0}}, "force", "kind must be one of"),
        ({"force": {"kind": "pulse", "amplitude": 1.0, "duration": 0.0}}, "force.duration", "must be > 0"),
    ],
)
def test_refusal_names_the_field(changes, field, words):
    errors = _refusal(changes)
    assert field in errors, errors
    assert words in errors[field]


def test_non_finite_numbers_are_refused_from_json():
    text = json.dumps(merge(BASE_CASE, {"striker": {"velocity": float("nan")}}))
    with pytest.raises(CaseError) as caught:
        parse_case(text)
    assert [e.field for e in caught.value.errors] == ["striker.velocity"]


def test_valid_profile_and_defaults():
    case = parse_case(merge(BASE_CASE, {"tool": PROFILE, "numerics": {"time_step": None, "cells": None}}))
    numerics = resolve_numerics(case)
    assert numerics.cells == 100 and numerics.gamma == 0.5
    assert 0 < numerics.courant <= 1.0  # the default step never exceeds the wave's Courant limit


@pytest.mark.parametrize(
    "changes, limits, field, words",
    [
        ({"numerics": {"cells": 5000}}, Limits(max_cells=1000), "numerics.cells", "limit of 1000"),
        ({"numerics": {"duration": 1.0}}, Limits(max_steps=10**6), "numerics.time_step", "limit of 1000000"),
        ({"outputs": {"fields": True, "field_stride": 1}}, Limits(max_output_values=1e5), "outputs", "limit"),
    ],
)
def test_a_case_over_a_limit_is_refused_up_front(changes, limits, field, words):
    case = parse_case(merge(BASE_CASE, changes))
    with pytest.raises(CaseError) as caught:
        check_limits(case, resolve_numerics(case), limits)
    errors = {e.field: e.message for e in caught.value.errors}
    assert words in errors[field]


def test_a_case_whose_time_step_cannot_be_chosen_is_refused():
    case = parse_case(merge(BASE_CASE, {"striker": {"mass": 5e-324}, "numerics": {"time_step": None}}))
    with pytest.raises(CaseError) as caught:
        resolve_numerics(case)
    assert caught.value.errors[0].field == "numerics.time_step"


def test_blows_count_toward_the_limits_and_the_refusal_says_so():
    """1000 blows of 1 ms: every blow's steps count, and fewer blows is offered as a way out."""
    case = parse_case(
        merge(
            BASE_CASE, {"numerics": {"scheme": "explicit", "time_step": None, "gamma": None}, "blows": {"count": 1000}}
        )
    )
    numerics = resolve_numerics(case)
    one_blow = resolve_numerics(
        parse_case(merge(BASE_CASE, {"numerics": {"scheme": "explicit", "time_step": None, "gamma": None}}))
    )
    assert numerics.steps == 1000 * one_blow.steps
    with pytest.raises(CaseError) as caught:
        check_limits(case, numerics, Limits(max_steps=numerics.steps - 1))
    [error] = caught.value.errors
    assert "× 1000 blows" in error.message and "fewer blows.count" in error.message
