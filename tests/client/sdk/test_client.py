"""`Client` against the real service app in process (conftest's ``service``; ``script`` for transport faults)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import httpx
import numpy as np
import pytest

from manifoundation.contract import ErrorType, JobState
from manifoundation.contract.codec import JSON, MSGPACK
from manifoundation.sdk import (
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
from tests.client.sdk.inprocess import InProcessService
from tests.client.sdk.queues import FAILURE, FOREVER, HAND

MakeClient = Callable[..., Client]


@pytest.mark.parametrize("encoding", ["msgpack", "json"])
def test_synthesize_returns_numpy_result(make_client: MakeClient, service: InProcessService,
                                         object_points: np.ndarray, encoding: str) -> None:  # fmt: skip
    client = make_client(encoding=encoding)
    result = client.synthesize(object_points, delta_pose([0, 0, 0.05]), HAND, method="direct_grasp", seed=3)
    best = result.best
    assert result.hand == HAND and best is not None and isinstance(best.contact_points, np.ndarray)
    assert np.allclose(best.contact_points, object_points[[0, 128], :3])  # the fake's contacts: input points
    sent = service.seen[-1]
    media = MSGPACK if encoding == "msgpack" else JSON
    assert sent.headers["content-type"] == media and sent.headers["accept"] == media
    (job_id,) = service.queue.job_ids()
    body = service.queue.requests[job_id]  # as the app decoded it
    assert body.options.seed == 3 and body.options.method == "direct_grasp"
    assert body.object.points.shape == (256, 3) and body.task.kind == "delta_pose"
    assert np.allclose(body.object.points, object_points[:, :3])
    assert sent.extensions["timeout"]["read"] >= body.options.timeout  # the HTTP read outlasts the server wait


def test_synthesize_follows_a_202_to_the_result(make_client: MakeClient, service: InProcessService,
                                                object_points: np.ndarray, sleeps: list[float]) -> None:  # fmt: skip
    service.queue.running_reads = 3  # outlives the synchronous wait: 202, then three polls answer running
    result = make_client().synthesize(object_points, "force_closure", HAND)
    assert result.hand == HAND
    (job_id,) = service.queue.job_ids()
    assert [r.url.path for r in service.seen] == ["/v1/synthesize"] + [f"/v1/jobs/{job_id}"] * 4
    assert len(sleeps) == 3


def test_synthesize_times_out_with_the_job_id(make_client: MakeClient, service: InProcessService,
                                              object_points: np.ndarray) -> None:  # fmt: skip
    service.queue.running_reads = FOREVER
    with pytest.raises(TimeoutError) as info:
        make_client(sleep=lambda s: None).synthesize(object_points, robot=HAND, timeout=0.05)
    assert info.value.job_id == service.queue.job_ids()[0]


def test_invalid_input_is_refused_before_sending(make_client: MakeClient, service: InProcessService) -> None:
    points = np.zeros((10, 3))
    with pytest.raises(ValidationError) as info:
        make_client().synthesize(points)
    assert info.value.status_code is None and info.value.detail[0].field == "object.points"
    with pytest.raises(ValidationError, match="seed"):
        make_client().synthesize(np.random.default_rng(0).normal(size=(100, 3)), seed=-1)
    assert service.seen == []


def test_service_errors_carry_field_and_status(make_client: MakeClient, service: InProcessService,
                                               object_points: np.ndarray) -> None:  # fmt: skip
    body = {"error": "object.normals: zero-length normal at index 3", "type": "ValidationError",
            "detail": [{"field": "object.normals", "problem": "zero-length normal at index 3"}]}  # fmt: skip
    service.script.append(httpx.Response(422, json=body))  # what the SDK's own checks never let through
    with pytest.raises(ValidationError) as info:
        make_client().robots()
    assert info.value.status_code == 422 and info.value.detail[0].field == "object.normals"
    with pytest.raises(NotFound) as missing:
        make_client().robot("nope")
    assert missing.value.status_code == 404 and missing.value.detail[0].field == "name"
    with pytest.raises(NotFound) as unknown:
        make_client().synthesize(object_points, robot="nope")
    assert unknown.value.detail[0].field == "robot.name" and "nope" in unknown.value.message
    with pytest.raises(ValidationError) as refused:  # the queue's URDF check: a 422 the app answers
        make_client().register_robot("<link name='a'/>", ["a"], name="no-robot")
    assert refused.value.status_code == 422 and "URDF" in refused.value.message
    assert service.queue.job_ids() == []


def test_retries_429_and_503_honouring_retry_after(make_client: MakeClient, service: InProcessService,
                                                   sleeps: list[float], object_points: np.ndarray) -> None:  # fmt: skip
    service.script += [
        httpx.Response(429, json={"error": "queue full", "type": "QueueFull"}, headers={"Retry-After": "2"}),
        httpx.Response(503, json={"error": "restarting", "type": "Unavailable"}),
    ]
    client = make_client(retries=RetryPolicy(max_retries=3, backoff=0.01, jitter=0.0))
    assert client.synthesize(object_points, robot=HAND).hand == HAND
    assert sleeps == [2.0, 0.02]
    assert len(service.queue.job_ids()) == 1  # the answers that were retried submitted nothing


def test_gives_up_after_the_retries(make_client: MakeClient, service: InProcessService, sleeps: list[float],
                                    object_points: np.ndarray) -> None:  # fmt: skip
    service.queue.full = True  # the app answers 429 QueueFull with Retry-After (the fake queue's 2.5 s: "3")
    with pytest.raises(RateLimited) as info:
        make_client(retries=2).submit(object_points, robot=HAND)
    assert info.value.type == ErrorType.QUEUE_FULL and info.value.retry_after == 3.0
    assert sleeps == [3.0, 3.0] and [r.url.path for r in service.seen] == ["/v1/jobs"] * 3


def test_connection_errors_become_unreachable(make_client: MakeClient, service: InProcessService,
                                              sleeps: list[float]) -> None:  # fmt: skip
    service.script += [httpx.ConnectError("refused")] * 4
    with pytest.raises(Unreachable, match="cannot reach"):
        make_client(retries=3).health()
    assert len(sleeps) == 3
    service.script[:] = [httpx.ConnectError("refused")]
    assert make_client(retries=3).health().status == "ok"  # recovered on the retry


def test_unreadable_answer_is_a_server_error(make_client: MakeClient, service: InProcessService) -> None:
    service.script.append(httpx.Response(200, content=b"\xc1garbage", headers={"content-type": MSGPACK}))
    with pytest.raises(ServerError, match="unreadable"):
        make_client().robot(HAND)


def test_api_key_is_sent(make_client: MakeClient, service: InProcessService) -> None:
    service.configure(api_keys=["s3cret-key"])
    with pytest.raises(Unauthorized):
        make_client().robots()
    with pytest.raises(Unauthorized):
        make_client(api_key="wrong-key").robots()
    assert [r.name for r in make_client(api_key="s3cret-key").robots()] == [HAND]


def test_job_status_wait_cancel_and_events(make_client: MakeClient, service: InProcessService,
                                           object_points: np.ndarray) -> None:  # fmt: skip
    service.queue.running_reads = 4
    client = make_client()
    job = client.submit(object_points, robot=HAND, method="direct_grasp")
    assert service.queue.job_ids() == [job.id]
    assert job.status().state is JobState.RUNNING
    events = list(job.events())
    assert [e.state for e in events] == [JobState.RUNNING, JobState.SUCCEEDED]
    assert events[0].result is None and events[-1].result is not None
    assert job.wait().hand == HAND

    other = client.submit(object_points, robot=HAND)
    assert other.cancel().state is JobState.CANCELLED
    with pytest.raises(JobFailed) as info:
        other.wait()
    assert info.value.state is JobState.CANCELLED and info.value.job_id == other.id


@pytest.mark.parametrize("sync", [True, False])
def test_failed_job_carries_its_error(make_client: MakeClient, service: InProcessService,
                                      object_points: np.ndarray, sync: bool) -> None:  # fmt: skip
    service.queue.error = FAILURE
    if not sync:  # else: the app answers the job's error (500) with X-Job-ID; here 202, then polling
        service.queue.running_reads = 0
    with pytest.raises(JobFailed) as info:
        make_client().synthesize(object_points, robot=HAND)
    assert info.value.error is not None and info.value.error.type == "InternalError"
    assert info.value.state is JobState.FAILED and info.value.job_id == service.queue.job_ids()[0]
    assert "InternalError" in str(info.value) and "refinement diverged" in str(info.value)
    assert len(service.seen) == (1 if sync else 2)


def test_job_wait_timeout(make_client: MakeClient, service: InProcessService, object_points: np.ndarray) -> None:
    service.queue.running_reads = FOREVER
    job = make_client(sleep=lambda s: None).submit(object_points, robot=HAND)
    with pytest.raises(TimeoutError):
        job.wait(timeout=0.02)


def test_batch_results_in_request_order_across_pages(make_client: MakeClient, service: InProcessService,
                                                     object_points: np.ndarray) -> None:  # fmt: skip
    service.queue.running_reads = 1
    requests = [make_request(object_points, "force_closure", HAND, seed=i) for i in range(7)]
    batch = make_client().submit_batch(requests)
    batch.page_size = 3
    seen: list[int] = []
    items = batch.wait(progress=lambda item: seen.append(item.index))
    assert [i.index for i in items] == list(range(7))
    assert sorted(seen) == list(range(7))
    assert all(i.state is JobState.SUCCEEDED and i.result is not None for i in items)
    job_ids = service.queue.batches[batch.id]
    assert [i.job_id for i in items] == job_ids
    assert [service.queue.requests[j].options.seed for j in job_ids] == list(range(7))
    offsets = [r.url.params.get("offset") for r in service.seen if r.url.path.startswith("/v1/batches/")]
    assert set(offsets) == {"0", "3", "6"}
    again = make_client().batch(batch.id)
    assert again.total == 7 and len(again.results()) == 7


def test_batch_failures_and_as_completed(make_client: MakeClient, service: InProcessService,
                                         object_points: np.ndarray) -> None:  # fmt: skip
    service.queue.error = FAILURE
    batch = make_client().submit_batch([make_request(object_points, robot=HAND) for _ in range(3)])
    items = list(batch.as_completed())
    assert {i.state for i in items} == {JobState.FAILED}
    with pytest.raises(JobFailed):
        batch.results()


def test_batch_too_large_is_refused_locally(make_client: MakeClient, service: InProcessService,
                                            object_points: np.ndarray) -> None:  # fmt: skip
    request = make_request(object_points)
    with pytest.raises(ValidationError, match="requests"):
        make_client().submit_batch([request] * 1001)
    assert service.seen == []


def test_robots_register_health_ready(make_client: MakeClient, tmp_path: Path) -> None:
    client = make_client()
    urdf = tmp_path / "My Gripper.urdf"
    urdf.write_text('<?xml version="1.0"?><robot name="g"><link name="base"/></robot>')
    robot = client.register_robot(urdf, ["tip_a", "tip_b"], tip_offsets=[[0, 0, 0.01], [0, 0, 0.01]])
    assert robot.name == "my-gripper" and robot.fingertips == ["tip_a", "tip_b"] and not robot.builtin
    assert [r.name for r in client.robots()] == [HAND, "my-gripper"]
    assert client.robot("my-gripper") == robot
    health = client.health()
    assert health.status == "ok" and health.backend == "fake"
    assert client.ready().ready


def test_not_ready_is_an_answer_not_a_retry(make_client: MakeClient, service: InProcessService,
                                            sleeps: list[float]) -> None:  # fmt: skip
    service.queue.down = True  # the app answers 503 with Retry-After and the readiness body
    ready = make_client().ready()
    assert not ready.ready and not ready.queue and ready.detail == "queue does not answer" and sleeps == []
    assert len(service.seen) == 1
