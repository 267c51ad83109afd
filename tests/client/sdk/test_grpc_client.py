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
    NotFound,
    RateLimited,
    TimeoutError,
    Unauthorized,
    Unreachable,
    ValidationError,
)
from manifoundation.sdk.grpc_client import GrpcClient
from manifoundation.server.api.versions import Versions
from tests.api.grpc.conftest import FAIL_SEED, HAND, KEY, Service, running
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
    service.app.state.versions = versions
    try:
        yield
    finally:
        service.app.state.versions = Versions()


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
        client.get("no-such-job")
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
    while (job := client.get(caught.value.job_id)).state is not JobState.EXPIRED and time.monotonic() < end:
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
            client.get("no-such-job")


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
    assert client.get(job.id).kind == "plan" and job.plan_result(30).waypoint_indices == [1, 2]
    with pytest.raises(JobFailed):  # a plan job carries no synthesis result
        job.wait(30)
