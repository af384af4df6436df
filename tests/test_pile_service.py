"""The bearing graph and the drivability through the HTTP API: refused with 422 naming the field, and
run as jobs whose variants spread over two workers, with Redis and with the embedded queue, to the
rows the library gives."""

from __future__ import annotations

import pytest

from percussim.client import Client, Refused
from percussim.solver.pile_studies import bearing_graph, drivability
from percussim.testing import merge
from percussim.testing.live_stack import Stack, redis_server
from percussim.testing.piles import PILE, SOIL

COMPARED = ("set", "blow_count", "max_compressive_stress", "max_tensile_stress", "transferred_energy", "blows")


@pytest.mark.parametrize(
    ("route", "body", "field"),
    [
        ("/v1/bearing-graphs", {"case": PILE}, "capacity"),
        ("/v1/bearing-graphs", {"case": PILE, "capacity": [1e6], "stroke": [1.0]}, "capacity"),
        ("/v1/bearing-graphs", {"case": merge(PILE, {"medium": {"kind": "linear"}}), "capacity": [1e6]}, "case.medium"),
        (
            "/v1/bearing-graphs",
            {"case": merge(PILE, {"striker": {"stroke": None, "efficiency": None, "velocity": 3.6}}), "stroke": [1.0]},
            "case.striker.stroke",
        ),
        ("/v1/bearing-graphs", {"case": PILE, "capacity": [1e6, 0.0]}, "capacity[1]"),
        ("/v1/bearing-graphs", {"case": merge(PILE, {"numerics": {"cells": 10**7}}), "capacity": [1e6]}, "capacity[0]"),
        ("/v1/drivability", {"case": PILE, "soil": merge(SOIL, {"depths": [3.0, 16.0]})}, "soil.depths[1]"),
        ("/v1/drivability", {"case": PILE, "soil": merge(SOIL, {"layers": SOIL["layers"][1:]})}, "soil.layers[0].from"),
        ("/v1/drivability", {"case": PILE}, "soil"),
    ],
)
def test_a_bad_pile_study_gets_422_naming_the_field(api_store, route, body, field):
    client, _ = api_store
    answer = client.post(route, json=body)
    assert answer.status_code == 422, answer.text
    assert answer.json()["detail"][0]["field"].startswith(field), answer.json()


def test_a_pile_study_is_a_job_of_its_kind_with_its_links(api_store):
    client, jobs = api_store
    answer = client.post("/v1/bearing-graphs", json={"case": PILE, "capacity": [1e6, 2e6]})
    assert answer.status_code == 202, answer.text
    study = answer.json()
    assert study["kind"] == "bearing_graph" and study["status"] == "queued"
    assert answer.headers["Location"] == study["links"]["self"] == f"/v1/bearing-graphs/{study['id']}"
    assert client.get(study["links"]["plot_png"]).status_code == 409  # not run yet
    assert client.get(f"/v1/drivability/{study['id']}").status_code == 404  # not a drivability
    assert jobs.request(study["id"])["capacity"] == [1e6, 2e6]


@pytest.fixture(scope="module")
def redis_url(tmp_path_factory):
    with redis_server(tmp_path_factory.mktemp("redis")) as url:
        yield url


ASKED = {"case": PILE, "capacity": [1.2e6, 1.5e6, 1.8e6, 2.1e6, 2.4e6, 2.7e6, 3.0e6, 3.3e6]}
SHALLOW = {"case": PILE, "soil": merge(SOIL, {"depths": [3.0, 5.0]})}  # the deep depths' refusal is test_piling's


@pytest.fixture(scope="module")
def here():
    """The library's bearing graph and drivability of the requests the services are sent."""
    return bearing_graph(ASKED, processes=2), drivability(SHALLOW, processes=2)


@pytest.mark.slow
@pytest.mark.parametrize("deployment", ["redis", "embedded"])
def test_pile_studies_spread_their_variants_over_the_workers_to_the_librarys_rows(request, tmp_path, deployment, here):
    broker = request.getfixturevalue("redis_url") if deployment == "redis" else None
    stack = Stack(tmp_path, broker, workers=2)
    graph_here, driven_here = here
    try:
        with Client(stack.url) as api:
            graph = api.run_bearing_graph(ASKED, timeout=120)
            for served, local in zip(graph["rows"], graph_here["rows"], strict=True):
                assert {k: served[k] for k in COMPARED} == {k: local[k] for k in COMPARED}
            assert graph["status"] == "succeeded" and graph["variable"] == "ultimate_resistance"
            print(f"{deployment}: bearing graph runs spread {graph['runs_spread']}")
            assert graph["runs_spread"]["other_workers"] > 0
            assert stack.client.get(graph["links"]["plot_png"]).content[:4] == b"\x89PNG"

            # what a job spreads must come back as the library computes it
            driven = api.run_drivability(SHALLOW, timeout=120)
            for key in ("total_blows", "driving_time", "refusal_depth", "driven_to", "restrike_refusal_depth"):
                assert driven[key] == driven_here[key], key
            assert [row["blow_count"] for row in driven["rows"]] == [row["blow_count"] for row in driven_here["rows"]]
            assert stack.client.get(driven["links"]["plot_svg"]).text.startswith("<?xml")
            with pytest.raises(Refused) as refused:
                api.submit_drivability({"case": PILE, "soil": merge(SOIL, {"depths": [30.0]})})
            assert refused.value.errors[0].field == "soil.depths[0]"
    finally:
        stack.stop()
