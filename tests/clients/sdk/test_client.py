"""`Client` through an injected transport serving real encoded contract bodies (see conftest's FakeService)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import httpx
import numpy as np
import pytest

from clients.codec import JSON, MSGPACK, decode_body
from clients.schemas import JobState, SynthesisRequest
from clients.sdk import (
    Client,
    JobFailed,
    NotFound,
    RateLimited,
    RetryPolicy,
    ServerError,
    TimeoutError,
    Unauthorized,
    Unreachable,
    ValidationError,
    delta_pose,
    make_request,
)

MakeClient = Callable[..., Client]


@pytest.mark.parametrize("encoding", ["msgpack", "json"])
def test_synthesize_returns_numpy_result(make_client: MakeClient, fake: Any, object_points: np.ndarray,
                                         encoding: str) -> None:  # fmt: skip
    client = make_client(encoding=encoding)
    result = client.synthesize(object_points, delta_pose([0, 0, 0.05]), "leap", method="direct_grasp", seed=3)
    best = result.best
    assert best is not None and isinstance(best.contact_points, np.ndarray) and best.contact_points.shape == (4, 3)
    sent = fake.seen[-1]
    media = MSGPACK if encoding == "msgpack" else JSON
    assert sent.headers["content-type"] == media and sent.headers["accept"] == media
    body = SynthesisRequest.model_validate(decode_body(sent.content, media))
    assert body.options.seed == 3 and body.options.method == "direct_grasp"
    assert body.object.points.shape == (256, 3) and body.task.kind == "delta_pose"
    assert sent.extensions["timeout"]["read"] >= body.options.timeout  # the HTTP read outlasts the server wait


def test_synthesize_follows_a_202_to_the_result(make_client: MakeClient, fake: Any, object_points: np.ndarray,
                                                sleeps: list[float]) -> None:  # fmt: skip
    fake.sync_finishes, fake.polls_to_finish = False, 3
    result = make_client().synthesize(object_points, "force_closure", "allegro")
    assert result.hand == "allegro"
    assert [r.url.path for r in fake.seen][1:] == ["/v1/jobs/job-0"] * 4
    assert len(sleeps) == 3


def test_synthesize_times_out_with_the_job_id(make_client: MakeClient, fake: Any, object_points: np.ndarray) -> None:
    fake.sync_finishes, fake.polls_to_finish = False, 10**6
    with pytest.raises(TimeoutError) as info:
        make_client(sleep=lambda s: None).synthesize(object_points, timeout=0.05)
    assert info.value.job_id == "job-0"


def test_invalid_input_is_refused_before_sending(make_client: MakeClient, fake: Any) -> None:
    points = np.zeros((10, 3))
    with pytest.raises(ValidationError) as info:
        make_client().synthesize(points)
    assert info.value.status_code is None and info.value.detail[0].field == "object.points"
    with pytest.raises(ValidationError, match="seed"):
        make_client().synthesize(np.random.default_rng(0).normal(size=(100, 3)), seed=-1)
    assert fake.seen == []


def test_service_errors_carry_field_and_status(make_client: MakeClient, fake: Any) -> None:
    body = {"error": "object.normals: zero-length normal at index 3", "type": "ValidationError",
            "detail": [{"field": "object.normals", "problem": "zero-length normal at index 3"}]}  # fmt: skip
    fake.script.append(httpx.Response(422, json=body))
    with pytest.raises(ValidationError) as info:
        make_client().robots()
    assert info.value.status_code == 422 and info.value.detail[0].field == "object.normals"
    with pytest.raises(NotFound) as missing:
        make_client().robot("nope")
    assert missing.value.detail[0].field == "robot.name"


def test_retries_429_and_503_honouring_retry_after(make_client: MakeClient, fake: Any, sleeps: list[float],
                                                   object_points: np.ndarray) -> None:  # fmt: skip
    fake.script += [
        httpx.Response(429, json={"error": "queue full", "type": "QueueFull"}, headers={"Retry-After": "2"}),
        httpx.Response(503, json={"error": "restarting", "type": "Unavailable"}),
    ]
    client = make_client(retries=RetryPolicy(max_retries=3, backoff=0.01, jitter=0.0))
    assert client.synthesize(object_points).hand == "leap"
    assert sleeps == [2.0, 0.02]


def test_gives_up_after_the_retries(make_client: MakeClient, fake: Any, sleeps: list[float]) -> None:
    body = {"error": "slow down", "type": "RateLimited"}
    fake.script += [httpx.Response(429, json=body, headers={"Retry-After": "1"}) for _ in range(3)]
    with pytest.raises(RateLimited) as info:
        make_client(retries=2).robots()
    assert info.value.retry_after == 1.0 and len(sleeps) == 2


def test_connection_errors_become_unreachable(make_client: MakeClient, fake: Any, sleeps: list[float]) -> None:
    fake.script += [httpx.ConnectError("refused")] * 4
    with pytest.raises(Unreachable, match="cannot reach"):
        make_client(retries=3).health()
    assert len(sleeps) == 3
    fake.script[:] = [httpx.ConnectError("refused")]
    assert make_client(retries=3).health() == {"status": "ok"}  # recovered on the retry


def test_unreadable_answer_is_a_server_error(make_client: MakeClient, fake: Any) -> None:
    fake.script.append(httpx.Response(200, content=b"\xc1garbage", headers={"content-type": MSGPACK}))
    with pytest.raises(ServerError, match="unreadable"):
        make_client().robot("leap")


def test_api_key_is_sent(make_client: MakeClient, fake: Any) -> None:
    fake.api_key = "s3cret"
    with pytest.raises(Unauthorized):
        make_client().robots()
    assert make_client(api_key="s3cret").robots() == []


def test_job_status_wait_cancel_and_events(make_client: MakeClient, fake: Any, object_points: np.ndarray) -> None:
    fake.polls_to_finish = 2
    client = make_client()
    job = client.submit(object_points, method="direct_grasp")
    assert job.id == "job-0"
    assert job.status().state is JobState.RUNNING
    events = list(job.events())
    assert [e.state for e in events] == [JobState.RUNNING, JobState.SUCCEEDED]
    assert events[-1].result is not None
    assert job.wait().hand == "leap"

    other = client.submit(object_points)
    assert other.cancel().state is JobState.CANCELLED
    with pytest.raises(JobFailed) as info:
        other.wait()
    assert info.value.state is JobState.CANCELLED and info.value.job_id == other.id


@pytest.mark.parametrize("sync", [True, False])
def test_failed_job_carries_its_error(
    make_client: MakeClient, fake: Any, object_points: np.ndarray, sync: bool
) -> None:
    fake.fail, fake.sync_finishes = True, sync  # sync: an error answer with X-Job-ID; else 202, then polling
    with pytest.raises(JobFailed) as info:
        make_client().synthesize(object_points)
    assert info.value.error is not None and info.value.error.type == "InternalError"
    assert info.value.state is JobState.FAILED and info.value.job_id == "job-0"
    assert "InternalError" in str(info.value)


def test_job_wait_timeout(make_client: MakeClient, fake: Any, object_points: np.ndarray) -> None:
    fake.polls_to_finish = 10**6
    job = make_client(sleep=lambda s: None).submit(object_points)
    with pytest.raises(TimeoutError):
        job.wait(timeout=0.02)


def test_batch_results_in_request_order_across_pages(make_client: MakeClient, fake: Any,
                                                     object_points: np.ndarray) -> None:  # fmt: skip
    fake.polls_to_finish = 1
    requests = [make_request(object_points, "force_closure", "leap", seed=i) for i in range(7)]
    batch = make_client().submit_batch(requests)
    batch.page_size = 3
    seen: list[int] = []
    items = batch.wait(progress=lambda item: seen.append(item.index))
    assert [i.index for i in items] == list(range(7))
    assert sorted(seen) == list(range(7))
    assert all(i.state is JobState.SUCCEEDED and i.result is not None for i in items)
    offsets = [r.url.params.get("offset") for r in fake.seen if r.url.path.startswith("/v1/batches/")]
    assert set(offsets) == {"0", "3", "6"}
    again = make_client().batch(batch.id)
    assert again.total == 7 and len(again.results()) == 7


def test_batch_failures_and_as_completed(make_client: MakeClient, fake: Any, object_points: np.ndarray) -> None:
    fake.fail = True
    batch = make_client().submit_batch([make_request(object_points) for _ in range(3)])
    items = list(batch.as_completed())
    assert {i.state for i in items} == {JobState.FAILED}
    with pytest.raises(JobFailed):
        batch.results()


def test_batch_too_large_is_refused_locally(make_client: MakeClient, object_points: np.ndarray) -> None:
    request = make_request(object_points)
    with pytest.raises(ValidationError, match="requests"):
        make_client().submit_batch([request] * 1001)


def test_robots_register_health_ready(make_client: MakeClient, fake: Any, tmp_path: Any) -> None:
    client = make_client()
    urdf = tmp_path / "My Gripper.urdf"
    urdf.write_text('<?xml version="1.0"?><robot name="g"><link name="base"/></robot>')
    robot = client.register_robot(urdf, ["tip_a", "tip_b"], tip_offsets=[[0, 0, 0.01], [0, 0, 0.01]])
    assert robot.name == "my-gripper" and robot.fingertips == ["tip_a", "tip_b"]
    assert [r.name for r in client.robots()] == ["my-gripper"]
    assert client.robot("my-gripper").dof == 2
    assert client.health() == {"status": "ok"}
    assert client.ready().ready


def test_not_ready_is_an_answer_not_a_retry(make_client: MakeClient, fake: Any, sleeps: list[float]) -> None:
    body = {"ready": False, "queue": True, "workers": 0, "model_loaded": False, "detail": "no live worker"}
    fake.script.append(httpx.Response(503, json=body, headers={"Retry-After": "5"}))
    ready = make_client().ready()
    assert not ready.ready and ready.detail == "no live worker" and sleeps == []
