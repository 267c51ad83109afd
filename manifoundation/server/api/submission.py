"""Submitting work, the same for every front end: one `Submitter` per call.

`POST /v1/synthesize`, `POST /v1/jobs`, `POST /v1/batches`, `POST /v1/plans`, their gRPC twins and the MCP tools
all refuse early when the queue is full, validate their body once, check the hands, submit on behalf of the
caller, keep the scene for the viewer and count what they submitted. `Submitter` does those steps once; a front
end states only how it reads its body (`read_and_submit` / `read_and_submit_batch` for HTTP,
`manifoundation.server.api.grpc.submit`
for gRPC, `manifoundation.server.api.mcp.backend` for MCP), its kind and its deadline.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Annotated, TypeVar

from fastapi import Depends, Request

from manifoundation.contract import (
    BatchCreate,
    BatchItem,
    BatchPublic,
    FieldError,
    JobRequest,
    JobState,
    PlanRequest,
    SynthesisRequest,
)
from manifoundation.server.api.deps import CallerDep, MetricsDep, QueueDep, RequestIdDep, RobotsDep, SettingsDep
from manifoundation.server.api.errors import InvalidInput, QueueFullError, Unavailable
from manifoundation.server.api.metrics import Metrics
from manifoundation.server.api.negotiation import read_batch, read_model
from manifoundation.server.api.robots import RobotCatalog
from manifoundation.server.api.scenes import SceneStore
from manifoundation.server.api.security import Caller
from manifoundation.server.api.services import AppServices, services_of
from manifoundation.server.api.settings import Settings
from manifoundation.server.queue import JobQueue
from manifoundation.server.spool import SpooledBatch, SpooledRequest

log = logging.getLogger("manifoundation.server.api.submission")
RequestT = TypeVar("RequestT", SynthesisRequest, PlanRequest)


def running_queue(services: AppServices) -> JobQueue:
    """The app's queue while it takes work; `Unavailable` before the lifespan started it or while shutting down.
    (The front ends outside FastAPI's dependencies, gRPC and MCP, ask for it here.)"""
    queue = services.queue
    if queue is None or services.shutting_down:
        raise Unavailable("the service is not accepting work (starting or shutting down)")
    return queue


@dataclass
class Submitter:
    """The caller's way into the queue for one call (HTTP request or gRPC call)."""

    queue: JobQueue
    robots: RobotCatalog
    metrics: Metrics
    settings: Settings
    scenes: SceneStore
    request_id: str
    caller: Caller
    transport: str = "http"

    async def admit(self, count: int = 1) -> None:
        """429 `QueueFull` before reading a body the queue has no room for (`submit` still decides, atomically)."""
        await refuse_if_full(self.queue, count)

    async def submit(self, body: JobRequest, kind: str, deadline: float | None) -> str:
        """Check the hand, submit one validated request (a synthesis or a plan; its job's deadline: ``deadline``,
        Unix s); its job id. ``kind`` labels the submission in the metrics and logs ("sync", "async", "plan")."""
        await self.robots.check(body, self.caller.tenant)
        tenant = self.caller.tenant
        (job_id,) = await self.queue.submit([body], deadline=deadline, request_id=self.request_id, owner=tenant)
        self.scenes.put(job_id, body)
        self.metrics.jobs_submitted.labels(kind=kind).inc()
        log.info("job submitted", extra={"job_id": job_id, "kind": kind, "request_id": self.request_id,
                                         "transport": self.transport})  # fmt: skip
        return job_id

    async def submit_batch(self, body: BatchCreate | SpooledBatch) -> str:
        """Check the batch's limits and hands, submit it all or none; its id. A batch already packed into the
        queue's spool (`manifoundation.server.spool.SpooledBatch`) is the queue's once accepted; refused, its files
        are removed."""
        try:
            return await self._submit_batch(body)
        except BaseException:
            if isinstance(body, SpooledBatch):
                body.discard()
            raise

    async def _submit_batch(self, body: BatchCreate | SpooledBatch) -> str:
        requests: Sequence[SynthesisRequest | SpooledRequest] = body.requests
        count, limit, capacity = len(requests), self.settings.max_batch_size, self.queue.capacity
        if count > limit:
            raise InvalidInput(f"requests: {count} requests, at most {limit} per batch")
        if capacity is not None and count > capacity:
            raise InvalidInput(
                f"requests: {count} requests can never fit: the queue holds at most {capacity} jobs"
                " (MANI_MAX_QUEUE); split the batch",
                detail=[FieldError(field="requests", problem=f"more than the queue's capacity of {capacity}")],
            )
        for index, item in enumerate(requests):
            await self.robots.check(item, self.caller.tenant, field=f"requests.{index}.robot.name")
        tenant = self.caller.tenant
        batch_id = await self.queue.create_batch(requests, request_id=self.request_id, owner=tenant)
        self.metrics.batch_size.observe(count)
        self.metrics.jobs_submitted.labels(kind="batch").inc(count)
        log.info("batch submitted", extra={"batch_id": batch_id, "jobs": count, "request_id": self.request_id,
                                           "transport": self.transport})  # fmt: skip
        return batch_id

    async def first_page(self, batch_id: str, size: int = 100) -> BatchPublic:
        """A just-submitted batch as its answer shows it: every job queued, the first ``size`` job ids."""
        job_ids = await self.queue.batch_job_ids(batch_id, owner=self.caller.tenant)
        limit = min(size, len(job_ids))
        items = [BatchItem(index=i, job_id=j, state=JobState.QUEUED) for i, j in enumerate(job_ids[:limit])]
        return BatchPublic(
            id=batch_id, total=len(job_ids), counts={JobState.QUEUED: len(job_ids)}, done=False, items=items,
            offset=0, limit=limit, created_at=time.time(),
        )  # fmt: skip


async def read_and_submit(
    request: Request, submitter: Submitter, kind: str, *, deadline_from_timeout: bool,
    model: type[RequestT] = SynthesisRequest,  # type: ignore[assignment]
) -> tuple[RequestT, str]:  # fmt: skip
    """HTTP: read and validate the body as ``model``, submit (the job's deadline ``options.timeout`` from now
    when ``deadline_from_timeout``; the route's `Admitted` has refused a full queue). Returns the request and the
    job's id."""
    body = await read_model(request, model, submitter.settings.max_body_bytes)
    deadline = time.time() + body.options.timeout if deadline_from_timeout else None
    job_id = await submitter.submit(body, kind, deadline)
    request.state.job_id = job_id
    return body, job_id


async def read_and_submit_batch(request: Request, submitter: Submitter) -> str:
    """HTTP: read and validate a batch (`Admitted` has refused a full queue; a large one packed into the queue's
    spool as it is decoded), submit it all or none. Returns its id."""
    body = await read_batch(request, submitter.settings.max_body_bytes, submitter.queue.spool)
    return await submitter.submit_batch(body)


async def refuse_if_full(queue: JobQueue, count: int = 1) -> None:
    """429 `QueueFull` when the queue has no room for ``count`` more jobs."""
    if not await queue.room(count):
        raise QueueFullError("the queue is full; retry later", retry_after=1.0)


async def admitted(queue: QueueDep) -> None:
    """The HTTP submit routes' first check after the key's: a full queue is refused before the body is read and
    before the rest of the call is prepared (the cheapest refusal; gRPC calls `Submitter.admit`)."""
    await refuse_if_full(queue)


Admitted = Depends(admitted)


async def get_submitter(
    request: Request, queue: QueueDep, robots: RobotsDep, metrics: MetricsDep, settings: SettingsDep,
    request_id: RequestIdDep, caller: CallerDep,
) -> Submitter:  # fmt: skip
    return Submitter(queue, robots, metrics, settings, services_of(request).scenes, request_id, caller)


SubmitterDep = Annotated[Submitter, Depends(get_submitter)]
