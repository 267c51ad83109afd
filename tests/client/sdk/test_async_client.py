"""`AsyncClient` against the same in-process app: the same answers as `Client`, awaited."""

from __future__ import annotations

import asyncio
from collections.abc import Awaitable, Callable
from pathlib import Path
from typing import Any, TypeVar

import httpx
import numpy as np
import pytest

from manifoundation.contract import ErrorType, JobState
from manifoundation.sdk import (
    AsyncClient,
    JobFailed,
    RateLimited,
    RetryPolicy,
    Unreachable,
    ValidationError,
    make_request,
)
from tests.client.sdk.inprocess import InProcessService
from tests.client.sdk.queues import HAND

T = TypeVar("T")


def run(service: InProcessService, body: Callable[[AsyncClient], Awaitable[T]], **kwargs: Any) -> T:
    """``body(client)`` on a fresh event loop, the client talking to ``service`` (sleeps not taken)."""

    async def sleep(seconds: float) -> None:
        pass

    async def main() -> T:
        transport = service.async_transport()
        async with AsyncClient("http://testserver", transport=transport, sleep=sleep, **kwargs) as client:
            return await body(client)

    return asyncio.run(main())


def test_synthesize_concurrently(service: InProcessService, object_points: np.ndarray) -> None:
    async def body(client: AsyncClient) -> list[str]:
        results = await asyncio.gather(*(client.synthesize(object_points, robot=HAND, seed=i) for i in range(5)))
        return [r.hand for r in results]

    assert run(service, body) == [HAND] * 5
    assert sorted(str(r.options.seed) for r in service.queue.requests.values()) == ["0", "1", "2", "3", "4"]


def test_202_job_events_and_cancel(service: InProcessService, object_points: np.ndarray) -> None:
    service.queue.running_reads = 4

    async def body(client: AsyncClient) -> tuple[str, list[JobState], JobState]:
        result = await client.synthesize(object_points, "force_closure", HAND)
        job = await client.submit(object_points, robot=HAND)
        states = [e.state async for e in job.events()]
        other = await client.submit(object_points, robot=HAND)
        cancelled = (await other.cancel()).state
        with pytest.raises(JobFailed):
            await other.wait()
        return result.hand, states, cancelled

    hand, states, cancelled = run(service, body)
    assert hand == HAND and states == [JobState.RUNNING, JobState.SUCCEEDED] and cancelled is JobState.CANCELLED
    assert service.seen[0].url.path == "/v1/synthesize" and service.seen[1].url.path.startswith("/v1/jobs/")


def test_batch_in_order(service: InProcessService, object_points: np.ndarray) -> None:
    service.queue.running_reads = 1

    async def body(client: AsyncClient) -> tuple[list[int], int, int]:
        batch = await client.submit_batch([make_request(object_points, robot=HAND, seed=i) for i in range(5)])
        batch.page_size = 2
        items = await batch.wait()
        assert [service.queue.requests[i.job_id].options.seed for i in items] == [0, 1, 2, 3, 4]
        again = await client.batch(batch.id)
        return [i.index for i in items], len(await again.results()), again.total

    assert run(service, body) == ([0, 1, 2, 3, 4], 5, 5)


def test_errors_and_retries(service: InProcessService, object_points: np.ndarray) -> None:
    service.script += [httpx.ConnectError("refused")] * 3

    async def unreachable(client: AsyncClient) -> None:
        await client.health()

    with pytest.raises(Unreachable):
        run(service, unreachable, retries=2)
    assert service.script == []

    service.queue.full = True  # the app's 429 QueueFull

    async def limited(client: AsyncClient) -> None:
        await client.submit(object_points, robot=HAND)

    with pytest.raises(RateLimited) as info:
        run(service, limited, retries=RetryPolicy(max_retries=0))
    assert info.value.type == ErrorType.QUEUE_FULL and info.value.retry_after == 3.0

    async def invalid(client: AsyncClient) -> None:
        await client.synthesize(np.zeros((3, 3)))

    sent = len(service.seen)
    with pytest.raises(ValidationError):
        run(service, invalid)
    assert len(service.seen) == sent


def test_robots_and_ready(service: InProcessService, tmp_path: Path) -> None:
    async def body(client: AsyncClient) -> tuple[str, list[str], bool]:
        robot = await client.register_robot('<robot name="Two Finger"/>', ["a", "b"])
        return robot.name, [r.name for r in await client.robots()], (await client.ready()).ready

    assert run(service, body) == ("two-finger", [HAND, "two-finger"], True)
