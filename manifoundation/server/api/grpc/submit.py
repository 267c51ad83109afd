"""Submitting work (a synthesis, a batch, a plan) from a gRPC call: `manifoundation.server.api.submission.Submitter`'s
steps.

Admission before validation (RESOURCE_EXHAUSTED when the queue has no room), validation once by the contract
(`convert.from_proto`), the hand check, submission on
the caller's behalf with the call's request id, the scene kept for the viewer and the submission counted: the
same order, objects and limits as the HTTP routes, so a job submitted over gRPC is indistinguishable from one
submitted over HTTP.

A large message (over ``MANI_PARSE_OFFLOAD_BYTES``) is decoded as a large HTTP body is: its bytes arrive as a
`LargeMessage` (the server's deserializer does not parse it, `deferred`), wait for one of the same large-body slots
(``AppServices.bodies``, 503 / UNAVAILABLE after ``MANI_BODY_TIMEOUT``) and go to a body process, which parses and
validates them (`manifoundation.server.api.bodies`); this process lets go of the bytes as soon as the body process
has them and never builds the protobuf message, so neither the event loop nor a thread of this process spends the
GIL on it. gRPC receives a unary message whole before any code sees it, so a few very large ones at once still cost
their size in this process: ``SubmitBatchStream`` takes the same message in pieces (`Submission.streamed`), read
only once a slot is held and passed on one at a time. A large batch (either RPC) is packed by its body process into
the embedded queue's spool (`manifoundation.server.spool`), so its arrays never reach this process.
"""

from __future__ import annotations

import asyncio
from collections.abc import AsyncIterator, Callable
from typing import TYPE_CHECKING, Any, TypeVar

import grpc
from google.protobuf.message import Message

from manifoundation.contract import BatchCreate, SynthesisRequest, WireModel
from manifoundation.contract.protos.convert import from_proto
from manifoundation.contract.protos.v1 import manifoundation_pb2 as pb
from manifoundation.server.api.bodies import PROTOBUF
from manifoundation.server.api.middleware import request_id_from
from manifoundation.server.api.negotiation import bounded_chunks, decoded
from manifoundation.server.api.security import Caller
from manifoundation.server.api.submission import RequestT, Submitter, running_queue
from manifoundation.server.spool import SpooledBatch

if TYPE_CHECKING:
    from manifoundation.server.api.services import AppServices

ModelT = TypeVar("ModelT", bound=WireModel)
CHUNK_BYTES = 1 << 20
"""A large message goes to its body process in pieces of this size."""


class LargeMessage:
    """A request message larger than ``MANI_PARSE_OFFLOAD_BYTES`` as it arrived: its bytes, not yet parsed."""

    __slots__ = ("data", "kind")

    def __init__(self, data: bytes, kind: type[Message]) -> None:
        self.data, self.kind = data, kind

    def ByteSize(self) -> int:
        return len(self.data)

    def take(self) -> bytes:
        """The bytes, dropped from here (so they are freed once the body process has them)."""
        data, self.data = self.data, b""
        return data


def deferred(kind: type[Message], offload_bytes: int) -> Callable[[bytes], Message | LargeMessage]:
    """The request deserializer of an RPC whose message may be large: small ones parsed at once as usual, larger
    ones handed over unparsed (`LargeMessage`)."""

    def deserialize(data: bytes) -> Message | LargeMessage:
        return LargeMessage(data, kind) if len(data) > offload_bytes else kind.FromString(data)

    return deserialize


async def _pieces(data: bytes) -> AsyncIterator[bytes]:
    view = memoryview(data)
    for start in range(0, len(view), CHUNK_BYTES):
        yield view[start : start + CHUNK_BYTES]  # type: ignore[misc]


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

    async def validate(self, message: Message | LargeMessage | ModelT, model: type[ModelT]) -> ModelT:
        """The contract's validation of ``message``: a `LargeMessage` in a body process while holding a large-body
        slot; a parsed message larger than ``parse_offload_bytes`` (the limit was raised since) in a thread; a
        model already validated as it is."""
        if isinstance(message, model):
            return message
        if isinstance(message, LargeMessage):
            bodies = self.services.bodies
            async with bodies.slot():
                value: ModelT = decoded(await bodies.decode(model, _pieces(message.take()), PROTOBUF))
                return value
        assert isinstance(message, Message)
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
        message: Message | LargeMessage | RequestT,
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

    async def batch(self, message: Message | LargeMessage, caller: Caller, context: grpc.aio.ServicerContext) -> str:
        """Validate and submit a batch, all or none (the HTTP route's limits); a large one, where the queue has a
        spool, packed into it by the body process that decodes it. Returns the batch id."""
        submitter = self.submitter(caller, context)
        await submitter.admit()
        spool = self.queue.spool
        if spool is None or not isinstance(message, LargeMessage):
            return await submitter.submit_batch(await self.validate(message, BatchCreate))
        return await submitter.submit_batch(await self._spooled(_pieces(message.take()), spool))

    async def batch_streamed(
        self, pieces: AsyncIterator[pb.MessagePiece], caller: Caller, context: grpc.aio.ServicerContext
    ) -> str:
        """`batch` for a ``BatchCreate`` sent in pieces (``SubmitBatchStream``; `streamed`'s limits), packed into
        the queue's spool by the body process that decodes it where the queue has one. Returns the batch id."""
        submitter = self.submitter(caller, context)
        await submitter.admit()
        spool = self.queue.spool
        if spool is None:
            return await submitter.submit_batch(await self.streamed(pieces, pb.BatchCreate, BatchCreate))
        return await submitter.submit_batch(await self._spooled(self._bounded(pieces), spool))

    async def _spooled(self, data: AsyncIterator[bytes], spool: str) -> BatchCreate | SpooledBatch:
        """A ``BatchCreate`` message's bytes decoded by a body process (while holding a large-body slot) and packed
        into the queue's ``spool``; or its error (no byte at all: the empty message's)."""
        bodies = self.services.bodies
        async with bodies.slot():
            outcome = await bodies.spool_batch(data, PROTOBUF, spool)
        if outcome[0] == "empty":
            return await self.validate(pb.BatchCreate(), BatchCreate)
        value: SpooledBatch = decoded(outcome)
        return value

    async def streamed(
        self, pieces: AsyncIterator[pb.MessagePiece], kind: type[Message], model: type[ModelT]
    ) -> ModelT:
        """The contract's validation of a ``kind`` message sent in ``pieces``: none is read before a large-body slot
        is held (UNAVAILABLE after ``MANI_BODY_TIMEOUT``), then each goes to a body process as it comes (`_bounded`'s
        limits). No piece at all is the empty message."""
        bodies = self.services.bodies
        async with bodies.slot():
            outcome = await bodies.decode(model, self._bounded(pieces), PROTOBUF)
        if outcome[0] == "empty":  # protobuf's empty message is a message (every field at its default)
            return await self.validate(kind(), model)
        value: ModelT = decoded(outcome)
        return value

    def _bounded(self, pieces: AsyncIterator[pb.MessagePiece]) -> AsyncIterator[bytes]:
        """The bytes of ``pieces``: more than ``MANI_GRPC_MAX_MESSAGE_BYTES`` in all is RESOURCE_EXHAUSTED, a sender
        slower than an HTTP body may be (``MANI_BODY_TIMEOUT`` in all, ``MANI_BODY_IDLE_TIMEOUT`` between two
        pieces: it holds a slot meanwhile) DEADLINE_EXCEEDED."""
        settings = self.services.settings
        return bounded_chunks(
            (piece.data async for piece in pieces), settings.grpc_max_message_bytes, settings.body_timeout,
            settings.body_idle_timeout, whole="message", unit="piece", limit_name="MANI_GRPC_MAX_MESSAGE_BYTES",
        )  # fmt: skip
