"""`GrpcClient` against the real gRPC server (the app's gRPC port on a free port, embedded workers running the
staged test pipeline: ``tests/api/grpc/conftest.py``): the HTTP SDK's results and exceptions, deadlines,
retries, and the version handshake."""

from __future__ import annotations

import contextlib
import time
import warnings
from collections.abc import Iterator
from typing import Any

import numpy as np
import pytest

from manifoundation.contract import JobState, SynthesisRequest, SynthesisResult
from manifoundation.contract.protos.v1 import manifoundation_pb2 as pb
from manifoundation.contract.versions import CONTRACT_HEADER, CONTRACT_VERSION, parse_version
from manifoundation.sdk import (
    ContractWarning,
    IncompatibleService,
    JobFailed,
    NeedsHttp,
    NotFound,
    RateLimited,
    TimeoutError,
    Unauthorized,
    Unreachable,
    ValidationError,
)
from manifoundation.sdk.grpc_client import GrpcClient
from manifoundation.server.api.versions import Versions
from tests.api.grpc.conftest import FAIL_SEED, HAND, KEY, OTHER, Service, calls_ok, running
from tests.api.helpers import request_body
from tests.api.server import free_port

MAJOR, MINOR = parse_version(CONTRACT_VERSION)


@pytest.fixture(scope="module")
def service(request: pytest.FixtureRequest) -> Iterator[Service]:
    with running(request) as svc:
        yield svc


@pytest.fixture
def client(service: Service) -> Iterator[GrpcClient]:
    with GrpcClient(service.target, KEY) as made:
        yield made


@contextlib.contextmanager
def reporting(service: Service, versions: Versions) -> Iterator[None]:
    """The service reports ``versions`` meanwhile."""
    service.app.state.services.versions = versions
    try:
        yield
    finally:
        service.app.state.services.versions = Versions()


def synthesis(hand: str = HAND, **options: Any) -> SynthesisRequest:
    return SynthesisRequest.model_validate(request_body(hand, 128, **{"max_iterations": 2, **options}))


def test_synthesize_returns_the_contracts_result(client: GrpcClient) -> None:
    result = client.synthesize(synthesis())  # the staged pipeline answers no proposals, its stages' timings
    assert isinstance(result, SynthesisResult) and result.hand == HAND and result.model_version == "staged-test"
    assert {"network", "refinement"} <= result.timings.keys()
    assert client.versions.service_contract == CONTRACT_VERSION  # the handshake ran on the first answer
    assert [r.name for r in client.robots()] == [HAND]


def test_submit_watch_get_and_wait(client: GrpcClient) -> None:
    job = client.submit(synthesis(max_iterations=4))
    updates = list(job.events(timeout=30))
    assert updates[-1].state is JobState.SUCCEEDED and updates[-1].result is not None
    assert "refinement" in {u.progress.stage for u in updates[:-1]}
    assert job.wait(timeout=30).hand == HAND
    with pytest.warns(DeprecationWarning, match=r"job\(id\)\.status\(\)"):  # the old name, for one release
        without = client.get(job.id, with_result=False)
    assert without.state is JobState.SUCCEEDED and without.result is None


def test_cancel(client: GrpcClient) -> None:
    job = client.submit(synthesis(max_iterations=20))
    assert job.cancel().id == job.id
    with pytest.raises(JobFailed) as caught:
        job.wait(timeout=20)
    assert caught.value.state is JobState.CANCELLED and caught.value.job_id == job.id


def test_errors_are_the_http_sdks(service: Service, client: GrpcClient) -> None:
    with pytest.raises(NotFound) as missing:
        client.job("no-such-job").status()
    assert missing.value.type == "NotFound" and missing.value.status_code is None
    with pytest.raises(NotFound, match="no_such_hand"):
        client.synthesize(synthesis("no_such_hand"))  # the service's UnknownHand
    with pytest.raises(ValidationError) as local:  # checked before sending, as by `Client`
        client.synthesize(np.zeros((10, 3)))
    assert local.value.detail[0].field == "object.points"
    unchecked = synthesis()
    unchecked.options.num_proposals = 0  # past the SDK's own check: the service's validation answers
    with pytest.raises(ValidationError) as invalid:
        client.synthesize(unchecked)
    assert invalid.value.type == "ValidationError" and invalid.value.detail[0].field == "options.num_proposals"
    with pytest.raises(JobFailed) as failed:
        client.synthesize(synthesis(seed=FAIL_SEED))
    assert failed.value.state is JobState.FAILED and failed.value.job_id
    with GrpcClient(service.target) as anonymous, pytest.raises(Unauthorized):
        anonymous.robots()
    with GrpcClient(f"127.0.0.1:{free_port()}", retries=0) as nobody, pytest.raises(Unreachable):
        nobody.robots()


def test_the_timeout_is_the_calls_and_the_jobs_deadline(client: GrpcClient) -> None:
    started = time.monotonic()
    with pytest.raises(TimeoutError) as caught:
        client.synthesize(synthesis(max_iterations=20, timeout=0.4))  # about 1.2 s of work
    assert time.monotonic() - started < 1.0 and caught.value.job_id
    end = time.monotonic() + 10
    while (job := client.job(caught.value.job_id).status()).state is not JobState.EXPIRED and time.monotonic() < end:
        time.sleep(0.05)
    assert job.state is JobState.EXPIRED


def test_a_full_queue_is_retried_then_rate_limited(service: Service) -> None:
    sleeps: list[float] = []
    submitted = []
    with GrpcClient(service.target, KEY, retries=2, sleep=sleeps.append) as client:
        try:
            with pytest.raises(RateLimited) as caught:
                for _ in range(20):  # max_queue is 8
                    submitted.append(client.submit(synthesis(max_iterations=20)))
        finally:
            for job in submitted:
                job.cancel()
    assert caught.value.type == "QueueFull" and caught.value.retry_after == 1.0
    assert len(sleeps) == 2 and all(s >= 1.0 for s in sleeps)  # the service's retry delay, honoured


def test_another_major_version_is_refused(service: Service, client: GrpcClient) -> None:
    with reporting(service, Versions(contract=f"{MAJOR + 1}.0")):
        _, call = service.stub.ListRobots.with_call(pb.ListRobotsRequest(), metadata=service.auth())
        assert dict(call.initial_metadata())[CONTRACT_HEADER] == f"{MAJOR + 1}.0"
        with pytest.raises(IncompatibleService, match=f"{MAJOR + 1}.0"):
            client.robots()
        with pytest.raises(IncompatibleService):  # a failed call names the version in its trailers
            client.job("no-such-job").status()


def test_a_newer_minor_version_warns_once(service: Service, client: GrpcClient) -> None:
    with reporting(service, Versions(contract=f"{MAJOR}.{MINOR + 1}")):
        with pytest.warns(ContractWarning):
            client.robots()
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            client.robots()


def test_plan_through_the_grpc_client(client: GrpcClient) -> None:
    from manifoundation.contract import PlanRequest
    from tests.api.helpers import sphere

    points, normals = sphere(128)
    request = PlanRequest.model_validate({
        "object": {"points": points, "normals": normals}, "start": {"position": [0, 0, 0.1]},
        "waypoints": [{"position": [0.05, 0, 0.1]}, {"position": [0.1, 0, 0.1]}], "robot": {"name": HAND},
    })  # fmt: skip
    plan = client.plan(request, wait=30)
    assert plan.positions.shape == (3, 3) and plan.waypoint_indices == [1, 2]
    job = client.submit_plan(request)
    assert job.status().kind == "plan" and job.plan_result(30).waypoint_indices == [1, 2]
    with pytest.raises(JobFailed):  # a plan job carries no synthesis result
        job.wait(30)


def test_batches_over_grpc(client: GrpcClient) -> None:
    batch = client.submit_batch([synthesis(seed=s) for s in range(3)] + [synthesis(seed=FAIL_SEED)])  # SubmitBatch
    assert batch.total == 4 and repr(batch) == f"Batch({batch.id!r})"
    seen = list(batch.as_completed(timeout=30))  # WatchBatch: each item as its job ends
    assert sorted(i.index for i in seen) == [0, 1, 2, 3]
    items = batch.wait(timeout=30)
    assert [i.index for i in items] == [0, 1, 2, 3] and [i.state for i in items[:3]] == [JobState.SUCCEEDED] * 3
    assert all(i.result is not None and i.result.hand == HAND for i in items[:3])
    assert items[3].state is JobState.FAILED and items[3].error is not None
    with pytest.raises(JobFailed) as failed:  # results(): the first item without one
        batch.results(timeout=30)
    assert failed.value.job_id == items[3].job_id
    page = client.batch(batch.id).status(offset=1, limit=2)  # GetBatch
    assert page.done and page.total == 4 and [i.index for i in page.items] == [1, 2]
    assert client.batch(batch.id).total == 4
    assert client.job(items[0].job_id).status().batch_id == batch.id
    slow = client.submit_batch([synthesis(max_iterations=20) for _ in range(2)])
    with pytest.raises(TimeoutError, match=f"batch {slow.id}: 0/2 done"):
        list(slow.as_completed(timeout=0.2))
    for item in slow.status().items:
        client.job(item.job_id).cancel()
    with pytest.raises(ValidationError):  # checked before sending, as by `Client`
        client.submit_batch([])


def test_robot_registration_over_grpc(service: Service, tmp_path: Any) -> None:
    urdf = '<robot name="r"><link name="base"/><link name="tip"/></robot>'
    with GrpcClient(service.target, OTHER) as other:  # another key: its own namespace, the module's key untouched
        mine = other.register_robot(urdf, ["tip"], name="sdk_grpc_hand")  # RegisterRobot
        assert mine.name == "sdk_grpc_hand" and not mine.builtin and mine.fingertips == ["tip"]
        (tmp_path / "hand.urdf").write_text(urdf)
        added = other.add_robot(tmp_path / "hand.urdf", fingertips=["tip"], name="sdk_grpc_hand_2")
        assert added.name == "sdk_grpc_hand_2" and added.fingertips == ["tip"]
        assert {"sdk_grpc_hand", "sdk_grpc_hand_2"} <= {r.name for r in other.robots()}
        found = other.robot("sdk_grpc_hand")  # from ListRobots
        assert found.name == "sdk_grpc_hand" and found.preview is None
        with pytest.raises(NotFound, match="no_such_hand") as unknown:
            other.robot("no_such_hand")
        assert unknown.value.type == "UnknownHand"
        with pytest.raises(ValidationError):  # the service's validation, as over HTTP
            other.register_robot(urdf, ["no_such_link"], name="sdk_bad_hand")
        with pytest.raises(NeedsHttp, match="delete_robot"):
            other.delete_robot("sdk_grpc_hand")
    with GrpcClient(service.target, KEY) as client:
        assert "sdk_grpc_hand" not in {r.name for r in client.robots()}


def test_a_large_batch_is_sent_in_pieces(client: GrpcClient, service: Service) -> None:
    """Over `STREAM_BATCH_BYTES` the batch goes as `SubmitBatchStream` pieces (the server reads them one at a
    time), with the same answer; a small one as `SubmitBatch`."""
    from manifoundation.sdk._grpc_core import STREAM_BATCH_BYTES, batch_message

    large = [SynthesisRequest.model_validate(request_body(HAND, 100_000, max_iterations=1, seed=s)) for s in (0, 1)]
    assert batch_message(large).ByteSize() > STREAM_BATCH_BYTES
    before = calls_ok(service, "SubmitBatchStream")
    batch = client.submit_batch(large)
    assert batch.total == 2 and calls_ok(service, "SubmitBatchStream") == before + 1
    assert [i.state for i in batch.wait(timeout=60)] == [JobState.SUCCEEDED] * 2
    client.submit_batch([synthesis()])
    assert calls_ok(service, "SubmitBatchStream") == before + 1  # the small one whole

