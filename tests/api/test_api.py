"""The API layer against an in-memory queue: every route, both encodings, every error case, auth, limits."""

from __future__ import annotations

import json
import time
from collections.abc import Iterator

import httpx
import msgpack
import numpy as np
import pytest
from fastapi.testclient import TestClient

from manifoundation.contract import ErrorBody, JobPublic, SynthesisResult
from manifoundation.contract.codec import MSGPACK, pack
from manifoundation.server.api.app import create_app
from manifoundation.server.api.settings import Settings

from .fakes import FakeQueue
from .helpers import request_body
from .server import serving

KEY = "secret-key-1234"


def make_client(queue: FakeQueue | None = None, **settings: object) -> TestClient:
    return TestClient(create_app(Settings(**settings), queue=queue or FakeQueue()))  # type: ignore[arg-type]


@pytest.fixture
def queue() -> FakeQueue:
    return FakeQueue()


@pytest.fixture
def client(queue: FakeQueue) -> Iterator[TestClient]:
    with make_client(queue) as c:
        yield c


def assert_error(response: httpx.Response, status: int, type_: str) -> ErrorBody:
    assert response.status_code == status, response.text
    body = ErrorBody.model_validate(response.json())
    assert body.type == type_
    return body


def test_synthesize_returns_the_result(client: TestClient) -> None:
    response = client.post("/v1/synthesize", json=request_body(return_heatmap=True))
    assert response.status_code == 200, response.text
    result = SynthesisResult.model_validate(response.json())
    assert result.proposals and result.heatmap is not None and len(result.heatmap) == 128
    job_id = response.headers["x-job-id"]
    assert client.get(f"/v1/jobs/{job_id}").json()["state"] == "succeeded"


def test_msgpack_both_ways(client: TestClient) -> None:
    body = request_body()
    body["object"]["points"] = np.asarray(body["object"]["points"], dtype=np.float32)
    response = client.post("/v1/synthesize", content=pack(body), headers={"Content-Type": MSGPACK, "Accept": MSGPACK})
    assert response.status_code == 200
    assert response.headers["content-type"] == MSGPACK
    data = msgpack.unpackb(response.content)
    assert set(data["proposals"][0]["contact_points"]) == {"dtype", "shape", "data"}
    result = SynthesisResult.model_validate(data)
    assert result.proposals[0].contact_points.shape == (2, 3)
    bad = client.post("/v1/jobs", content=pack({"object": 1}), headers={"Content-Type": MSGPACK, "Accept": MSGPACK})
    assert bad.status_code == 422 and ErrorBody.model_validate(msgpack.unpackb(bad.content)).type == "ValidationError"


def test_async_job_get_list_cancel() -> None:
    queue = FakeQueue(hold=True)
    with make_client(queue) as client:
        response = client.post("/v1/jobs", json=request_body())
        assert response.status_code == 202
        created = response.json()
        assert created["state"] == "queued" and created["url"].endswith(f"/v1/jobs/{created['id']}")
        assert response.headers["location"] == created["url"]
        assert client.get(f"/v1/jobs/{created['id']}").json()["state"] == "queued"
        assert [j["id"] for j in client.get("/v1/jobs?limit=5").json()["jobs"]] == [created["id"]]
        cancelled = client.delete(f"/v1/jobs/{created['id']}")
        assert cancelled.status_code == 200 and cancelled.json()["state"] == "cancelled"


def test_synthesize_answers_202_when_the_wait_runs_out() -> None:
    with make_client(FakeQueue(hold=True), sync_wait_max=0.2) as client:
        started = time.monotonic()
        response = client.post("/v1/synthesize", json=request_body(timeout=60))
        assert response.status_code == 202 and time.monotonic() - started < 5
        assert "/v1/jobs/" in response.json()["url"]


def test_failed_job_keeps_the_error_shape() -> None:
    queue = FakeQueue(hold=True)
    with make_client(queue, sync_wait_max=0.3) as client:
        job_id = client.post("/v1/jobs", json=request_body()).json()["id"]
        queue.finish(job_id, ErrorBody(error="object.points: too flat", type="ValidationError"))
        job = JobPublic.model_validate(client.get(f"/v1/jobs/{job_id}").json())
        assert job.state == "failed" and job.error is not None and job.error.type == "ValidationError"


def test_every_submit_route_hands_the_request_id_to_the_queue(client: TestClient, queue: FakeQueue) -> None:
    sync = client.post("/v1/synthesize", json=request_body(), headers={"X-Request-ID": "abc-123"})
    assert sync.headers["x-request-id"] == "abc-123"
    assert queue.request_ids[sync.headers["x-job-id"]] == "abc-123"
    job_id = client.post("/v1/jobs", json=request_body(), headers={"X-Request-ID": "abc-124"}).json()["id"]
    assert queue.request_ids[job_id] == "abc-124"
    batch = client.post("/v1/batches", json={"requests": [request_body()] * 3}, headers={"X-Request-ID": "abc-125"})
    assert [queue.request_ids[i["job_id"]] for i in batch.json()["items"]] == ["abc-125"] * 3
    fresh = client.post("/v1/jobs", json=request_body())  # no header: the id the service made up and echoed
    assert queue.request_ids[fresh.json()["id"]] == fresh.headers["x-request-id"]


def test_batches_with_paging(client: TestClient) -> None:
    response = client.post("/v1/batches", json={"requests": [request_body() for _ in range(5)]})
    assert response.status_code == 202, response.text
    batch_id = response.json()["id"]
    page = client.get(f"/v1/batches/{batch_id}", params={"offset": 2, "limit": 2}).json()
    assert page["total"] == 5 and page["done"] and page["counts"] == {"succeeded": 5}
    assert [i["index"] for i in page["items"]] == [2, 3] and page["items"][0]["result"]["proposals"]
    invalid = client.post("/v1/batches", json={"requests": [request_body(), {"object": {}}]})
    assert any(d.field.startswith("requests.1.") for d in assert_error(invalid, 422, "ValidationError").detail or [])
    assert_error(client.post("/v1/batches", json={"requests": []}), 422, "ValidationError")
    assert_error(client.get("/v1/batches/nope"), 404, "NotFound")


def test_robots(client: TestClient) -> None:
    assert [r["name"] for r in client.get("/v1/robots").json()["robots"]] == ["fake_hand"]
    assert client.get("/v1/robots/fake_hand").json()["dof"] == 2
    assert_error(client.get("/v1/robots/nope"), 404, "UnknownHand")
    urdf = '<robot name="r"><link name="tip"/></robot>'
    created = client.post("/v1/robots", json={"name": "my_hand", "urdf": urdf, "fingertips": ["tip"]})
    assert created.status_code == 201 and created.json()["name"] == "my_hand"
    assert client.get("/v1/robots/my_hand").status_code == 200
    bad = client.post("/v1/robots", json={"name": "bad_hand", "urdf": "<nope/>", "fingertips": ["tip"]})
    assert assert_error(bad, 422, "RobotInvalid").detail[0].field == "urdf"  # type: ignore[index]
    taken = client.post("/v1/robots", json={"name": "fake_hand", "urdf": urdf, "fingertips": ["tip"]})
    assert_error(taken, 409, "Conflict")


def test_validation_errors_name_field_and_problem(client: TestClient) -> None:
    body = request_body()
    body["object"]["points"][3][1] = float("nan")
    response = client.post("/v1/synthesize", content=json.dumps(body), headers={"Content-Type": "application/json"})
    error = assert_error(response, 422, "ValidationError")
    assert error.detail and error.detail[0].field == "object.points" and "NaN" in error.detail[0].problem
    body = request_body()
    body["object"]["normals"] = body["object"]["normals"][:-1]
    error = assert_error(client.post("/v1/jobs", json=body), 422, "ValidationError")
    assert error.detail and error.detail[0].field == "object.normals"
    body = request_body()
    body["object"]["points"] = body["object"]["points"][:10]
    body["object"]["normals"] = None
    error = assert_error(client.post("/v1/jobs", json=body), 422, "ValidationError")
    assert "10 points" in error.error


def test_malformed_bodies(client: TestClient) -> None:
    headers = {"Content-Type": "application/json"}
    assert_error(client.post("/v1/synthesize", content=b"{not json", headers=headers), 400, "BadRequest")
    assert_error(client.post("/v1/synthesize", content=b"", headers=headers), 400, "BadRequest")
    assert_error(client.post("/v1/synthesize", content=b"[1, 2]", headers=headers), 422, "ValidationError")
    raw = {"Content-Type": MSGPACK}
    assert_error(client.post("/v1/synthesize", content=b"\xc1\xff", headers=raw), 400, "BadRequest")
    text = {"Content-Type": "text/plain"}
    assert_error(client.post("/v1/synthesize", content=b"hi", headers=text), 415, "UnsupportedMediaType")


def test_unknown_job_and_hand(client: TestClient) -> None:
    assert_error(client.get("/v1/jobs/nope"), 404, "NotFound")
    assert_error(client.delete("/v1/jobs/nope"), 404, "NotFound")
    assert_error(client.get("/v1/jobs/nope/events"), 404, "NotFound")
    error = assert_error(client.post("/v1/synthesize", json=request_body(hand="no_such_hand")), 404, "UnknownHand")
    assert error.detail and error.detail[0].field == "robot.name"


def test_body_size_limit() -> None:
    with make_client(max_body_bytes=4096) as client:
        error = assert_error(client.post("/v1/synthesize", json=request_body()), 413, "PayloadTooLarge")
        assert "4096" in error.error


def test_queue_full_and_unavailable(queue: FakeQueue, client: TestClient) -> None:
    queue.full = True
    response = client.post("/v1/jobs", json=request_body())
    assert_error(response, 429, "QueueFull")
    assert response.headers["retry-after"] == "3"
    queue.full, queue.down = False, True
    response = client.post("/v1/jobs", json=request_body())
    assert_error(response, 503, "Unavailable")
    assert "retry-after" in response.headers
    assert client.get("/readyz").status_code == 503
    assert client.get("/healthz").status_code == 200


def test_shutting_down_answers_503(client: TestClient) -> None:
    client.app.state.services.shutting_down = True  # type: ignore[attr-defined]
    assert_error(client.post("/v1/jobs", json=request_body()), 503, "Unavailable")
    assert client.get("/healthz").status_code == 200
    client.app.state.services.shutting_down = False  # type: ignore[attr-defined]


def test_auth_on() -> None:
    with make_client(api_keys=[KEY]) as client:
        assert_error(client.get("/v1/jobs"), 401, "Unauthorized")
        assert_error(client.get("/v1/jobs", headers={"Authorization": "Bearer wrong-key-99"}), 401, "Unauthorized")
        assert_error(client.get("/v1/jobs", headers={"Authorization": f"Basic {KEY}"}), 401, "Unauthorized")
        assert client.get("/v1/jobs", headers={"Authorization": f"Bearer {KEY}"}).status_code == 200
        assert_error(client.get("/dashboard/data"), 401, "Unauthorized")
        for path in ("/healthz", "/readyz", "/metrics", "/", "/view/x", "/static/plotly.min.js"):
            assert client.get(path).status_code == 200, path
        assert_error(client.get("/v1/jobs/x/view"), 401, "Unauthorized")  # under /v1: the key, then 404
        assert_error(client.get("/v1/jobs/x/view", headers={"Authorization": f"Bearer {KEY}"}), 404, "NotFound")
    with make_client(api_keys=[KEY], open_paths=["/healthz"]) as client:
        assert client.get("/metrics").status_code == 401


def test_auth_off_by_default(client: TestClient) -> None:
    assert client.get("/v1/jobs").status_code == 200


def test_rate_limit_per_key() -> None:
    with make_client(api_keys=[KEY, "other-key-5678"], rate_limit_per_s=0.5, rate_limit_burst=2) as client:
        auth = {"Authorization": f"Bearer {KEY}"}
        assert [client.get("/v1/jobs", headers=auth).status_code for _ in range(2)] == [200, 200]
        limited = client.get("/v1/jobs", headers=auth)
        assert_error(limited, 429, "RateLimited")
        assert int(limited.headers["retry-after"]) >= 1
        assert client.get("/v1/jobs", headers={"Authorization": "Bearer other-key-5678"}).status_code == 200


def test_request_id_is_echoed_or_generated(client: TestClient) -> None:
    assert client.get("/healthz", headers={"X-Request-ID": "abc-123"}).headers["x-request-id"] == "abc-123"
    generated = client.get("/healthz", headers={"X-Request-ID": "bad id with spaces"}).headers["x-request-id"]
    assert len(generated) == 32


def test_health_ready_metrics(client: TestClient) -> None:
    assert client.get("/healthz").json()["status"] == "ok"
    ready = client.get("/readyz").json()
    assert ready["ready"] and ready["workers"] == 1
    client.post("/v1/synthesize", json=request_body())
    client.post("/v1/batches", json={"requests": [request_body()] * 3})
    text = client.get("/metrics").text
    for name in (
        'mani_requests_total{method="POST",route="/v1/synthesize",status="200"}',
        "mani_request_duration_seconds_bucket",
        "mani_queue_depth",
        'mani_jobs{state="succeeded"} 4.0',
        'mani_stage_duration_seconds_count{stage="refinement"}',
        "mani_batch_size_count 1.0",
        "mani_workers 1.0",
        "mani_dead_letters 0.0",
        "mani_jobs_completed_total 4.0",
    ):
        assert name in text, name


def test_openapi_documents_bodies(client: TestClient) -> None:
    schema = client.get("/openapi.json").json()
    body = schema["paths"]["/v1/synthesize"]["post"]["requestBody"]["content"]
    assert set(body) == {"application/json", "application/msgpack"}
    assert "SynthesisRequest" in schema["components"]["schemas"]
    assert "ObjectIn" in schema["components"]["schemas"]


def test_scene_and_pages(client: TestClient) -> None:
    job_id = client.post("/v1/synthesize", json=request_body(return_heatmap=True)).headers["x-job-id"]
    scene = client.get(f"/v1/jobs/{job_id}/scene").json()
    assert len(scene["points"]) == 128 and len(scene["heatmap"]) == 128 and scene["job"]["result"]
    assert "plotly.min.js" in client.get("/").text
    assert "viewer.js" in client.get(f"/v1/jobs/{job_id}/view").text
    bundle = client.get("/static/plotly.min.js")
    assert bundle.status_code == 200 and len(bundle.content) > 1_000_000
    assert client.get("/static/../settings.py").status_code == 404
    data = client.get("/dashboard/data").json()
    assert data["recent"][0]["id"] == job_id


def test_dashboard_data_has_the_verified_grasp_rate() -> None:
    """Of the recent synthesis jobs that finished (succeeded or failed), the share whose best proposal is verified;
    a succeeded job without a verified proposal counts against it (it is not 'succeeded' in the user's sense)."""
    queue = FakeQueue(hold=True)
    with make_client(queue) as client:
        assert client.get("/dashboard/data").json().get("verified_rate") is None  # nothing finished yet (omitted)
        ids = [client.post("/v1/jobs", json=request_body(seed=k)).json()["id"] for k in range(4)]
        queue.finish(ids[0])  # verified
        queue.finish(ids[1])  # succeeded, but its only proposal failed verification
        result = queue.jobs[ids[1]].result
        assert result is not None
        result.proposals[0].quality.success = False
        queue.finish(ids[2], ErrorBody(error="boom", type="InternalError"))  # failed
        # ids[3] still queued: not finished, not counted
        for _ in range(2):  # the second answer comes from what the first remembered
            data = client.get("/dashboard/data").json()
            assert (data["verified_grasps"], data["finished_jobs"]) == (1, 3)
            assert data["verified_rate"] == pytest.approx(1 / 3)
        assert "verified_rate" in client.get("/static/dashboard.js").text


def test_sse_events_over_uvicorn() -> None:
    queue = FakeQueue(hold=True)
    with serving(create_app(Settings(sse_interval=0.05), queue=queue)) as base:
        job_id = httpx.post(f"{base}/v1/jobs", json=request_body()).json()["id"]
        events: list[tuple[str, dict[str, object]]] = []
        with httpx.stream("GET", f"{base}/v1/jobs/{job_id}/events", timeout=10) as response:
            assert response.headers["content-type"].startswith("text/event-stream")
            name = ""
            for line in response.iter_lines():
                if line.startswith("event: "):
                    name = line[7:]
                elif line.startswith("data: "):
                    events.append((name, json.loads(line[6:])))
                    if name == "progress":
                        queue.finish(job_id)
                    if name == "end":
                        break
        assert events[0][0] == "progress" and events[0][1]["state"] == "queued"
        assert events[-1][0] == "end" and events[-1][1]["state"] == "succeeded" and events[-1][1]["result"]


@pytest.mark.parametrize(
    "accept, expected",
    [
        ("application/msgpack", MSGPACK),
        ("application/x-msgpack, application/json;q=0.5", MSGPACK),
        ("application/msgpack;q=0.1, application/json", "application/json"),
        ("text/html, */*;q=0.8", "application/json"),
        ("", "application/json"),
    ],
)
def test_accept_negotiation(client: TestClient, accept: str, expected: str) -> None:
    assert client.get("/healthz", headers={"Accept": accept}).headers["content-type"] == expected


def test_robot_body_is_size_capped() -> None:
    urdf = '<robot name="r"><link name="tip"/>' + "<!-- padding -->" * 200 + "</robot>"
    with make_client(max_robot_bytes=2048) as client:
        response = client.post("/v1/robots", json={"name": "big_hand", "urdf": urdf, "fingertips": ["tip"]})
        assert "2048" in assert_error(response, 413, "PayloadTooLarge").error
