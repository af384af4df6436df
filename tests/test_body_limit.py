"""An oversized body's 413 reaches every common client, sent with a Content-Length or chunked,
instead of a connection reset while the client is still sending (a real `percussim serve`)."""

from __future__ import annotations

import json
import shutil
import subprocess
import urllib.error
import urllib.request

import httpx
import pytest
import requests
from conftest import BASE_CASE, merge

from percussim.testing.live_stack import Stack

pytestmark = pytest.mark.slow  # a live server

LIMIT = 4096
# Megabytes: a few hundred kB fit in loopback's socket buffers, and a client then reads the 413
# even from a server that does not read the body.
BIG = json.dumps(merge(BASE_CASE, {"description": "x" * 4_000_000})).encode()
JSON = {"Content-Type": "application/json"}


@pytest.fixture(scope="module")
def stack(tmp_path_factory):
    s = Stack(tmp_path_factory.mktemp("limit"), None, workers=0, env={"PERCUSSIM_MAX_BODY_BYTES": str(LIMIT)})
    yield s
    s.stop()


def chunks(body: bytes):
    """`body` as an iterator, which every client sends chunked, without a Content-Length."""
    return (body[k : k + 16384] for k in range(0, len(body), 16384))


def with_urllib(url: str, body: bytes, chunked: bool, tmp_path) -> tuple[int, bytes]:
    request = urllib.request.Request(url, data=chunks(body) if chunked else body, headers=JSON)
    try:
        with urllib.request.urlopen(request, timeout=30) as answer:
            return answer.status, answer.read()
    except urllib.error.HTTPError as error:
        return error.code, error.read()


def with_requests(url: str, body: bytes, chunked: bool, tmp_path) -> tuple[int, bytes]:
    answer = requests.post(url, data=chunks(body) if chunked else body, headers=JSON, timeout=30)
    return answer.status_code, answer.content


def with_httpx(url: str, body: bytes, chunked: bool, tmp_path) -> tuple[int, bytes]:
    answer = httpx.post(url, content=chunks(body) if chunked else body, headers=JSON, timeout=30)
    return answer.status_code, answer.content


def with_curl(url: str, body: bytes, chunked: bool, tmp_path) -> tuple[int, bytes]:
    curl = shutil.which("curl")
    assert curl, "curl is not installed: these tests need it (apt-get install curl)"
    (tmp_path / "body.json").write_bytes(body)
    args = [
        curl,
        "-sS",
        "--max-time",
        "30",
        "-o",
        str(tmp_path / "answer"),
        "-w",
        "%{http_code}",
        "-H",
        "Content-Type: application/json",
        "--data-binary",
        f"@{tmp_path / 'body.json'}",
        url,
    ]
    if chunked:
        args[1:1] = ["-H", "Transfer-Encoding: chunked"]
    run = subprocess.run(args, capture_output=True, text=True)
    assert run.returncode == 0, f"curl failed: {run.stderr}"
    return int(run.stdout), (tmp_path / "answer").read_bytes()


@pytest.mark.parametrize("chunked", [False, True], ids=["content-length", "chunked"])
@pytest.mark.parametrize(
    "post", [with_urllib, with_requests, with_httpx, with_curl], ids=["urllib", "requests", "httpx", "curl"]
)
def test_every_client_reads_the_413_of_an_oversized_body(stack, post, chunked, tmp_path):
    status, body = post(f"{stack.url}/v1/jobs", BIG, chunked, tmp_path)
    assert status == 413, body
    assert json.loads(body)["detail"] == [
        {"field": "body", "message": f"is larger than the limit of {LIMIT} bytes (PERCUSSIM_MAX_BODY_BYTES)"}
    ]


def test_a_body_under_the_limit_is_accepted_and_a_413_leaves_the_client_usable(stack):
    small = json.dumps(merge(BASE_CASE, {"description": "x" * 3000})).encode()
    assert 3000 < len(small) <= LIMIT
    with httpx.Client(base_url=stack.url, headers=JSON, timeout=30) as client:
        for content in (small, chunks(small)):
            assert client.post("/v1/jobs", content=content).status_code == 202
        assert client.post("/v1/jobs", content=BIG).status_code == 413
        assert client.post("/v1/jobs", content=small).status_code == 202  # the same client, after it
