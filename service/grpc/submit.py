"""Submitting synthesis work from a gRPC call: the steps of `service.submission.Submitter`, for a proto message.

Admission before validation (RESOURCE_EXHAUSTED when the queue has no room), validation once by the contract
(`convert.from_proto`; a large message off the event loop, like a large HTTP body), the hand check, submission on
the caller's behalf with the call's request id, the scene kept for the viewer and the submission counted: the
same order, objects and limits as the HTTP routes, so a job submitted over gRPC is indistinguishable from one
submitted over HTTP.
"""

from __future__ import annotations

import asyncio
import logging
from typing import Any, TypeVar

import grpc
from google.protobuf.message import Message

from clients.schemas import BatchCreate, FieldError, SynthesisRequest, WireModel
from service.errors import InvalidInput, QueueFullError, Unavailable
from service.grpc.convert import from_proto
from service.middleware import request_id_from
from service.security import Caller

log = logging.getLogger("service.grpc")
ModelT = TypeVar("ModelT", bound=WireModel)


def request_id(context: grpc.aio.ServicerContext) -> str:
    """The caller's ``x-request-id`` metadata when it is sane, else a fresh id (as for HTTP)."""
    pairs = [(k.encode(), v.encode()) for k, v in context.invocation_metadata() or () if isinstance(v, str)]
    return request_id_from(pairs)


class Submission:
    """The caller's way into the queue, over the app's own objects (``state``: the FastAPI app's state)."""

    def __init__(self, state: Any) -> None:
        self.state = state

    @property
    def queue(self) -> Any:
        """The running queue (UNAVAILABLE before the lifespan started it or while shutting down)."""
        queue = getattr(self.state, "queue", None)
        if queue is None or getattr(self.state, "shutting_down", False):
            raise Unavailable("the service is not accepting work (starting or shutting down)")
        return queue

    async def admit(self, count: int = 1) -> None:
        """RESOURCE_EXHAUSTED before validating a message the queue has no room for."""
        if not await self.queue.room(count):
            raise QueueFullError("the queue is full; retry later", retry_after=1.0)

    async def validate(self, message: Message, model: type[ModelT]) -> ModelT:
        """The contract's validation of ``message``; a message larger than ``parse_offload_bytes`` off the loop."""
        if message.ByteSize() > self.state.settings.parse_offload_bytes:
            return await asyncio.to_thread(from_proto, message, model)
        return from_proto(message, model)

    async def one(
        self,
        message: Message,
        caller: Caller,
        context: grpc.aio.ServicerContext,
        *,
        kind: str,
        deadline: float | None = None,
    ) -> tuple[SynthesisRequest, str]:
        """Validate and submit one request (its job's deadline: ``deadline``, Unix s). Returns it and its job id."""
        await self.admit()
        body = await self.validate(message, SynthesisRequest)
        await self.state.robots.check(body, caller.tenant)
        rid = request_id(context)
        (job_id,) = await self.queue.submit([body], deadline=deadline, request_id=rid, owner=caller.tenant)
        self.state.scenes.put(job_id, body)
        self.state.metrics.jobs_submitted.labels(kind=kind).inc()
        log.info("job submitted", extra={"job_id": job_id, "kind": kind, "request_id": rid, "transport": "grpc"})
        return body, job_id

    async def batch(self, message: Message, caller: Caller, context: grpc.aio.ServicerContext) -> str:
        """Validate and submit a batch, all or none (the HTTP route's limits). Returns the batch id."""
        await self.admit()
        body = await self.validate(message, BatchCreate)
        settings, capacity = self.state.settings, self.queue.capacity
        count = len(body.requests)
        if count > settings.max_batch_size:
            raise InvalidInput(f"requests: {count} requests, at most {settings.max_batch_size} per batch")
        if capacity is not None and count > capacity:
            raise InvalidInput(
                f"requests: {count} requests can never fit: the queue holds at most {capacity} jobs"
                " (MANI_MAX_QUEUE); split the batch",
                detail=[FieldError(field="requests", problem=f"more than the queue's capacity of {capacity}")],
            )
        for index, item in enumerate(body.requests):
            await self.state.robots.check(item, caller.tenant, field=f"requests.{index}.robot.name")
        rid = request_id(context)
        batch_id: str = await self.queue.create_batch(body.requests, request_id=rid, owner=caller.tenant)
        self.state.metrics.batch_size.observe(count)
        self.state.metrics.jobs_submitted.labels(kind="batch").inc(count)
        log.info("batch submitted", extra={"batch_id": batch_id, "jobs": count, "request_id": rid, "transport": "grpc"})
        return batch_id
