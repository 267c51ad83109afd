"""Submitting work (a synthesis, a batch, a plan) from a gRPC call: `manifoundation.server.api.submission.Submitter`'s
steps.

Admission before validation (RESOURCE_EXHAUSTED when the queue has no room), validation once by the contract
(`convert.from_proto`; a large message off the event loop, like a large HTTP body), the hand check, submission on
the caller's behalf with the call's request id, the scene kept for the viewer and the submission counted: the
same order, objects and limits as the HTTP routes, so a job submitted over gRPC is indistinguishable from one
submitted over HTTP.
"""

from __future__ import annotations

import asyncio
from typing import TYPE_CHECKING, Any, TypeVar

import grpc
from google.protobuf.message import Message

from manifoundation.contract import BatchCreate, SynthesisRequest, WireModel
from manifoundation.contract.protos.convert import from_proto
from manifoundation.server.api.middleware import request_id_from
from manifoundation.server.api.security import Caller
from manifoundation.server.api.submission import RequestT, Submitter, running_queue

if TYPE_CHECKING:
    from manifoundation.server.api.services import AppServices

ModelT = TypeVar("ModelT", bound=WireModel)


def request_id(context: grpc.aio.ServicerContext) -> str:
    """The caller's ``x-request-id`` metadata when it is sane, else a fresh id (as for HTTP)."""
    pairs = [(k.encode(), v.encode()) for k, v in context.invocation_metadata() or () if isinstance(v, str)]
    return request_id_from(pairs)


class Submission:
    """The caller's way into the queue, over the app's own objects (``services``: the app's shared objects)."""

    def __init__(self, services: AppServices) -> None:
        self.services = services

    @property
    def queue(self) -> Any:
        """The running queue (UNAVAILABLE before the lifespan started it or while shutting down)."""
        return running_queue(self.services)

    async def validate(self, message: Message, model: type[ModelT]) -> ModelT:
        """The contract's validation of ``message``; a message larger than ``parse_offload_bytes`` off the loop."""
        if message.ByteSize() > self.services.settings.parse_offload_bytes:
            return await asyncio.to_thread(from_proto, message, model)
        return from_proto(message, model)

    def submitter(self, caller: Caller, context: grpc.aio.ServicerContext) -> Submitter:
        """The HTTP routes' `Submitter`, over this call's caller and request id."""
        s = self.services
        return Submitter(self.queue, s.catalog(), s.metrics, s.settings, s.scenes,
                         request_id(context), caller, transport="grpc")  # fmt: skip

    async def one(
        self,
        message: Message,
        caller: Caller,
        context: grpc.aio.ServicerContext,
        *,
        kind: str,
        deadline: float | None = None,
        model: type[RequestT] = SynthesisRequest,  # type: ignore[assignment]
    ) -> tuple[RequestT, str]:
        """Validate ``message`` as ``model`` (a synthesis or a plan) and submit it (its job's deadline:
        ``deadline``, Unix s). Returns it and its job id."""
        submitter = self.submitter(caller, context)
        await submitter.admit()
        body = await self.validate(message, model)
        return body, await submitter.submit(body, kind, deadline)

    async def batch(self, message: Message, caller: Caller, context: grpc.aio.ServicerContext) -> str:
        """Validate and submit a batch, all or none (the HTTP route's limits). Returns the batch id."""
        submitter = self.submitter(caller, context)
        await submitter.admit()
        return await submitter.submit_batch(await self.validate(message, BatchCreate))
