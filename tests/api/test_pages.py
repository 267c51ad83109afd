"""Dashboard and result viewer in headless Chromium against a running service (offline: no CDN)."""

from __future__ import annotations

import re
from collections.abc import Iterator

import httpx
import pytest

from manifoundation.server.api.app import create_app
from manifoundation.server.api.settings import Settings

from .browser import chromium, dump_dom, screenshot
from .fakes import FakeQueue
from .helpers import request_body
from .server import serving
from .workers import start_queue_and_workers

KEY = "page-test-key-1"


@pytest.fixture(scope="module")
def service() -> Iterator[str]:
    """A service whose jobs carry full results (in-memory queue: contacts, forces, hand pose, heatmap)."""
    chromium()
    with serving(create_app(Settings(api_keys=[KEY], dashboard_sample_s=0.2), queue=FakeQueue())) as base:
        yield base


@pytest.fixture(scope="module")
def embedded(request: pytest.FixtureRequest) -> Iterator[str]:
    """A service on the embedded backend with one real worker process (staged pipeline)."""
    chromium()
    settings = Settings(api_keys=[KEY], dashboard_sample_s=0.2)
    with (
        start_queue_and_workers(request, stage_seconds=0.01) as queue,
        serving(create_app(settings, queue=queue)) as base,
    ):
        yield base


def test_pages_load_nothing_from_outside(service: str) -> None:
    for path in ("/", "/view/x"):
        html = httpx.get(service + path).text
        sources = re.findall(r'(?:src|href)="([^"]+)"', html)
        assert sources and all(s.startswith("/") for s in sources), sources


def test_dashboard_shows_the_submitted_job(embedded: str) -> None:
    auth = {"Authorization": f"Bearer {KEY}"}
    response = httpx.post(f"{embedded}/v1/synthesize", json=request_body("test_gripper"), headers=auth, timeout=60)
    job_id = response.headers["x-job-id"]
    worker = httpx.get(f"{embedded}/v1/jobs/{job_id}", headers=auth).json()["worker"]
    dom = dump_dom(f"{embedded}/#key={KEY}")
    assert job_id in dom and 'class="state-succeeded"' in dom
    assert worker in dom and "staged-test" in dom  # the worker row: id and model version
    assert "could not load" not in dom and "main-svg" in dom  # plotly drew the time-series charts
    png = screenshot(f"{embedded}/#key={KEY}", "dashboard.png")
    assert png.stat().st_size > 10_000


def test_viewer_draws_the_result(service: str) -> None:
    auth = {"Authorization": f"Bearer {KEY}"}
    response = httpx.post(f"{service}/v1/synthesize", json=request_body(return_heatmap=True), headers=auth)
    job_id = response.headers["x-job-id"]
    url = f"{service}/view/{job_id}#key={KEY}"
    dom = dump_dom(url, budget_ms=4000)
    assert "could not load" not in dom
    assert "Ferrari–Canny ε" in dom and "converged" in dom and "fake_hand" in dom
    assert "proposal 0" in dom and "proposal 1" not in dom  # numbered as the CLI and `result.proposals[i]`
    assert "not run: options.simulate false" in dom  # no physics test ran


def test_viewer_shows_the_physics_trials(service: str) -> None:
    auth = {"Authorization": f"Bearer {KEY}"}
    response = httpx.post(f"{service}/v1/synthesize", json=request_body(simulate=True), headers=auth)
    url = f"{service}/view/{response.headers['x-job-id']}#key={KEY}"
    dom = dump_dom(url, budget_ms=4000)
    assert "failed (moved)" in dom and "push +z" in dom and "80.0 mm" in dom and "1.2, 0.4" in dom
    assert "gl-container" in dom and "3D view unavailable" not in dom  # plotly's WebGL scene was drawn
    png = screenshot(url, "viewer.png", budget_ms=4000)
    assert png.stat().st_size > 10_000


@pytest.mark.slow
def test_viewer_without_key_says_why(service: str) -> None:
    dom = dump_dom(f"{service}/view/whatever")
    assert "could not load the job" in dom and "API key" in dom
