"""One encode and one validation per trust boundary (docs/request-flow.md), counted on real processes.

`mani serve` (and, for Redis, `mani worker`) run with a start-up hook (`tests/api/counting`) that counts, per
process, every msgpack/JSON encode and decode of a request or a result and every validation of one; one msgpack
request goes through `POST /v1/synthesize` and comes back as msgpack. The API must decode and validate the
request once, encode it once for the queue, and decode, validate and encode the result once; the worker must
decode and validate the request once and build and encode the result once.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from collections import Counter
from collections.abc import Iterator
from pathlib import Path

import httpx
import pytest

from manifoundation.contract.codec import MSGPACK, pack, unpack
from tests.api.server import free_port

COUNTING = Path(__file__).parent / "counting"
STAGED = "research.staged_pipeline:StagedPipeline"

API = Counter({
    "decode.request": 1, "validate.request": 1, "encode.request": 1,
    "decode.result": 1, "validate.result": 1, "encode.result": 1,
})  # fmt: skip
WORKER = Counter({"decode.request": 1, "validate.request": 1, "validate.result": 1, "encode.result": 1})


def _request() -> dict[str, object]:
    import numpy as np

    points = np.random.default_rng(0).normal(size=(64, 3))
    points = 0.03 * points / np.linalg.norm(points, axis=1, keepdims=True)
    return {
        "object": {"points": points, "normals": points / 0.03},
        "task": {"kind": "force_closure"},
        "robot": {"name": "test_gripper"},
        "options": {"method": "direct_grasp", "seed": 1},
    }


def _wait_ready(base: str, proc: subprocess.Popen[bytes], workers: int) -> None:
    deadline = time.monotonic() + 120
    while True:
        assert proc.poll() is None, "mani serve exited"
        assert time.monotonic() < deadline, "mani serve never became ready"
        try:
            ready = httpx.get(f"{base}/readyz", timeout=2)
            if ready.status_code == 200 and ready.json()["workers"] >= workers:
                return
        except httpx.HTTPError:
            pass
        time.sleep(0.2)


@pytest.fixture(params=["embedded", "redis"])
def counted_service(request: pytest.FixtureRequest, tmp_path: Path) -> Iterator[tuple[str, Path]]:
    counts = tmp_path / "counts"
    counts.mkdir()
    env = dict(os.environ, MANI_PIPELINE=STAGED, MANI_LOG_LEVEL="WARNING", MANI_TEST_COUNT_DIR=str(counts))
    env["PYTHONPATH"] = os.pathsep.join([str(COUNTING), *filter(None, [env.get("PYTHONPATH")])])
    env.pop("MANI_REDIS_URL", None)
    procs: list[subprocess.Popen[bytes]] = []
    if request.param == "redis":
        env["MANI_REDIS_URL"] = request.getfixturevalue("redis_url")
        env["MANI_QUEUE_PREFIX"] = request.getfixturevalue("redis_prefix")
        worker = [sys.executable, "-m", "manifoundation.cli.main", "worker", "--concurrency", "1"]
        procs.append(subprocess.Popen(worker, env=env))
    port = free_port()
    serve = [sys.executable, "-m", "manifoundation.cli.main", "serve", "--port", str(port), "--workers", "1"]
    procs.append(subprocess.Popen(serve, env=env))
    base = f"http://127.0.0.1:{port}"
    try:
        _wait_ready(base, procs[-1], workers=1)
        yield base, counts
    finally:
        for proc in reversed(procs):
            proc.send_signal(signal.SIGTERM)
            proc.wait(60)


def _by_role(counts: Path) -> dict[str, Counter[str]]:
    found: dict[str, Counter[str]] = {}
    for path in counts.glob("*.json"):
        data = json.loads(path.read_text())
        found.setdefault(data["role"], Counter()).update(data["counts"])
    return found


def test_one_encode_and_one_validation_per_boundary(counted_service: tuple[str, Path]) -> None:
    base, counts = counted_service
    response = httpx.post(
        f"{base}/v1/synthesize", content=pack(_request()),
        headers={"Content-Type": MSGPACK, "Accept": MSGPACK}, timeout=60,
    )  # fmt: skip
    assert response.status_code == 200, response.text
    assert unpack(response.content)["model_version"] == "staged-test"
    roles = _by_role(counts)
    worker_role = (
        "manifoundation.server.worker.worker"
        if "manifoundation.server.worker.worker" in roles
        else "manifoundation.server.worker.child"
    )
    assert roles.get("service") == API, roles
    assert roles.get(worker_role) == WORKER, roles
