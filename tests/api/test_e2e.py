"""End to end through uvicorn on a free port, on the real queue backends (embedded; Redis when reachable).

Workers run `research.staged_pipeline.StagedPipeline` (the real stage sequence, no science) so these stay fast; the
science itself is exercised by `test_e2e_science.py`.
"""

from __future__ import annotations

import json
import time
from collections.abc import Iterator
from typing import Any

import httpx
import msgpack
import pytest
from fastapi import FastAPI

from manifoundation.contract import ErrorBody, JobPublic, SynthesisResult
from manifoundation.contract.codec import MSGPACK, pack
from manifoundation.server.api.app import create_app
from manifoundation.server.api.settings import Settings

from .helpers import request_body
from .server import serving
from .workers import start_queue_and_workers

KEY = "e2e-test-key-1"
AUTH = {"Authorization": f"Bearer {KEY}"}
HAND = "test_gripper"


class Service:
    def __init__(self, app: FastAPI, base: str) -> None:
        self.app = app
        self.base = base
        self.http = httpx.Client(base_url=base, headers=AUTH, timeout=60)

    def set(self, **changes: Any) -> None:
        """Change settings of the running app (read per request)."""
        self.app.state.services.settings = self.app.state.services.settings.model_copy(update=changes)


@pytest.fixture(scope="module", params=["embedded", "redis"])
def service(request: pytest.FixtureRequest) -> Iterator[Service]:
    with start_queue_and_workers(request, stage_seconds=0.03, max_queue=50) as queue:
        settings = Settings(api_keys=[KEY], rate_limit_per_s=0, sync_wait_max=20, sse_interval=0.05)
        app = create_app(settings, queue=queue)
        with serving(app) as base:
            svc = Service(app, base)
            deadline = time.monotonic() + 120
            while svc.http.get("/readyz").status_code != 200:
                assert time.monotonic() < deadline, "no worker became ready"
                time.sleep(0.1)
            yield svc
            svc.http.close()


def body(**options: Any) -> dict[str, Any]:
    return request_body(HAND, **options)


def error_of(response: httpx.Response, status: int, type_: str) -> ErrorBody:
    assert response.status_code == status, response.text
    error = ErrorBody.model_validate(response.json())
    assert error.type == type_
    return error


def test_sync(service: Service) -> None:
    response = service.http.post("/v1/synthesize", json=body())
    assert response.status_code == 200, response.text
    result = SynthesisResult.model_validate(response.json())
    assert result.hand == HAND and "refinement" in result.timings
    job = JobPublic.model_validate(service.http.get(f"/v1/jobs/{response.headers['x-job-id']}").json())
    assert job.state == "succeeded" and job.result is not None and job.worker


def test_sync_falls_back_to_202(service: Service) -> None:
    service.set(sync_wait_max=0.05)
    try:
        response = service.http.post("/v1/synthesize", json=body(max_iterations=20))
    finally:
        service.set(sync_wait_max=20)
    assert response.status_code == 202, response.text
    job_url = response.json()["url"]
    deadline = time.monotonic() + 30
    while (job := service.http.get(job_url).json())["state"] in ("queued", "running"):
        assert time.monotonic() < deadline
        time.sleep(0.05)
    assert job["state"] == "succeeded"


def test_msgpack(service: Service) -> None:
    response = service.http.post(
        "/v1/synthesize", content=pack(body()), headers={"Content-Type": MSGPACK, "Accept": MSGPACK}
    )
    assert response.status_code == 200 and response.headers["content-type"] == MSGPACK
    assert SynthesisResult.model_validate(msgpack.unpackb(response.content)).hand == HAND


def test_async_and_sse(service: Service) -> None:
    created = service.http.post("/v1/jobs", json=body(max_iterations=5))
    assert created.status_code == 202
    names: list[str] = []
    stages: list[str] = []
    last: dict[str, Any] = {}
    with service.http.stream("GET", f"/v1/jobs/{created.json()['id']}/events") as stream:
        for line in stream.iter_lines():
            if line.startswith("event: "):
                names.append(line[7:])
            elif line.startswith("data: "):
                last = json.loads(line[6:])
                stages.append(last["progress"]["stage"])
    assert names[-1] == "end" and names.count("end") == 1 and "progress" in names
    assert last["state"] == "succeeded" and last["result"]["hand"] == HAND
    assert "refinement" in stages


def test_batch_with_paging(service: Service) -> None:
    created = service.http.post("/v1/batches", json={"requests": [body(seed=i) for i in range(6)]})
    assert created.status_code == 202, created.text
    batch_id = created.json()["id"]
    deadline = time.monotonic() + 60
    while not (batch := service.http.get(f"/v1/batches/{batch_id}", params={"limit": 4}).json())["done"]:
        assert time.monotonic() < deadline
        time.sleep(0.1)
    assert batch["total"] == 6 and batch["counts"] == {"succeeded": 6} and len(batch["items"]) == 4
    second = service.http.get(f"/v1/batches/{batch_id}", params={"offset": 4, "limit": 4}).json()
    assert [i["index"] for i in second["items"]] == [4, 5] and second["items"][1]["result"]["hand"] == HAND


def test_cancel(service: Service) -> None:
    ids = [service.http.post("/v1/jobs", json=body(max_iterations=30)).json()["id"] for _ in range(6)]
    cancelled = service.http.delete(f"/v1/jobs/{ids[-1]}")
    assert cancelled.status_code == 200
    deadline = time.monotonic() + 60
    while (job := service.http.get(f"/v1/jobs/{ids[-1]}").json())["state"] in ("queued", "running"):
        assert time.monotonic() < deadline
        time.sleep(0.05)
    assert job["state"] == "cancelled"


def test_robots(service: Service) -> None:
    names = [r["name"] for r in service.http.get("/v1/robots").json()["robots"]]
    assert HAND in names
    assert service.http.get(f"/v1/robots/{HAND}").json()["fingertips"] == ["left_tip", "right_tip"]
    error_of(service.http.get("/v1/robots/nope"), 404, "UnknownHand")
    urdf = '<robot name="r"><link name="base"/><link name="tip"/></robot>'
    created = service.http.post("/v1/robots", json={"name": "e2e_hand", "urdf": urdf, "fingertips": ["tip"]})
    assert created.status_code == 201, created.text
    assert service.http.get("/v1/robots/e2e_hand").status_code == 200
    bad = service.http.post("/v1/robots", json={"name": "e2e_bad", "urdf": "<robot", "fingertips": ["tip"]})
    error_of(bad, 422, "RobotInvalid")


def test_errors(service: Service) -> None:
    http = service.http
    error_of(http.get("/v1/jobs/0123456789abcdef"), 404, "NotFound")
    error_of(http.post("/v1/synthesize", json=request_body("no_such_hand")), 404, "UnknownHand")
    broken = body()
    broken["object"]["points"][0] = [0.0, "x", 1.0]
    invalid = error_of(http.post("/v1/synthesize", json=broken), 422, "ValidationError")
    assert invalid.detail and invalid.detail[0].field == "object.points"
    error_of(http.post("/v1/jobs", content=b"{", headers={"Content-Type": "application/json"}), 400, "BadRequest")
    service.set(max_body_bytes=2048)
    try:
        assert "2048" in error_of(http.post("/v1/synthesize", json=body()), 413, "PayloadTooLarge").error
    finally:
        service.set(max_body_bytes=64 * 1024 * 1024)
    never = error_of(http.post("/v1/batches", json={"requests": [body()] * 60}), 422, "ValidationError")
    assert "50" in never.error  # a batch larger than the queue can never fit: named, not 429 for ever
    service.app.state.services.shutting_down = True
    try:
        error_of(http.post("/v1/jobs", json=body()), 503, "Unavailable")
    finally:
        service.app.state.services.shutting_down = False


def test_auth_on_and_off(service: Service) -> None:
    anonymous = httpx.Client(base_url=service.base, timeout=30)
    error_of(anonymous.get("/v1/jobs"), 401, "Unauthorized")
    assert anonymous.get("/healthz").status_code == 200 and anonymous.get("/metrics").status_code == 200
    service.set(api_keys=[])
    try:
        assert anonymous.post("/v1/synthesize", json=body()).status_code == 200
    finally:
        service.set(api_keys=[KEY])
    anonymous.close()


def test_rate_limit(service: Service) -> None:
    from manifoundation.server.api.security import RateLimiter

    previous = service.app.state.services.limiter
    service.app.state.services.limiter = RateLimiter(0.2, 2)
    try:
        codes = [service.http.get("/v1/jobs").status_code for _ in range(3)]
    finally:
        service.app.state.services.limiter = previous
    assert codes == [200, 200, 429]


def test_ready_metrics_dashboard(service: Service) -> None:
    ready = service.http.get("/readyz").json()
    assert ready["ready"] and ready["model_loaded"] and ready["workers"] >= 1
    service.http.post("/v1/synthesize", json=body())
    metrics = service.http.get("/metrics").text
    for name in (
        "mani_requests_total",
        "mani_request_duration_seconds_bucket",
        "mani_queue_depth",
        'mani_jobs{state="succeeded"}',
        "mani_stage_duration_seconds_bucket",
        "mani_workers 1.0",
        "mani_batch_size_count",
        "mani_dead_letters",
        "mani_queue_up 1.0",
    ):
        assert name in metrics, name
    data = service.http.get("/dashboard/data").json()
    assert data["queue_up"] and data["workers"] and data["recent"]
    assert data["workers"][0]["model_loaded"]
