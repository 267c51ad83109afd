"""The one surface of the asyncio clients: `AsyncClient` (HTTP) and `AsyncGrpcClient` (gRPC) are `AsyncAPI` over
an `AsyncTransport`; the calls, arguments, handles and errors of `manifoundation.sdk._api.SyncAPI`, awaited.

As httpx does, the asyncio surface mirrors the synchronous one method for method; what does not wait (building
requests, reading answers, batch bookkeeping, `HTTP_ONLY`) is shared with it.

Why one module: the surface, its two handles and the transport interface they drive are one unit, read together
and side by side with `manifoundation.sdk._api`.
"""

from __future__ import annotations

import os
import time
from abc import ABC, abstractmethod
from collections.abc import AsyncIterator, Callable
from typing import Any, ClassVar, Self

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
    RobotRegister,
    SynthesisRequest,
    SynthesisResult,
)
from manifoundation.sdk._api import find_robot, needs_http, plan_wait
from manifoundation.sdk.compat import VersionCheck
from manifoundation.sdk.errors import TimeoutError
from manifoundation.sdk.hands import hand_registration
from manifoundation.sdk.objects import ObjectLike
from manifoundation.sdk.plans import PoseLike, make_plan
from manifoundation.sdk.requests import RobotLike, make_request, robot_registration
from manifoundation.sdk.retry import poll_delays
from manifoundation.sdk.tasks import TaskLike
from manifoundation.sdk.tracking import (
    PLAN,
    RESULT,
    Answer,
    BatchTracker,
    item_result,
    job_result,
    plan_result,
    settled,
)


class AsyncTransport(ABC):
    """How an asyncio client sends: `manifoundation.sdk._api.Transport`'s calls, awaited (streams are async
    iterators); a call it cannot make raises `NeedsHttp` (the defaults here)."""

    streams: ClassVar[bool] = False
    versions: VersionCheck
    poll_interval: float = 1.0

    @abstractmethod
    async def sleep(self, seconds: float) -> None:
        """Wait between polls."""

    @abstractmethod
    async def aclose(self) -> None:
        """Release the connection pool or channel."""

    @abstractmethod
    async def synthesize(self, request: SynthesisRequest) -> SynthesisResult | JobCreated:
        """Submit and wait on the service's side."""

    @abstractmethod
    async def submit(self, request: SynthesisRequest) -> str:
        """Queue a synthesis; its job id."""

    @abstractmethod
    async def submit_plan(self, request: PlanRequest) -> str:
        """Queue a plan; its job id."""

    @abstractmethod
    async def job(self, job_id: str, with_result: bool = True) -> JobPublic:
        """The job now."""

    @abstractmethod
    async def cancel(self, job_id: str) -> JobPublic:
        """Ask the service to cancel the job."""

    @abstractmethod
    def events(self, job_id: str, timeout: float | None) -> AsyncIterator[JobPublic]:
        """The job on every change, ending with its final state."""

    @abstractmethod
    async def submit_batch(self, requests: list[SynthesisRequest]) -> str:
        """Queue many syntheses; the batch id."""

    @abstractmethod
    async def batch(self, batch_id: str, offset: int, limit: int) -> BatchPublic:
        """One page of a batch."""

    def batch_items(self, batch_id: str, timeout: float | None) -> AsyncIterator[BatchItem]:
        """Each item of a batch as it ends (a transport that `streams`)."""
        raise NotImplementedError(f"{type(self).__name__} does not stream batches")

    @abstractmethod
    async def robots(self) -> list[RobotPublic]:
        """The hands this key may use."""

    async def robot(self, name: str) -> RobotPublic:
        """One hand (default: found in `robots`)."""
        return find_robot(await self.robots(), name)

    @abstractmethod
    async def register_robot(self, body: RobotRegister) -> RobotPublic:
        """Register a hand."""

    async def jobs(self, limit: int) -> list[JobPublic]:
        """The most recent jobs."""
        raise needs_http("jobs")

    async def robot_preview(self, name: str) -> RobotPreview:
        """A registered hand's preview data."""
        raise needs_http("robot_preview")

    async def delete_robot(self, name: str) -> None:
        """Remove a hand."""
        raise needs_http("delete_robot")

    async def health(self) -> HealthPublic:
        """Liveness."""
        raise needs_http("health")

    async def ready(self) -> ReadyPublic:
        """Readiness."""
        raise needs_http("ready")


class AsyncAPI:
    """The calls of an asyncio client over any `AsyncTransport` (`AsyncClient`: HTTP, `AsyncGrpcClient`: gRPC):
    those of `manifoundation.sdk._api.SyncAPI`, awaited. Closed by ``await client.aclose()`` or ``async with``."""

    _job_type: ClassVar[type[AsyncJob]]

    def __init__(self, transport: AsyncTransport) -> None:
        self._transport = transport

    @property
    def versions(self) -> VersionCheck:
        """The contract version handshake with the service (`manifoundation.sdk.compat`)."""
        return self._transport.versions

    async def aclose(self) -> None:
        """Close the connection pool (HTTP) or channel (gRPC; calls still in flight are cancelled)."""
        await self._transport.aclose()

    async def __aenter__(self) -> Self:
        return self

    async def __aexit__(self, *exc: object) -> None:
        await self.aclose()

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
        """Synthesise and wait for the answer; see `SyncAPI.synthesize`."""
        request = make_request(object, task, robot, contacts=contacts, **options)
        deadline = time.monotonic() + request.options.timeout
        answer = await self._transport.synthesize(request)
        if isinstance(answer, JobCreated):
            return await self.job(answer.id).wait(max(0.0, deadline - time.monotonic()))
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
        return self.job(await self._transport.submit(request))

    async def submit_plan(
        self,
        object: ObjectLike | PlanRequest,
        start: PoseLike | None = None,
        waypoints: list[PoseLike] | None = None,
        robot: RobotLike = "allegro",
        **fields: Any,
    ) -> AsyncJob:
        """Queue a manipulation plan and return at once with its `AsyncJob`; see `SyncAPI.submit_plan`."""
        request = make_plan(object, start, waypoints or [], robot, **fields)
        return self.job(await self._transport.submit_plan(request))

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
        """Plan a manipulation and wait for it; see `SyncAPI.plan`."""
        request = make_plan(object, start, waypoints or [], robot, **fields)
        return await (await self.submit_plan(request)).plan_result(plan_wait(request, wait))

    def job(self, job_id: str) -> AsyncJob:
        """A handle on an existing job (submitted over either transport)."""
        return self._job_type(self, job_id)

    async def jobs(self, limit: int = 50) -> list[JobPublic]:
        """The most recent jobs, newest first (without results). HTTP only (`NeedsHttp` over gRPC)."""
        return await self._transport.jobs(limit)

    async def submit_batch(self, requests: list[SynthesisRequest]) -> AsyncBatch:
        """Queue many requests in one call, all or none; build them with `make_request`."""
        requests = list(requests)
        return AsyncBatch(self, await self._transport.submit_batch(requests), total=len(requests))

    async def batch(self, batch_id: str) -> AsyncBatch:
        """A handle on an existing batch (reads its size)."""
        batch = AsyncBatch(self, batch_id)
        batch.total = (await batch.status(limit=1)).total
        return batch

    # ---- robots and health ----------------------------------------------------------------------------------

    async def robots(self) -> list[RobotPublic]:
        """The built-in hands and the ones this key registered."""
        return await self._transport.robots()

    async def robot(self, name: str) -> RobotPublic:
        """One hand: DoF, joints and limits, fingertips (`NotFound` for an unknown name)."""
        return await self._transport.robot(name)

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
        return await self._transport.register_robot(body)

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
        """Register a hand from an archive, a folder or a description file; see `SyncAPI.add_robot`."""
        body = hand_registration(
            source, palm=palm, fingertips=fingertips, name=name, tip_offsets=tip_offsets, description=description,
            rest=rest, approach_axis=approach_axis,
        )  # fmt: skip
        return await self._transport.register_robot(body)

    async def robot_preview(self, name: str) -> RobotPreview:
        """A registered hand at rest (palm frame). HTTP only (`NeedsHttp` over gRPC)."""
        return await self._transport.robot_preview(name)

    async def delete_robot(self, name: str) -> None:
        """Remove a hand this key registered. HTTP only."""
        await self._transport.delete_robot(name)

    async def health(self) -> HealthPublic:
        """``GET /healthz``. HTTP only (over gRPC: grpc.health.v1)."""
        return await self._transport.health()

    async def ready(self) -> ReadyPublic:
        """``GET /readyz``. HTTP only."""
        return await self._transport.ready()


class AsyncJob:
    """A queued synthesis or plan, awaited: see `manifoundation.sdk.Job`."""

    def __init__(self, client: AsyncAPI, job_id: str) -> None:
        self.client = client
        self.id = job_id

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.id!r})"

    async def status(self) -> JobPublic:
        """The job now (with its result or error when finished)."""
        return await self.client._transport.job(self.id)

    async def cancel(self) -> JobPublic:
        """Ask the service to cancel the job."""
        return await self.client._transport.cancel(self.id)

    def events(self, timeout: float | None = None) -> AsyncIterator[JobPublic]:
        """The job's progress as it happens (SSE or ``WatchJob``), ending with its final state; see `Job.events`."""
        return self.client._transport.events(self.id, timeout)

    async def wait(self, timeout: float | None = None) -> SynthesisResult:
        """Wait for the result; raises `TimeoutError` or `JobFailed`."""
        return job_result(await self._until_done(timeout, RESULT))

    async def plan_result(self, timeout: float | None = None) -> PlanResult:
        """Wait for a plan job's plan; raises as `wait`."""
        return plan_result(await self._until_done(timeout, PLAN))

    async def finished(self, timeout: float | None = None) -> JobPublic:
        """Wait until the job has ended; the job then (`TimeoutError` after ``timeout``)."""
        return await self._until_done(timeout, None)

    async def _until_done(self, timeout: float | None, answer: Answer | None) -> JobPublic:
        """As `Job._until_done`: follow the stream where the transport has one, else poll."""
        if self.client._transport.streams:
            last: JobPublic | None = None
            async for job in self.events(timeout):
                last = job
            done = settled(last, answer)
            return await self.status() if done is None else done
        deadline = None if timeout is None else time.monotonic() + timeout
        for delay in poll_delays(cap=self.client._transport.poll_interval):
            job = await self.status()
            if job.state.terminal:
                return job
            if deadline is not None:
                left = deadline - time.monotonic()
                if left <= 0:
                    raise TimeoutError(f"job {self.id} still {job.state.value} after {timeout:g} s", job_id=self.id)
                delay = min(delay, left)
            await self.client._transport.sleep(delay)
        raise AssertionError("unreachable")


class AsyncBatch:
    """Many queued syntheses, awaited: see `manifoundation.sdk.Batch` (``total`` is read by `AsyncAPI.batch`)."""

    def __init__(self, client: AsyncAPI, batch_id: str, total: int = 0, page_size: int = 100) -> None:
        self.client = client
        self.id = batch_id
        self.total = total
        self.page_size = page_size

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.id!r})"

    async def status(self, offset: int = 0, limit: int = 100) -> BatchPublic:
        """Counts by state and one page of items."""
        return await self.client._transport.batch(self.id, offset, limit)

    async def as_completed(self, timeout: float | None = None) -> AsyncIterator[BatchItem]:
        """Each item as soon as it finishes (gRPC: ``WatchBatch``; HTTP: pages polled); raises `TimeoutError`
        after ``timeout`` seconds."""
        if not self.total:
            self.total = (await self.status(limit=1)).total
        if self.client._transport.streams:
            done = 0
            try:
                async for item in self.client._transport.batch_items(self.id, timeout):
                    done += 1
                    yield item
            except TimeoutError as exc:
                raise TimeoutError(f"batch {self.id}: {done}/{self.total} done after {timeout:g} s") from exc
            return
        async for item in self._polled(timeout):
            yield item

    async def _polled(self, timeout: float | None) -> AsyncIterator[BatchItem]:
        tracker = BatchTracker(self.id, self.total, self.page_size)
        deadline = None if timeout is None else time.monotonic() + timeout
        delays = poll_delays(cap=self.client._transport.poll_interval)
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
            await self.client._transport.sleep(delay)

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


AsyncAPI._job_type = AsyncJob
