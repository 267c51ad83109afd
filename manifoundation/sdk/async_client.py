"""`AsyncClient`: the asyncio SDK. Same calls as `Client`, awaited; every decision lives in `BaseClient`.

Why one module: it mirrors `Client` method for method (the httpx pattern); keeping each client in one file keeps
the pair side by side, and every method is a thin await of a `BaseClient` call.
"""

from __future__ import annotations

import asyncio
import os
import time
from collections.abc import AsyncIterator, Awaitable, Callable
from typing import Any, TypeVar

import httpx

from manifoundation.contract import (
    BatchItem,
    BatchPublic,
    ContactsIn,
    HealthPublic,
    JobCreated,
    JobPublic,
    PlanRequest,
    PlanResult,
    ReadyPublic,
    RobotPreview,
    RobotPublic,
    SynthesisRequest,
    SynthesisResult,
)
from manifoundation.sdk._core import BaseClient, Call
from manifoundation.sdk.errors import TimeoutError
from manifoundation.sdk.hands import hand_registration
from manifoundation.sdk.objects import ObjectLike
from manifoundation.sdk.plans import PoseLike, make_plan
from manifoundation.sdk.requests import RobotLike, make_request, robot_registration
from manifoundation.sdk.retry import poll_delays
from manifoundation.sdk.sse import SSEDecoder
from manifoundation.sdk.tasks import TaskLike
from manifoundation.sdk.tracking import JOB_EVENT_TYPES, BatchTracker, item_result, job_result, parse_event, plan_result

T = TypeVar("T")


class AsyncClient(BaseClient):
    """Talk to a ManiFoundation service from asyncio code (e.g. many requests in flight at once).

    Example::

        async with AsyncClient("http://127.0.0.1:8000") as client:
            results = await asyncio.gather(*(client.synthesize(obj, task, "leap") for task in tasks))

    Args:
        base_url, api_key, timeout, retries, encoding, headers, poll_interval: see `BaseClient`.
        transport: an ``httpx.AsyncBaseTransport`` to send through (tests: the app in process).
        sleep: how to wait between retries and polls.
    """

    def __init__(
        self,
        base_url: str | None = None,
        api_key: str | None = None,
        *,
        transport: httpx.AsyncBaseTransport | None = None,
        sleep: Callable[[float], Awaitable[None]] = asyncio.sleep,
        **kwargs: Any,
    ) -> None:
        super().__init__(base_url, api_key, **kwargs)
        self._http = httpx.AsyncClient(transport=transport, timeout=self.timeout)
        self._sleep = sleep

    async def aclose(self) -> None:
        """Close the connection pool."""
        await self._http.aclose()

    async def __aenter__(self) -> AsyncClient:
        return self

    async def __aexit__(self, *exc: object) -> None:
        await self.aclose()

    # ---- sending --------------------------------------------------------------------------------------------

    async def send(self, request: httpx.Request, *, stream: bool = False, retry: bool = True) -> httpx.Response:
        """Send with retries (429/503 and connection errors, backoff + jitter, Retry-After honoured)."""
        attempt = 0 if retry else self.retry_policy.max_retries
        while True:
            try:
                response = await self._http.send(request, stream=stream)
            except httpx.TransportError as exc:
                delay = self.retry_delay(attempt, request, exc=exc)
                if delay is None:
                    raise self.transport_error(request, exc) from exc
            else:
                delay = self.retry_delay(attempt, request, response=response)
                if delay is None:
                    if stream and not response.is_success:
                        await response.aread()
                    return response
                await response.aclose()
            await self._sleep(delay)
            attempt += 1

    async def _run(self, call: Call[T]) -> T:
        return call.parse(await self.send(call.request, retry=call.retry))

    # ---- synthesis ------------------------------------------------------------------------------------------

    async def synthesize(
        self,
        object: ObjectLike | SynthesisRequest,
        task: TaskLike = "force_closure",
        robot: RobotLike = "leap",
        *,
        contacts: ContactsIn | dict[str, Any] | None = None,
        **options: Any,
    ) -> SynthesisResult:
        """Synthesise and wait for the answer; see `Client.synthesize`."""
        request = make_request(object, task, robot, contacts=contacts, **options)
        deadline = time.monotonic() + request.options.timeout
        answer = await self._run(self._call_synthesize(request))
        if isinstance(answer, JobCreated):
            return await AsyncJob(self, answer.id).wait(max(0.0, deadline - time.monotonic()))
        return answer

    async def submit(
        self,
        object: ObjectLike | SynthesisRequest,
        task: TaskLike = "force_closure",
        robot: RobotLike = "leap",
        *,
        contacts: ContactsIn | dict[str, Any] | None = None,
        **options: Any,
    ) -> AsyncJob:
        """Queue a synthesis and return at once with its `AsyncJob`."""
        request = make_request(object, task, robot, contacts=contacts, **options)
        return AsyncJob(self, (await self._run(self._call_submit(request))).id)

    async def submit_plan(
        self,
        object: ObjectLike | PlanRequest,
        start: PoseLike | None = None,
        waypoints: list[PoseLike] | None = None,
        robot: RobotLike = "allegro",
        **fields: Any,
    ) -> AsyncJob:
        """Queue a manipulation plan and return at once with its `AsyncJob`; see `Client.submit_plan`."""
        request = make_plan(object, start, waypoints or [], robot, **fields)
        return AsyncJob(self, (await self._run(self._call_submit_plan(request))).id)

    async def plan(
        self,
        object: ObjectLike | PlanRequest,
        start: PoseLike | None = None,
        waypoints: list[PoseLike] | None = None,
        robot: RobotLike = "allegro",
        *,
        wait: float | None = None,
        **fields: Any,
    ) -> PlanResult:
        """Plan a manipulation and wait for it; see `Client.plan`."""
        request = make_plan(object, start, waypoints or [], robot, **fields)
        job = AsyncJob(self, (await self._run(self._call_submit_plan(request))).id)
        return await job.plan_result(request.options.timeout + 60.0 if wait is None else wait)

    def job(self, job_id: str) -> AsyncJob:
        """A handle on an existing job."""
        return AsyncJob(self, job_id)

    async def jobs(self, limit: int = 50) -> list[JobPublic]:
        """The most recent jobs, newest first (without results)."""
        return await self._run(self._call_jobs(limit))

    async def submit_batch(self, requests: list[SynthesisRequest]) -> AsyncBatch:
        """Queue many requests in one call; build them with `make_request`."""
        batch_id = await self._run(self._call_submit_batch(list(requests)))
        return AsyncBatch(self, batch_id, total=len(requests))

    async def batch(self, batch_id: str) -> AsyncBatch:
        """A handle on an existing batch (reads its size)."""
        batch = AsyncBatch(self, batch_id)
        batch.total = (await batch.status(limit=1)).total
        return batch

    # ---- robots and health ----------------------------------------------------------------------------------

    async def robots(self) -> list[RobotPublic]:
        """The built-in and registered hands."""
        return await self._run(self._call_robots())

    async def robot(self, name: str) -> RobotPublic:
        """One hand: DoF, joints and limits, fingertips."""
        return await self._run(self._call_robot(name))

    async def register_robot(
        self,
        urdf: str | bytes | os.PathLike[str],
        fingertips: list[str],
        *,
        name: str | None = None,
        tip_offsets: Any = None,
    ) -> RobotPublic:
        """Register a custom hand from a URDF (text or file)."""
        body = robot_registration(urdf, fingertips, name=name, tip_offsets=tip_offsets)
        return await self._run(self._call_register_robot(body))

    async def add_robot(
        self,
        source: str | bytes | os.PathLike[str],
        *,
        palm: str | None = None,
        fingertips: list[str] | None = None,
        name: str | None = None,
        tip_offsets: Any = None,
        description: str | None = None,
        rest: dict[str, float] | None = None,
        approach_axis: Any = None,
    ) -> RobotPublic:
        """Register a hand from an archive (zip/tar of a URDF or MJCF and its meshes), a folder, or a description
        file (see `manifoundation.sdk.hands`); ``palm`` cuts it from a whole robot. The answer reports DoF, fingertips,
        spheres, pad areas, couplings, what was ignored, and ``view_url``."""
        body = hand_registration(
            source, palm=palm, fingertips=fingertips, name=name, tip_offsets=tip_offsets, description=description,
            rest=rest, approach_axis=approach_axis,
        )  # fmt: skip
        return await self._run(self._call_register_robot(body))

    async def robot_preview(self, name: str) -> RobotPreview:
        """A registered hand at rest (palm frame): coarse meshes, collision spheres, pad samples, fingertips."""
        return await self._run(self._call_robot_preview(name))

    async def delete_robot(self, name: str) -> None:
        """Remove a hand this key registered (jobs naming it afterwards get 404)."""
        await self._run(self._call_delete_robot(name))

    async def health(self) -> HealthPublic:
        """``GET /healthz``."""
        return await self._run(self._call_health())

    async def ready(self) -> ReadyPublic:
        """``GET /readyz``."""
        return await self._run(self._call_ready())


class AsyncJob:
    """A queued synthesis, awaited: see `Job`."""

    def __init__(self, client: AsyncClient, job_id: str) -> None:
        self.client = client
        self.id = job_id

    def __repr__(self) -> str:
        return f"AsyncJob({self.id!r})"

    async def status(self) -> JobPublic:
        """The job now (with its result or error when finished)."""
        return await self.client._run(self.client._call_job(self.id))

    async def cancel(self) -> JobPublic:
        """Ask the service to cancel the job."""
        return await self.client._run(self.client._call_cancel(self.id))

    async def wait(self, timeout: float | None = None) -> SynthesisResult:
        """Wait for the result; raises `TimeoutError` or `JobFailed`."""
        return job_result(await self.finished(timeout))

    async def plan_result(self, timeout: float | None = None) -> PlanResult:
        """Wait for a plan job's plan; raises as `wait`."""
        return plan_result(await self.finished(timeout))

    async def finished(self, timeout: float | None = None) -> JobPublic:
        """Poll until the job has ended; the job then (`TimeoutError` after ``timeout``)."""
        deadline = None if timeout is None else time.monotonic() + timeout
        for delay in poll_delays(cap=self.client.poll_interval):
            job = await self.status()
            if job.state.terminal:
                return job
            if deadline is not None:
                left = deadline - time.monotonic()
                if left <= 0:
                    raise TimeoutError(f"job {self.id} still {job.state.value} after {timeout:g} s", job_id=self.id)
                delay = min(delay, left)
            await self.client._sleep(delay)
        raise AssertionError("unreachable")

    async def events(self, timeout: float | None = None) -> AsyncIterator[JobPublic]:
        """The job's progress as it happens (Server-Sent Events), ending with its final state."""
        request = self.client.build_request(
            "GET", f"/v1/jobs/{self.id}/events", accept="text/event-stream", read_timeout=timeout
        )
        response = await self.client.send(request, stream=True)
        try:
            self.client.raise_for_status(response)
            decoder = SSEDecoder()
            async for line in response.aiter_lines():
                event = decoder.decode(line)
                if event is None or not event.data or event.event not in JOB_EVENT_TYPES:
                    continue
                job = parse_event(event.data)
                yield job
                if job.state.terminal:
                    return
        except httpx.TimeoutException as exc:
            raise TimeoutError(f"no progress from job {self.id} in {timeout} s", job_id=self.id) from exc
        finally:
            await response.aclose()


class AsyncBatch:
    """Many queued syntheses, awaited: see `Batch`."""

    def __init__(self, client: AsyncClient, batch_id: str, total: int = 0, page_size: int = 100) -> None:
        self.client = client
        self.id = batch_id
        self.total = total
        self.page_size = page_size

    def __repr__(self) -> str:
        return f"AsyncBatch({self.id!r})"

    async def status(self, offset: int = 0, limit: int = 100) -> BatchPublic:
        """Counts by state and one page of items."""
        return await self.client._run(self.client._call_batch(self.id, offset, limit))

    async def as_completed(self, timeout: float | None = None) -> AsyncIterator[BatchItem]:
        """Each item as soon as it finishes; raises `TimeoutError` after ``timeout`` seconds."""
        if not self.total:
            self.total = (await self.status(limit=1)).total
        tracker = BatchTracker(self.id, self.total, self.page_size)
        deadline = None if timeout is None else time.monotonic() + timeout
        delays = poll_delays(cap=self.client.poll_interval)
        while not tracker.done:
            for n, offset in enumerate(tracker.pending_pages()):
                if n > 0 and not tracker.worth_more_pages():
                    break
                for item in tracker.update(await self.status(offset, self.page_size)):
                    yield item
            for item in tracker.missing_results():
                yield tracker.fill(item.index, await self.client.job(item.job_id).status())
            if tracker.done:
                return
            delay = next(delays)
            if deadline is not None:
                left = deadline - time.monotonic()
                if left <= 0:
                    done = len(tracker.reported)
                    raise TimeoutError(f"batch {self.id}: {done}/{tracker.total} done after {timeout:g} s")
                delay = min(delay, left)
            await self.client._sleep(delay)

    async def wait(
        self, timeout: float | None = None, progress: Callable[[BatchItem], object] | None = None
    ) -> list[BatchItem]:
        """Every item in request order, each with its ``result`` or ``error``."""
        items: dict[int, BatchItem] = {}
        async for item in self.as_completed(timeout):
            items[item.index] = item
            if progress is not None:
                progress(item)
        return [items[i] for i in range(self.total)]

    async def results(self, timeout: float | None = None) -> list[SynthesisResult]:
        """Every result in request order; raises `JobFailed` for the first item that did not succeed."""
        return [item_result(item) for item in await self.wait(timeout)]
