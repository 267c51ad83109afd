"""What `GrpcClient` and `AsyncGrpcClient` share: their settings and every decision, without I/O.

The two clients only send (one blocking on ``grpc``, one awaited on ``grpc.aio``); what a call carries (the
API key, the channel's options), whether a failed call is retried and after how long, which SDK exception it
becomes, the version handshake and the conversions between the contract's models and the messages are here,
once. Imported by the clients after they checked that the ``[grpc]`` extra is installed.
"""

from __future__ import annotations

import contextlib
import random
import warnings
from collections.abc import Callable, Iterator
from typing import Any, Protocol, TypeAlias, TypedDict

import grpc
import pydantic
from google.protobuf.message import Message

from manifoundation.contract import (
    BatchCreate,
    BatchItem,
    BatchPublic,
    JobPublic,
    PlanRequest,
    RobotPublic,
    RobotRegister,
    SynthesisRequest,
    SynthesisResult,
)
from manifoundation.contract.protos import metadata as keys
from manifoundation.contract.protos.convert import from_proto, to_proto
from manifoundation.contract.protos.v1 import manifoundation_pb2 as pb
from manifoundation.sdk.compat import VersionCheck
from manifoundation.sdk.errors import TimeoutError, local_validation_error
from manifoundation.sdk.grpc_errors import RETRYABLE, error_from, pairs, retry_after, sent_by_service
from manifoundation.sdk.retry import DEFAULT_RETRY, RetryPolicy

DEFAULT_TARGET = "127.0.0.1:50051"
MAX_MESSAGE_BYTES = 64 * 1024 * 1024
"""Largest message sent or received: the service's default limit (``MANI_GRPC_MAX_MESSAGE_BYTES``)."""
USER_AGENT = "manifoundation-sdk/0.1"
STREAM_BATCH_BYTES = 8 * 1024 * 1024
"""Batches whose message is larger than this are sent in pieces (``SubmitBatchStream``, `batch_request`): gRPC
receives a unary message whole before the service reads a byte of it, so many large ones at once cost the service
their size; pieces are read one at a time as it decodes them."""
PIECE_BYTES = 1024 * 1024
"""The size of a piece of a streamed batch."""
Request: TypeAlias = Message | Callable[[], Iterator[Message]]
"""What a call sends: a message, or (a client-streaming call) a function making the stream of its pieces anew for
each attempt."""


class StreamCall(Protocol):
    """What `GrpcBase.following` needs of a streaming call (``grpc`` and ``grpc.aio`` ones have it)."""

    def cancel(self) -> bool: ...


class UnaryRpc(Protocol):
    """A blocking unary method of a ``grpc`` stub."""

    def with_call(
        self, request: Message | Iterator[Message], *, timeout: float | None, metadata: tuple[tuple[str, str], ...]
    ) -> tuple[Message, grpc.Call]: ...


class GrpcSettings(TypedDict, total=False):
    """The keyword settings both gRPC clients take (see `GrpcBase`)."""

    timeout: float
    retries: RetryPolicy | int
    max_message_bytes: int


class GrpcBase:
    """The state and the decisions of a gRPC client (the base of `GrpcClient` and `AsyncGrpcClient`).

    Args:
        target: ``host:port`` of the service's gRPC port.
        api_key: sent as ``authorization: Bearer ...`` metadata (None: no auth).
        timeout: deadline of one unary call other than `synthesize`, seconds.
        retries: a `RetryPolicy`, or the number of retries with the default backoff.
        max_message_bytes: largest message sent or received.
    """

    def __init__(
        self,
        target: str,
        api_key: str | None,
        *,
        timeout: float = 30.0,
        retries: RetryPolicy | int = DEFAULT_RETRY,
        max_message_bytes: int = MAX_MESSAGE_BYTES,
    ) -> None:
        self.target = target
        self.timeout = timeout
        self.retry_policy = retries if isinstance(retries, RetryPolicy) else RetryPolicy(max_retries=int(retries))
        self.versions = VersionCheck(f"grpc://{target}")
        self.metadata: tuple[tuple[str, str], ...] = ((keys.AUTHORIZATION, f"Bearer {api_key}"),) if api_key else ()
        self.options: list[tuple[str, int | str]] = [
            ("grpc.max_send_message_length", max_message_bytes),
            ("grpc.max_receive_message_length", max_message_bytes),
            ("grpc.primary_user_agent", USER_AGENT),
        ]
        self._rng = random.Random()

    def __repr__(self) -> str:
        return f"{type(self).__name__}(target={self.target!r})"

    def next_delay(self, attempt: int, exc: grpc.RpcError, idempotent: bool) -> float:
        """Seconds to wait before trying a failed unary call again (``attempt``: the retries so far).

        Raises:
            ManiError: the SDK's exception for the failure, when it stands (`manifoundation.sdk.grpc_errors`).
            IncompatibleService: the failed call named another major version of the contract.
        """
        self.check_failed(exc)
        delay = self._retry_delay(attempt, exc, idempotent)
        if delay is None:
            job_id = pairs(exc.initial_metadata()).get(keys.JOB_ID)
            raise error_from(exc, self.target, job_id) from exc
        return delay

    def _retry_delay(self, attempt: int, exc: grpc.RpcError, idempotent: bool) -> float | None:
        """Seconds before the next try, or None: the failure stands."""
        code = exc.code()
        if attempt >= self.retry_policy.max_retries or code not in RETRYABLE:
            return None
        if sent_by_service(exc) or (idempotent and code is grpc.StatusCode.UNAVAILABLE):
            after = retry_after(pairs(exc.trailing_metadata()))
            return self.retry_policy.delay(attempt, after, self._rng)
        return None

    @contextlib.contextmanager
    def following(
        self, call: StreamCall, subject: str, timeout: float | None, job_id: str | None = None
    ) -> Iterator[None]:
        """Around the reading of a ``WatchJob`` or ``WatchBatch`` stream: its failure as the SDK's exception (past
        its ``timeout``: `TimeoutError` naming ``subject``, e.g. ``"job <id>"``, and ``job_id``), and the stream
        cancelled however the reading ends."""
        try:
            yield
        except grpc.RpcError as exc:
            self.check_failed(exc)
            failure = error_from(exc, self.target, job_id)
            if isinstance(failure, TimeoutError):
                raise TimeoutError(f"{subject} still running after {timeout} s", job_id=job_id) from exc
            raise failure from exc
        finally:
            call.cancel()

    def check(self, metadata: Any) -> None:
        """The version handshake on an answer's metadata (`manifoundation.sdk.compat`)."""
        self.versions.see(pairs(metadata).get)

    def check_failed(self, exc: grpc.RpcError) -> None:
        """The version handshake on a failed call (its initial metadata, else its trailers)."""
        found = {**pairs(exc.trailing_metadata()), **pairs(exc.initial_metadata())}
        self.versions.see(found.get)


# ---- messages -----------------------------------------------------------------------------------------------


def synthesis_message(request: SynthesisRequest) -> pb.SynthesisRequest:
    """The ``Synthesize`` / ``SubmitJob`` request."""
    return to_proto(request, pb.SynthesisRequest)


def plan_message(request: PlanRequest) -> pb.PlanRequest:
    """The ``SubmitPlan`` request."""
    return to_proto(request, pb.PlanRequest)


def sent(request: Request) -> Message | Iterator[Message]:
    """What one attempt of a call sends (`Request`)."""
    return request() if callable(request) else request


def batch_request(stub: Any, requests: list[SynthesisRequest]) -> tuple[Any, Request]:
    """The RPC and the request that submit ``requests``: ``SubmitBatch`` with the whole message, or above
    `STREAM_BATCH_BYTES` ``SubmitBatchStream`` with its `PIECE_BYTES` pieces (the same answer)."""
    message = batch_message(requests)
    if message.ByteSize() <= STREAM_BATCH_BYTES:
        return stub.SubmitBatch, message
    pieces = message_pieces(message.SerializeToString())
    return stub.SubmitBatchStream, lambda: iter(pieces)


def message_pieces(data: bytes, size: int = PIECE_BYTES) -> list[pb.MessagePiece]:
    """A serialized message as the `MessagePiece`s of a client-streaming call, ``size`` bytes each (the last
    shorter)."""
    return [pb.MessagePiece(data=data[i : i + size]) for i in range(0, len(data), size)]


def batch_message(requests: list[SynthesisRequest]) -> pb.BatchCreate:
    """The ``SubmitBatch`` request, checked as `Client`'s (1 to `MAX_BATCH_SIZE` requests) before sending.

    Raises:
        ValidationError: too few or too many requests.
    """
    try:
        body = BatchCreate(requests=requests)
    except pydantic.ValidationError as exc:
        raise local_validation_error(exc) from exc
    return to_proto(body, pb.BatchCreate)


def robot_message(body: RobotRegister) -> pb.RobotRegister:
    """The ``RegisterRobot`` request."""
    return to_proto(body, pb.RobotRegister)


def get_job(job_id: str, with_result: bool) -> pb.GetJobRequest:
    """The ``GetJob`` request."""
    return pb.GetJobRequest(id=job_id, without_result=not with_result)


def job_ref(job_id: str) -> pb.JobRef:
    """The ``CancelJob`` request."""
    return pb.JobRef(id=job_id)


def watch_job(job_id: str, cancel_on_disconnect: bool) -> pb.WatchJobRequest:
    """The ``WatchJob`` request."""
    return pb.WatchJobRequest(id=job_id, cancel_on_disconnect=cancel_on_disconnect)


def get_batch(batch_id: str, offset: int, limit: int) -> pb.GetBatchRequest:
    """The ``GetBatch`` request."""
    return pb.GetBatchRequest(id=batch_id, offset=offset, limit=limit)


def batch_ref(batch_id: str) -> pb.BatchRef:
    """The ``WatchBatch`` request."""
    return pb.BatchRef(id=batch_id)


def created_id(reply: Message) -> str:
    """The job id of a ``JobCreated`` answer (the message has no ``url``: the HTTP answer's link)."""
    assert isinstance(reply, pb.JobCreated)
    return reply.id


def as_result(reply: Message) -> SynthesisResult:
    """A ``SynthesisResult`` message as the contract's model."""
    return from_proto(reply, SynthesisResult, answer=True)


def as_job(reply: Message) -> JobPublic:
    """A ``JobPublic`` message as the contract's model."""
    return from_proto(reply, JobPublic, answer=True)


def as_batch(reply: Message) -> BatchPublic:
    """A ``BatchPublic`` message as the contract's model."""
    return from_proto(reply, BatchPublic, answer=True)


def as_batch_item(reply: Message) -> BatchItem:
    """A ``BatchItem`` message as the contract's model."""
    return from_proto(reply, BatchItem, answer=True)


def as_robot(reply: Message) -> RobotPublic:
    """A ``RobotPublic`` message as the contract's model."""
    return from_proto(reply, RobotPublic, answer=True)


def as_robots(reply: Message) -> list[RobotPublic]:
    """A ``RobotList`` message as the contract's hands."""
    assert isinstance(reply, pb.RobotList)
    return [from_proto(robot, RobotPublic, answer=True) for robot in reply.robots]


def deprecated(old: str, new: str) -> None:
    """Warn once per call site that ``old`` is going (one release): use ``new``."""
    warnings.warn(f"{old} is deprecated and goes in the next release: use {new}", DeprecationWarning, stacklevel=3)
