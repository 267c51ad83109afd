"""`AsyncGrpcClient` against the real gRPC server (the app's gRPC port on a free port, embedded workers running
the staged test pipeline: ``tests/api/grpc/conftest.py``): `GrpcClient`'s results, exceptions, deadlines and
retries, awaited."""

from __future__ import annotations

import asyncio
from collections.abc import Awaitable, Callable, Iterator
from typing import Any, TypeVar

import numpy as np
import pytest

from manifoundation.contract import (
    BatchItem,
    JobPublic,
    JobState,
    PlanRequest,
    RobotPublic,
    SynthesisRequest,
    SynthesisResult,
)
from manifoundation.contract.versions import CONTRACT_VERSION
from manifoundation.sdk import (
    JobFailed,
    ManiError,
    NeedsHttp,
    NotFound,
    RateLimited,
    TimeoutError,
    Unauthorized,
    Unreachable,
    ValidationError,
)
from manifoundation.sdk.grpc_async_client import AsyncGrpcClient, AsyncGrpcJob
from manifoundation.sdk.grpc_client import GrpcClient
from tests.api.grpc.conftest import FAIL_SEED, HAND, KEY, OTHER, Service, calls_ok, running
from tests.api.helpers import request_body, sphere
from tests.api.server import free_port

T = TypeVar("T")


@pytest.fixture(scope="module")
def service(request: pytest.FixtureRequest) -> Iterator[Service]:
    with running(request) as svc:
        yield svc


def run(target: str, body: Callable[[AsyncGrpcClient], Awaitable[T]], key: str | None = KEY, **kwargs: Any) -> T:
    """``body(client)`` on a fresh event loop, with a client made in it (a ``grpc.aio`` channel is the loop's)."""

    async def main() -> T:
        async with AsyncGrpcClient(target, key, **kwargs) as client:
            return await body(client)

    return asyncio.run(main())


def synthesis(hand: str = HAND, **options: Any) -> SynthesisRequest:
    return SynthesisRequest.model_validate(request_body(hand, 128, **{"max_iterations": 2, **options}))


def test_synthesize_concurrently_and_robots(service: Service) -> None:
    async def body(client: AsyncGrpcClient) -> tuple[list[SynthesisResult], list[str]]:
        results = await asyncio.gather(*(client.synthesize(synthesis(seed=i)) for i in range(3)))
        return list(results), [r.name for r in await client.robots()]

    results, robots = run(service.target, body)
    assert [r.hand for r in results] == [HAND] * 3 and robots == [HAND]
    assert all(r.model_version == "staged-test" and "refinement" in r.timings for r in results)


def test_submit_watch_get_and_wait(service: Service) -> None:
    async def body(client: AsyncGrpcClient) -> tuple[AsyncGrpcJob, list[JobPublic], SynthesisResult, JobPublic]:
        job = await client.submit(synthesis(max_iterations=4))
        updates = [update async for update in job.events(timeout=30)]
        result = await job.wait(timeout=30)
        with pytest.warns(DeprecationWarning):  # the old name, for one release
            return job, updates, result, await client.get(job.id, with_result=False)

    job, updates, result, without = run(service.target, body)
    assert updates[-1].state is JobState.SUCCEEDED and updates[-1].result is not None
    assert all(not u.state.terminal for u in updates[:-1]) and "refinement" in {u.progress.stage for u in updates}
    assert result.hand == HAND and without.state is JobState.SUCCEEDED and without.result is None
    assert repr(job) == f"AsyncGrpcJob({job.id!r})"


def test_cancel(service: Service) -> None:
    async def body(client: AsyncGrpcClient) -> tuple[str, JobPublic, JobFailed]:
        job = await client.submit(synthesis(max_iterations=20))
        cancelled = await job.cancel()
        with pytest.raises(JobFailed) as caught:
            await job.wait(timeout=20)
        return job.id, cancelled, caught.value

    job_id, cancelled, failed = run(service.target, body)
    assert cancelled.id == job_id and failed.state is JobState.CANCELLED and failed.job_id == job_id


def test_errors_are_the_sync_clients(service: Service) -> None:
    unchecked = synthesis()
    unchecked.options.num_proposals = 0  # past the SDK's own check: the service's validation answers

    async def body(client: AsyncGrpcClient) -> dict[str, ManiError]:
        raised: dict[str, ManiError] = {}
        for name, call in (
            ("missing", lambda: client.job("no-such-job").status()),
            ("hand", lambda: client.synthesize(synthesis("no_such_hand"))),
            ("local", lambda: client.synthesize(np.zeros((10, 3)))),
            ("invalid", lambda: client.synthesize(unchecked)),
            ("failed", lambda: client.synthesize(synthesis(seed=FAIL_SEED))),
        ):
            with pytest.raises(ManiError) as caught:
                await call()
            raised[name] = caught.value
        return raised

    raised = run(service.target, body)
    assert isinstance(raised["missing"], NotFound) and raised["missing"].status_code is None
    assert isinstance(raised["hand"], NotFound) and "no_such_hand" in str(raised["hand"])
    local, invalid, failed = raised["local"], raised["invalid"], raised["failed"]
    assert isinstance(local, ValidationError) and local.detail[0].field == "object.points"
    assert isinstance(invalid, ValidationError) and invalid.detail[0].field == "options.num_proposals"
    with GrpcClient(service.target, KEY) as sync, pytest.raises(ValidationError) as same:
        sync.synthesize(unchecked)
    assert (same.value.type, same.value.detail) == (invalid.type, invalid.detail)
    assert isinstance(failed, JobFailed) and failed.state is JobState.FAILED and failed.job_id
    with pytest.raises(Unauthorized):
        run(service.target, lambda client: client.robots(), key=None)
    with pytest.raises(Unreachable):
        run(f"127.0.0.1:{free_port()}", lambda client: client.robots(), retries=0)


def test_timeouts_name_the_job(service: Service) -> None:
    async def body(client: AsyncGrpcClient) -> tuple[TimeoutError, TimeoutError, str]:
        # about 1.2 s of work: the call's deadline, or on a loaded machine the job's own deadline noticed first by
        # the service (`JobExpired`, also a TimeoutError) — either names the job
        with pytest.raises(TimeoutError) as call:
            await client.synthesize(synthesis(max_iterations=20, timeout=0.4))
        job = await client.submit(synthesis(max_iterations=20))
        with pytest.raises(TimeoutError) as stream:
            await job.wait(timeout=0.2)
        await job.cancel()
        return call.value, stream.value, job.id

    call, stream, job_id = run(service.target, body)
    assert call.job_id and stream.job_id == job_id


def test_a_full_queue_is_retried_after_the_services_delay(service: Service) -> None:
    sleeps: list[float] = []

    async def sleep(seconds: float) -> None:
        sleeps.append(seconds)

    async def body(client: AsyncGrpcClient) -> tuple[RateLimited, int]:
        submitted: list[AsyncGrpcJob] = []
        before = 0
        try:
            with pytest.raises(RateLimited) as caught:
                for _ in range(20):  # max_queue is 8
                    before = len(sleeps)
                    submitted.append(await client.submit(synthesis(max_iterations=20)))
        finally:
            await asyncio.gather(*(job.cancel() for job in submitted))
        return caught.value, len(sleeps) - before

    refused, waits = run(service.target, body, retries=2, sleep=sleep)
    assert refused.type == "QueueFull" and refused.retry_after == 1.0
    # the refused submit waited the service's delay twice; an earlier one may have got in on a retry (a worker
    # took a job from the queue meanwhile), so only the last submit's waits are counted
    assert waits == 2 and all(s >= 1.0 for s in sleeps)


def test_plan(service: Service) -> None:
    points, normals = sphere(128)
    request = PlanRequest.model_validate({
        "object": {"points": points, "normals": normals}, "start": {"position": [0, 0, 0.1]},
        "waypoints": [{"position": [0.05, 0, 0.1]}, {"position": [0.1, 0, 0.1]}], "robot": {"name": HAND},
    })  # fmt: skip

    async def body(client: AsyncGrpcClient) -> tuple[list[int], str]:
        plan = await client.plan(request, wait=30)
        assert client.versions.service_contract == CONTRACT_VERSION  # the handshake ran on an answer
        return plan.waypoint_indices, repr(client)

    assert run(service.target, body) == ([1, 2], f"AsyncGrpcClient(target={service.target!r})")


def test_batches(service: Service) -> None:
    async def body(client: AsyncGrpcClient) -> tuple[int, list[int], list[BatchItem], int, str]:
        batch = await client.submit_batch([synthesis(seed=s) for s in range(2)] + [synthesis(seed=FAIL_SEED)])
        seen = sorted([item.index async for item in batch.as_completed(timeout=30)])  # WatchBatch
        items = await batch.wait(timeout=30)
        with pytest.raises(JobFailed):
            await batch.results(timeout=30)
        again = await client.batch(batch.id)  # GetBatch: reads its size
        return batch.total, seen, items, again.total, (await again.status(limit=1)).id

    total, seen, items, again, batch_id = run(service.target, body)
    assert total == again == 3 and seen == [0, 1, 2] and batch_id
    assert [i.state for i in items] == [JobState.SUCCEEDED, JobState.SUCCEEDED, JobState.FAILED]
    assert items[0].result is not None and items[0].result.hand == HAND


def test_robot_registration(service: Service) -> None:
    urdf = '<robot name="r"><link name="base"/><link name="tip"/></robot>'

    async def body(client: AsyncGrpcClient) -> tuple[RobotPublic, RobotPublic, NeedsHttp]:
        mine = await client.register_robot(urdf.encode(), ["tip"], name="sdk_async_hand")  # RegisterRobot
        found = await client.robot("sdk_async_hand")  # from ListRobots
        with pytest.raises(NotFound):
            await client.robot("no_such_hand")
        with pytest.raises(NeedsHttp) as preview:
            await client.robot_preview("sdk_async_hand")
        return mine, found, preview.value

    mine, found, preview = run(service.target, body, key=OTHER)  # another key: the module's key sees one hand
    assert mine.name == found.name == "sdk_async_hand" and found.fingertips == ["tip"] and not found.builtin
    assert preview.method == "robot_preview"


def test_a_large_batch_is_sent_in_pieces(service: Service) -> None:
    """As `GrpcClient`: over `STREAM_BATCH_BYTES` the batch goes as `SubmitBatchStream` pieces, the same answer."""
    large = [SynthesisRequest.model_validate(request_body(HAND, 100_000, max_iterations=1, seed=s)) for s in (0, 1)]

    async def body(client: AsyncGrpcClient) -> list[JobState]:
        batch = await client.submit_batch(large)
        return [item.state for item in await batch.wait(timeout=60)]

    before = calls_ok(service, "SubmitBatchStream")
    assert run(service.target, body) == [JobState.SUCCEEDED] * 2
    assert calls_ok(service, "SubmitBatchStream") == before + 1

