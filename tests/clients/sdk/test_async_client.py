"""`AsyncClient` over the same fake transport: the same answers as `Client`, awaited."""

from __future__ import annotations

import asyncio
from collections.abc import Awaitable, Callable
from typing import Any, TypeVar

import httpx
import numpy as np
import pytest

from clients.schemas import JobState
from clients.sdk import AsyncClient, JobFailed, RateLimited, RetryPolicy, Unreachable, ValidationError, make_request

T = TypeVar("T")


def run(fake: Any, body: Callable[[AsyncClient], Awaitable[T]], **kwargs: Any) -> T:
    sleeps: list[float] = []

    async def sleep(seconds: float) -> None:
        sleeps.append(seconds)

    async def main() -> T:
        async with AsyncClient("http://testserver", transport=fake.transport(), sleep=sleep, **kwargs) as client:
            return await body(client)

    return asyncio.run(main())


def test_synthesize_concurrently(fake: Any, object_points: np.ndarray) -> None:
    async def body(client: AsyncClient) -> list[str]:
        results = await asyncio.gather(*(client.synthesize(object_points, seed=i) for i in range(5)))
        return [r.hand for r in results]

    assert run(fake, body) == ["leap"] * 5


def test_202_job_events_and_cancel(fake: Any, object_points: np.ndarray) -> None:
    fake.sync_finishes, fake.polls_to_finish = False, 2

    async def body(client: AsyncClient) -> tuple[str, list[JobState], JobState]:
        result = await client.synthesize(object_points, "force_closure", "allegro")
        job = await client.submit(object_points)
        states = [e.state async for e in job.events()]
        other = await client.submit(object_points)
        cancelled = (await other.cancel()).state
        with pytest.raises(JobFailed):
            await other.wait()
        return result.hand, states, cancelled

    hand, states, cancelled = run(fake, body)
    assert hand == "allegro" and states[-1] is JobState.SUCCEEDED and cancelled is JobState.CANCELLED


def test_batch_in_order(fake: Any, object_points: np.ndarray) -> None:
    fake.polls_to_finish = 1

    async def body(client: AsyncClient) -> tuple[list[int], int, int]:
        batch = await client.submit_batch([make_request(object_points, seed=i) for i in range(5)])
        batch.page_size = 2
        items = await batch.wait()
        again = await client.batch(batch.id)
        return [i.index for i in items], len(await again.results()), again.total

    assert run(fake, body) == ([0, 1, 2, 3, 4], 5, 5)


def test_errors_and_retries(fake: Any, object_points: np.ndarray) -> None:
    fake.script += [httpx.ConnectError("refused")] * 3

    async def unreachable(client: AsyncClient) -> None:
        await client.health()

    with pytest.raises(Unreachable):
        run(fake, unreachable, retries=2)

    fake.script[:] = [httpx.Response(429, json={"error": "full", "type": "QueueFull"}, headers={"Retry-After": "1"})]

    async def limited(client: AsyncClient) -> None:
        await client.robots()

    with pytest.raises(RateLimited):
        run(fake, limited, retries=RetryPolicy(max_retries=0))

    async def invalid(client: AsyncClient) -> None:
        await client.synthesize(np.zeros((3, 3)))

    with pytest.raises(ValidationError):
        run(fake, invalid)


def test_robots_and_ready(fake: Any, tmp_path: Any) -> None:
    async def body(client: AsyncClient) -> tuple[str, int, bool]:
        robot = await client.register_robot('<robot name="Two Finger"/>', ["a", "b"])
        return robot.name, len(await client.robots()), (await client.ready()).ready

    assert run(fake, body) == ("two-finger", 1, True)
