"""Submitting synthesis work: one dependency that holds what every submit route needs.

`POST /v1/synthesize`, `POST /v1/jobs` and `POST /v1/batches` all refuse early when the queue is full, read and
validate their body, check the hands, submit on behalf of the caller and count what they submitted. `Submitter`
does those steps once, so a route states only what differs (its kind, its deadline, what it answers).
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass
from typing import Annotated

from fastapi import Depends, Request

from clients.schemas import BatchCreate, FieldError, SynthesisRequest
from service.deps import CallerDep, MetricsDep, QueueDep, RequestIdDep, RobotsDep, SettingsDep
from service.errors import InvalidInput, QueueFullError
from service.metrics import Metrics
from service.negotiation import read_model
from service.robots import RobotCatalog
from service.scenes import SceneStore
from service.security import Caller
from service.settings import Settings
from workers.queue import JobQueue

log = logging.getLogger("service.submission")


@dataclass
class Submitter:
    """The caller's way into the queue for one HTTP request."""

    request: Request
    queue: JobQueue
    robots: RobotCatalog
    metrics: Metrics
    settings: Settings
    request_id: str
    caller: Caller

    async def admit(self, count: int = 1) -> None:
        """429 `QueueFull` before reading a body the queue has no room for (`submit` still decides, atomically)."""
        if not await self.queue.room(count):
            raise QueueFullError("the queue is full; retry later", retry_after=1.0)

    async def one(self, kind: str, *, deadline_from_timeout: bool) -> tuple[SynthesisRequest, str]:
        """Read, validate and submit one request; its job's deadline is ``options.timeout`` from now when
        ``deadline_from_timeout``. Returns the request and the job's id."""
        await self.admit()
        body = await read_model(self.request, SynthesisRequest, self.settings.max_body_bytes)
        await self.robots.check(body, self.caller.tenant)
        deadline = time.time() + body.options.timeout if deadline_from_timeout else None
        tenant = self.caller.tenant
        (job_id,) = await self.queue.submit([body], deadline=deadline, request_id=self.request_id, owner=tenant)
        self.request.state.job_id = job_id
        scenes: SceneStore = self.request.app.state.scenes
        scenes.put(job_id, body)
        self.metrics.jobs_submitted.labels(kind=kind).inc()
        log.info("job submitted", extra={"job_id": job_id, "kind": kind, "request_id": self.request_id})
        return body, job_id

    async def batch(self) -> tuple[BatchCreate, str]:
        """Read, validate and submit a batch, all or none. Returns the batch and its id."""
        await self.admit()
        body = await read_model(self.request, BatchCreate, self.settings.max_body_bytes)
        count, limit, capacity = len(body.requests), self.settings.max_batch_size, self.queue.capacity
        if count > limit:
            raise InvalidInput(f"requests: {count} requests, at most {limit} per batch")
        if capacity is not None and count > capacity:
            raise InvalidInput(
                f"requests: {count} requests can never fit: the queue holds at most {capacity} jobs"
                " (MANI_MAX_QUEUE); split the batch",
                detail=[FieldError(field="requests", problem=f"more than the queue's capacity of {capacity}")],
            )
        for index, item in enumerate(body.requests):
            await self.robots.check(item, self.caller.tenant, field=f"requests.{index}.robot.name")
        tenant = self.caller.tenant
        batch_id = await self.queue.create_batch(body.requests, request_id=self.request_id, owner=tenant)
        self.metrics.batch_size.observe(count)
        self.metrics.jobs_submitted.labels(kind="batch").inc(count)
        log.info("batch submitted", extra={"batch_id": batch_id, "jobs": len(body.requests),
                                           "request_id": self.request_id})  # fmt: skip
        return body, batch_id


async def get_submitter(
    request: Request, queue: QueueDep, robots: RobotsDep, metrics: MetricsDep, settings: SettingsDep,
    request_id: RequestIdDep, caller: CallerDep,
) -> Submitter:  # fmt: skip
    return Submitter(request, queue, robots, metrics, settings, request_id, caller)


SubmitterDep = Annotated[Submitter, Depends(get_submitter)]
