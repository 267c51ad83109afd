"""Every RPC against a real server: synthesis, jobs, watching, cancellation, deadlines, batches, hands."""

from __future__ import annotations

import time

import grpc
import httpx
import numpy as np
import pytest

from manifoundation.contract import JobPublic, SynthesisResult
from manifoundation.contract.protos.convert import from_proto
from manifoundation.contract.protos.v1 import manifoundation_pb2 as pb
from manifoundation.server.spool import payload_files

from .conftest import HAND, KEY, OTHER, Service, metrics_text, request, wait_terminal


def test_synthesize(service: Service) -> None:
    result, call = service.stub.Synthesize.with_call(request(), metadata=service.auth(), timeout=30)
    answer = from_proto(result, SynthesisResult, answer=True)
    assert answer.hand == HAND and answer.model_version == "staged-test" and "refinement" in answer.timings
    job_id = dict(call.initial_metadata())["x-job-id"]
    job = from_proto(service.stub.GetJob(pb.GetJobRequest(id=job_id), metadata=service.auth()), JobPublic, answer=True)
    assert job.state == "succeeded" and job.result is not None and job.worker and job.deadline is not None


def test_a_200000_point_cloud_passes(service: Service) -> None:
    message = request(n=200_000)
    assert message.ByteSize() > 4 * 1024 * 1024  # over gRPC's default 4 MiB limit
    result = service.stub.Synthesize(message, metadata=service.auth(), timeout=60)
    assert result.hand == HAND


def test_submit_watch_get(service: Service) -> None:
    created = service.stub.SubmitJob(request(max_iterations=4), metadata=service.auth())
    assert created.state == "queued"
    updates = list(service.stub.WatchJob(pb.WatchJobRequest(id=created.id), metadata=service.auth(), timeout=30))
    stages = [u.progress.stage for u in updates[:-1]]
    assert "refinement" in stages and all(not u.HasField("result") for u in updates[:-1])
    last = updates[-1]
    assert last.state == "succeeded" and last.result.hand == HAND
    assert service.stub.GetJob(pb.GetJobRequest(id=created.id, without_result=True), metadata=service.auth()).state
    job = service.stub.GetJob(pb.GetJobRequest(id=created.id, without_result=True), metadata=service.auth())
    assert job.state == "succeeded" and not job.HasField("result")


def test_cancel_job(service: Service) -> None:
    created = service.stub.SubmitJob(request(max_iterations=20), metadata=service.auth())
    cancelled = service.stub.CancelJob(pb.JobRef(id=created.id), metadata=service.auth())
    assert cancelled.id == created.id
    job = wait_terminal(service, created.id)
    assert job.state == "cancelled" and job.error.type == "Cancelled"


def _newest_running_job(service: Service) -> str:
    """The id of the newest job once it runs (found over HTTP: a unary call's client sees no metadata before the
    answer)."""
    end = time.monotonic() + 10
    while True:
        jobs = httpx.get(f"{service.base}/v1/jobs?limit=1", headers={"Authorization": f"Bearer {KEY}"}).json()["jobs"]
        if jobs and jobs[0]["state"] == "running":
            return str(jobs[0]["id"])
        assert time.monotonic() < end, jobs
        time.sleep(0.02)


def test_a_client_that_cancels_cancels_its_job(service: Service) -> None:
    call = service.stub.Synthesize.future(request(max_iterations=20), metadata=service.auth(), timeout=30)
    job_id = _newest_running_job(service)
    call.cancel()
    assert call.code() is grpc.StatusCode.CANCELLED
    job = wait_terminal(service, job_id)
    assert job.state == "cancelled", job
    assert job.progress.iteration < 20  # the worker stopped working on it


def test_the_call_deadline_is_the_jobs_deadline(service: Service) -> None:
    started = time.time()
    call = service.stub.Synthesize.future(request(max_iterations=20), metadata=service.auth(), timeout=0.6)
    job_id = _newest_running_job(service)
    assert call.exception(timeout=10).code() is grpc.StatusCode.DEADLINE_EXCEEDED
    job = wait_terminal(service, job_id)
    assert job.state == "expired" and job.error.type == "DeadlineExceeded", job
    assert job.deadline == pytest.approx(started + 0.6, abs=0.3)
    assert job.progress.iteration < 20


def test_watch_can_cancel_on_disconnect(service: Service) -> None:
    # 200 iterations (≈ 10 s): long enough that a loaded machine cannot finish the job before the cancel lands
    created = service.stub.SubmitJob(request(max_iterations=200), metadata=service.auth())
    stream = service.stub.WatchJob(
        pb.WatchJobRequest(id=created.id, cancel_on_disconnect=True), metadata=service.auth()
    )
    next(stream)
    stream.cancel()
    assert wait_terminal(service, created.id).state == "cancelled"


def test_batch_submit_watch_and_pages(service: Service) -> None:
    batch = service.stub.SubmitBatch(
        pb.BatchCreate(requests=[request(seed=s) for s in range(3)]), metadata=service.auth()
    )
    assert batch.total == 3 and batch.counts["queued"] == 3 and [i.index for i in batch.items] == [0, 1, 2]
    items = list(service.stub.WatchBatch(pb.BatchRef(id=batch.id), metadata=service.auth(), timeout=30))
    assert sorted(i.index for i in items) == [0, 1, 2]
    assert all(i.state == "succeeded" and i.result.hand == HAND for i in items)
    page = service.stub.GetBatch(pb.GetBatchRequest(id=batch.id, offset=1, limit=1), metadata=service.auth())
    assert page.done and page.total == 3 and page.counts["succeeded"] == 3
    assert [(i.index, i.job_id) for i in page.items] == [(1, batch.items[1].job_id)]


def test_robots(service: Service) -> None:
    robots = service.stub.ListRobots(pb.ListRobotsRequest(), metadata=service.auth())
    assert HAND in [r.name for r in robots.robots]
    urdf = '<robot name="r"><link name="base"/><link name="tip"/></robot>'
    mine = service.stub.RegisterRobot(pb.RobotRegister(name="grpc_hand", urdf=urdf, fingertips=["tip"]),
                                      metadata=service.auth())  # fmt: skip
    assert mine.name == "grpc_hand" and not mine.builtin and list(mine.fingertips) == ["tip"]
    names = [r.name for r in service.stub.ListRobots(pb.ListRobotsRequest(), metadata=service.auth()).robots]
    others = [r.name for r in service.stub.ListRobots(pb.ListRobotsRequest(), metadata=service.auth(OTHER)).robots]
    assert "grpc_hand" in names and "grpc_hand" not in others  # per-key namespaces, as over HTTP


def test_a_large_robot_and_a_large_synthesis_go_through_the_body_pool(service: Service) -> None:
    """`RegisterRobot` and `Synthesize` messages over MANI_PARSE_OFFLOAD_BYTES are decoded in the large-body
    processes too (`LargeMessage`): the same answers as small ones; a synthesis's timeout read from the decoded
    request."""
    padding = "<!--" + "x" * 1_200_000 + "-->"  # 1.2 MB: over the 1 MiB offload threshold
    urdf = f'<robot name="r">{padding}<link name="base"/><link name="tip"/></robot>'
    mine = service.stub.RegisterRobot(pb.RobotRegister(name="grpc_large_hand", urdf=urdf, fingertips=["tip"]),
                                      metadata=service.auth(), timeout=60)  # fmt: skip
    assert mine.name == "grpc_large_hand" and mine.stored_bytes >= len(urdf)
    message = request(n=100_000, timeout=30)
    assert message.ByteSize() > 1024 * 1024
    result, call = service.stub.Synthesize.with_call(message, metadata=service.auth(), timeout=60)
    assert result.hand == HAND
    job_id = dict(call.trailing_metadata())["x-job-id"]
    job = service.stub.GetJob(pb.GetJobRequest(id=job_id), metadata=service.auth())
    assert job.state == "succeeded" and job.deadline - job.created_at == pytest.approx(30, abs=1)


def test_tips_offsets_travel_as_typed_arrays(service: Service) -> None:
    message = request()
    message.robot.tip_offsets.CopyFrom(pb.Array(dtype="float32", shape=[1, 3], data=np.zeros(3, "<f4").tobytes()))
    with pytest.raises(grpc.RpcError) as caught:  # a named hand takes no offsets: the contract says so
        service.stub.SubmitJob(message, metadata=service.auth())
    assert caught.value.code() is grpc.StatusCode.INVALID_ARGUMENT and "fingertips" in caught.value.details()


def test_grpc_calls_are_counted(service: Service) -> None:
    service.stub.ListRobots(pb.ListRobotsRequest(), metadata=service.auth())
    text = metrics_text(service)
    assert 'mani_grpc_requests_total{code="OK",method="ListRobots"}' in text
    assert "mani_grpc_request_duration_seconds_bucket" in text


def test_large_messages_are_decoded_in_a_body_process_and_their_memory_given_back(service: Service) -> None:
    """A message over MANI_PARSE_OFFLOAD_BYTES reaches the servicer unparsed and is decoded by the large-body pool
    HTTP uses (its slots, its processes), not on the event loop or a thread of the API; a batch's requests are
    packed there into the embedded queue's spool (the API never holds their arrays), their files removed once
    their jobs end, and the memory of the payloads sent to the workers is given back to the OS (issue 62, item 3:
    3 × 57.6 MB batches left the API at 515-578 MB)."""
    from manifoundation.server.api.bodies import SPOOL_BATCH

    services = service.app.state.services
    bodies, queue = services.bodies, services.queue
    seen: list[str] = []
    run = bodies.run

    async def counting(decoder, chunks, *args):  # type: ignore[no-untyped-def]
        seen.append(decoder)
        return await run(decoder, chunks, *args)

    bodies.run = counting
    trims = queue._freed.trims
    try:
        big = request(n=200_000, max_iterations=1)
        batch = pb.BatchCreate(requests=[big] * 4)  # 38 MB
        created = service.stub.SubmitBatch(batch, metadata=service.auth(), timeout=60)
        assert created.total == 4
        broken = pb.BatchCreate(requests=[big] * 2)
        broken.requests[1].object.normals.data = broken.requests[1].object.normals.data[:-1]
        with pytest.raises(grpc.RpcError) as caught:
            service.stub.SubmitBatch(broken, metadata=service.auth(), timeout=60)
        assert caught.value.code() is grpc.StatusCode.INVALID_ARGUMENT, caught.value
        assert "requests.1.object.normals" in caught.value.details()  # type: ignore[attr-defined]
        small = service.stub.SubmitBatch(pb.BatchCreate(requests=[request()]), metadata=service.auth(), timeout=30)
        page = service.stub.GetBatch(pb.GetBatchRequest(id=created.id), metadata=service.auth())
        for item in [*page.items, *small.items]:
            assert wait_terminal(service, item.job_id, 60).state == "succeeded"
    finally:
        bodies.run = run
    assert seen == [SPOOL_BATCH] * 2  # the small batch was parsed at once, as before
    assert payload_files(queue.spool) == []  # every payload's file went with its job (the broken batch wrote none)
    end = time.monotonic() + 10
    while queue._freed.trims == trims and time.monotonic() < end:
        time.sleep(0.1)
    assert queue._freed.trims > trims, "4 × 9.6 MB payloads freed and the heap never trimmed"
