"""Registered hands are bounded per key (MANI_MAX_ROBOTS, and MANI_MAX_ROBOT_BYTES each) and can be removed,
on the real queue backends."""

from __future__ import annotations

import time
from collections.abc import Iterator

import httpx
import pytest

from manifoundation.server.api.app import create_app
from manifoundation.server.api.settings import Settings

from .helpers import request_body
from .server import serving
from .workers import start_queue_and_workers

URDF = '<robot name="r"><link name="a"/><link name="b"/><joint name="j" type="revolute"><parent link="a"/>' \
       '<child link="b"/><limit lower="0" upper="1"/></joint></robot>'  # fmt: skip


@pytest.fixture(scope="module", params=["embedded", "redis"])
def http(request: pytest.FixtureRequest) -> Iterator[httpx.Client]:
    with start_queue_and_workers(request, stage_seconds=0.0) as queue:
        settings = Settings(rate_limit_per_s=0, max_robots=2, max_robot_bytes=2048, robots_cache_s=0)
        with serving(create_app(settings, queue=queue)) as base, httpx.Client(base_url=base, timeout=60) as client:
            deadline = time.monotonic() + 120
            while client.get("/readyz").status_code != 200:
                assert time.monotonic() < deadline
                time.sleep(0.1)
            yield client


def register(http: httpx.Client, name: str, urdf: str = URDF) -> httpx.Response:
    return http.post("/v1/robots", json={"name": name, "urdf": urdf, "fingertips": ["b"]})


def test_count_and_size_bounds_and_delete(http: httpx.Client) -> None:
    assert [register(http, n).status_code for n in ("h1", "h2")] == [201, 201]
    full = register(http, "h3")
    assert full.status_code == 409 and "at most 2" in full.json()["error"]
    assert register(http, "h2").status_code == 201  # replacing one of its own is fine
    assert register(http, "big", URDF + " " * 4096).status_code == 413
    assert http.delete("/v1/robots/h1").status_code == 204
    assert http.get("/v1/robots/h1").status_code == 404
    gone = http.post("/v1/synthesize", json=request_body("h1", max_iterations=1))
    assert gone.status_code == 404
    assert register(http, "h3").status_code == 201
    assert http.delete("/v1/robots/h1").status_code == 404
    assert http.delete("/v1/robots/test_gripper").status_code == 409  # built-in
    assert {r["name"] for r in http.get("/v1/robots").json()["robots"]} == {"test_gripper", "h2", "h3"}
