"""The SDK and the CLI against the real service: uvicorn on a free loopback port, the real app and routes.

The queue behind it is the service tests' in-memory `FakeQueue` (``tests/api/fakes.py``: jobs finish at once
with a synthetic result, or wait for `finish` when held), so these tests exercise the whole HTTP path (encodings,
errors, 202s, SSE, batches and paging, auth, rate limits) in a few seconds. ``test_embedded_e2e.py`` runs the
real embedded queue and workers.
"""

from __future__ import annotations

import asyncio
import contextlib
import importlib.util
import json
import socket
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np
import pytest

from manifoundation.cli.main import EXIT_FAILED, EXIT_OK, EXIT_USAGE
from manifoundation.cli.main import main as mani
from manifoundation.contract import JobState
from manifoundation.sdk import (
    AsyncClient,
    Client,
    JobFailed,
    NotFound,
    RateLimited,
    Unauthorized,
    ValidationError,
    make_request,
    object_from_points,
    save_object,
)

ROOT = Path(__file__).resolve().parents[3]
KEY = "sdk-test-key-0001"
HAND = "fake_hand"

import uvicorn  # noqa: E402


def _load(name: str) -> ModuleType:
    path = ROOT / "tests" / "api" / f"{name}.py"
    spec = importlib.util.spec_from_file_location(f"_sdk_e2e_{name}", path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


@contextlib.contextmanager
def serving(queue: Any, **settings: Any) -> Iterator[str]:
    """The real app with ``queue`` under uvicorn in a thread; yields its base URL."""
    from manifoundation.server.api.app import create_app
    from manifoundation.server.api.settings import Settings

    settings.setdefault("log_level", "WARNING")
    app = create_app(Settings(**settings), queue=queue)
    port = _free_port()
    config = uvicorn.Config(app, host="127.0.0.1", port=port, log_config=None, access_log=False, lifespan="on")
    server = uvicorn.Server(config)
    thread = threading.Thread(target=server.run, daemon=True)
    thread.start()
    deadline = time.monotonic() + 60
    while not server.started:
        assert thread.is_alive() and time.monotonic() < deadline, "uvicorn did not start"
        time.sleep(0.02)
    try:
        yield f"http://127.0.0.1:{port}"
    finally:
        server.should_exit = True
        thread.join(timeout=30)


@pytest.fixture(scope="module")
def fakes() -> ModuleType:
    return _load("fakes")


@pytest.fixture(scope="module")
def served(fakes: ModuleType) -> Iterator[tuple[str, Any]]:
    queue = fakes.FakeQueue()
    with serving(queue, sync_wait_max=0.5, max_batch_size=20, rate_limit_per_s=0) as url:
        yield url, queue


@pytest.fixture
def client(served: tuple[str, Any]) -> Iterator[Client]:
    with Client(served[0], poll_interval=0.05) as c:
        yield c


def _points(n: int = 128, scale: float = 0.04) -> np.ndarray:
    i = np.arange(n) + 0.5
    phi, theta = np.arccos(1 - 2 * i / n), np.pi * (1 + 5**0.5) * i
    normals = np.stack([np.cos(theta) * np.sin(phi), np.sin(theta) * np.sin(phi), np.cos(phi)], axis=1)
    return np.hstack([normals * scale, normals])


def _until(predicate: Any, timeout: float = 10.0) -> None:
    deadline = time.monotonic() + timeout
    while not predicate():
        assert time.monotonic() < deadline, "condition not reached"
        time.sleep(0.01)


@pytest.mark.parametrize("encoding", ["msgpack", "json"])
def test_synthesize_both_encodings(served: tuple[str, Any], encoding: str) -> None:
    with Client(served[0], encoding=encoding) as client:
        result = client.synthesize(_points(), "force_closure", HAND, method="direct_grasp")
    assert result.hand or result.proposals
    best = result.best
    assert best is not None and isinstance(best.contact_points, np.ndarray)
    assert np.allclose(best.contact_points[0], _points()[0, :3])  # the fake's contacts are input points


def test_service_errors_map_to_the_tree(client: Client) -> None:
    with pytest.raises(NotFound) as unknown:
        client.synthesize(_points(), robot="no_such_hand")
    assert unknown.value.status_code == 404 and "no_such_hand" in str(unknown.value)
    with pytest.raises(ValidationError) as too_many:  # the server's own limit (max_batch_size=20)
        client.submit_batch([make_request(_points(), robot=HAND)] * 21)
    assert too_many.value.status_code == 422 and "requests" in too_many.value.message
    with pytest.raises(NotFound):
        client.job("0123456789abcdef").status()


def test_202_then_the_job_finishes(served: tuple[str, Any], client: Client) -> None:
    _, queue = served
    queue.hold = True
    try:
        before = set(queue.jobs)
        box: dict[str, Any] = {}
        thread = threading.Thread(target=lambda: box.setdefault("r", client.synthesize(_points(), robot=HAND,
                                                                                       timeout=20)))  # fmt: skip
        thread.start()
        _until(lambda: set(queue.jobs) - before)
        (job_id,) = set(queue.jobs) - before
        time.sleep(0.8)  # past the server's 0.5 s wait: the SDK got a 202 and polls the job
        queue.finish(job_id)
        thread.join(timeout=20)
        assert box["r"].best is not None
    finally:
        queue.hold = False


def test_job_events_cancel_and_failure(served: tuple[str, Any], client: Client) -> None:
    _, queue = served
    queue.hold = True
    try:
        job = client.submit(_points(), robot=HAND)
        assert job.status().state is JobState.QUEUED
        threading.Timer(0.3, lambda: queue.finish(job.id)).start()
        events = list(job.events(timeout=10))
        assert events[-1].state is JobState.SUCCEEDED and events[-1].result is not None
        assert job.wait(5).best is not None

        other = client.submit(_points(), robot=HAND)
        assert other.cancel().state is JobState.CANCELLED
        with pytest.raises(JobFailed) as info:
            other.wait(5)
        assert info.value.state is JobState.CANCELLED

        failing = client.submit(_points(), robot=HAND)
        from manifoundation.contract import ErrorBody

        queue.finish(failing.id, ErrorBody(error="no feasible grasp", type="InternalError"))
        with pytest.raises(JobFailed) as failed:
            failing.wait(5)
        assert failed.value.error is not None and failed.value.error.type == "InternalError"
    finally:
        queue.hold = False


def test_batch_results_in_request_order(client: Client) -> None:
    scales = np.linspace(0.02, 0.06, 7)
    requests = [make_request(_points(scale=s), "force_closure", HAND) for s in scales]
    batch = client.submit_batch(requests)
    batch.page_size = 3
    results = batch.results(timeout=20)
    firsts = [r.best.contact_points[0] for r in results if r.best is not None]
    assert np.allclose(firsts, [_points(scale=s)[0, :3] for s in scales])
    assert client.batch(batch.id).total == 7


def test_robots_health_ready(client: Client) -> None:
    assert HAND in [r.name for r in client.robots()]
    assert client.robot(HAND).fingertips
    registered = client.register_robot('<robot name="Tiny Gripper"><link name="a"/></robot>', ["a"])
    assert registered.name == "tiny-gripper"
    with pytest.raises(ValidationError, match="urdf"):
        client.register_robot("<notarobot/>", ["a"], name="broken")
    assert client.health()
    ready = client.ready()
    assert ready.ready and ready.workers >= 1


def test_async_client(served: tuple[str, Any]) -> None:
    async def main() -> tuple[int, int]:
        async with AsyncClient(served[0], poll_interval=0.05) as client:
            results = await asyncio.gather(*(client.synthesize(_points(), robot=HAND) for _ in range(4)))
            batch = await client.submit_batch([make_request(_points(), robot=HAND) for _ in range(3)])
            return len(results), len(await batch.results(timeout=20))

    assert asyncio.run(main()) == (4, 3)


def test_auth_rate_limit_and_full_queue(fakes: ModuleType) -> None:
    queue = fakes.FakeQueue()
    with serving(queue, api_keys=[KEY], rate_limit_per_s=0.01, rate_limit_burst=2) as url:
        with Client(url) as anonymous:
            with pytest.raises(Unauthorized):
                anonymous.robots()
            assert anonymous.health()  # open without a key
        with Client(url, KEY, retries=0) as client:
            client.robots()
            client.robots()
            with pytest.raises(RateLimited) as limited:
                client.robots()
            assert limited.value.retry_after is not None and limited.value.retry_after >= 1
    queue = fakes.FakeQueue()
    queue.full = True
    with serving(queue, rate_limit_per_s=0) as url, Client(url, retries=0) as client:
        with pytest.raises(RateLimited) as full:
            client.synthesize(_points(), robot=HAND)
        assert full.value.type == "QueueFull" and full.value.retry_after == 3.0


def test_cli_against_the_service(served: tuple[str, Any], tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    url = served[0]
    obj = save_object(object_from_points(_points()), tmp_path / "ball.npz")
    view = tmp_path / "view.html"
    assert mani(["synthesize", str(obj), "--hand", HAND, "--url", url, "--view", str(view), "--json"]) == EXIT_OK
    job_id = json.loads(capsys.readouterr().out)["job_id"]
    assert view.stat().st_size > 100_000  # plotly bundled: works offline
    assert mani(["synthesize", str(obj), "--hand", "nope", "--url", url]) == EXIT_USAGE
    assert mani(["jobs", "show", job_id, "--url", url, "--json"]) == EXIT_OK
    assert json.loads(capsys.readouterr().out)["state"] == "succeeded"
    save_object(object_from_points(_points(scale=0.05)), tmp_path / "ball2.npz")
    out = tmp_path / "results.jsonl"
    code = mani(["batch", "submit", str(tmp_path), "--hand", HAND, "--url", url, "--wait", "--out", str(out), "--json"])
    assert code == EXIT_OK and len(out.read_text().splitlines()) == 2
    capsys.readouterr()
    assert mani(["jobs", "--url", url, "--json"]) == EXIT_OK
    assert job_id in [j["id"] for j in json.loads(capsys.readouterr().out)]
    assert mani(["jobs", "show", "ffff", "--url", url]) in (EXIT_USAGE, EXIT_FAILED)
