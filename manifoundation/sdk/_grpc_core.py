"""What `GrpcClient` and `AsyncGrpcClient` share: their settings and every decision, without I/O.

The two clients only send (one blocking on ``grpc``, one awaited on ``grpc.aio``); what a call carries (the
API key, the channel's options), whether a failed call is retried and after how long, which SDK exception it
becomes, the version handshake and the conversions between the contract's models and the messages are here,
once. Imported by the clients after they checked that the ``[grpc]`` extra is installed.
"""

from __future__ import annotations

import contextlib
import random
from collections.abc import Iterator
from typing import Any, TypedDict

import grpc
from google.protobuf.message import Message

from manifoundation.contract import ContactsIn, JobPublic, RobotPublic, SynthesisRequest, SynthesisResult
from manifoundation.contract.plans import PlanRequest
from manifoundation.contract.protos import metadata as keys
from manifoundation.contract.protos.convert import from_proto, to_proto
from manifoundation.contract.protos.v1 import manifoundation_pb2 as pb
from manifoundation.sdk.compat import VersionCheck
from manifoundation.sdk.errors import TimeoutError
from manifoundation.sdk.grpc_errors import RETRYABLE, error_from, pairs, retry_after, sent_by_service
from manifoundation.sdk.objects import ObjectLike
from manifoundation.sdk.plans import PoseLike, make_plan
from manifoundation.sdk.requests import RobotLike, make_request
from manifoundation.sdk.retry import DEFAULT_RETRY, RetryPolicy
from manifoundation.sdk.tasks import TaskLike

DEFAULT_TARGET = "127.0.0.1:50051"
MAX_MESSAGE_BYTES = 64 * 1024 * 1024
"""Largest message sent or received: the service's default limit (``MANI_GRPC_MAX_MESSAGE_BYTES``)."""
USER_AGENT = "manifoundation-sdk/0.1"
PLAN_GRACE = 60.0
"""How much longer than a plan's ``options.timeout`` `plan` waits by default, seconds."""


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
    def following(self, call: Any, job_id: str, timeout: float | None) -> Iterator[None]:
        """Around the reading of a ``WatchJob`` stream: its failure as the SDK's exception (past its ``timeout``:
        `TimeoutError` naming the job), and the stream cancelled however the reading ends."""
        try:
            yield
        except grpc.RpcError as exc:
            self.check_failed(exc)
            failure = error_from(exc, self.target, job_id)
            if isinstance(failure, TimeoutError):
                raise TimeoutError(f"job {job_id} still running after {timeout} s", job_id=job_id) from exc
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


def synthesis(
    object: ObjectLike | SynthesisRequest,
    task: TaskLike,
    robot: RobotLike,
    contacts: ContactsIn | dict[str, Any] | None,
    options: dict[str, Any],
) -> tuple[SynthesisRequest, pb.SynthesisRequest]:
    """A synthesis request (`make_request`'s checks) and its message.

    Raises:
        ValidationError: invalid input, before anything is sent.
    """
    request = make_request(object, task, robot, contacts=contacts, **options)
    return request, to_proto(request, pb.SynthesisRequest)


def planning(
    object: ObjectLike | PlanRequest,
    start: PoseLike | None,
    waypoints: list[PoseLike] | None,
    robot: RobotLike,
    fields: dict[str, Any],
) -> tuple[PlanRequest, pb.PlanRequest]:
    """A plan request (`make_plan`'s checks) and its message."""
    request = make_plan(object, start, waypoints or [], robot, **fields)
    return request, to_proto(request, pb.PlanRequest)


def plan_wait(request: PlanRequest, wait: float | None) -> float:
    """How long `plan` waits for its job: ``wait``, else the plan's ``options.timeout`` and `PLAN_GRACE`."""
    return request.options.timeout + PLAN_GRACE if wait is None else wait


def get_job(job_id: str, with_result: bool) -> pb.GetJobRequest:
    """The ``GetJob`` request."""
    return pb.GetJobRequest(id=job_id, without_result=not with_result)


def job_ref(job_id: str) -> pb.JobRef:
    """The ``CancelJob`` request."""
    return pb.JobRef(id=job_id)


def watch_job(job_id: str, cancel_on_disconnect: bool) -> pb.WatchJobRequest:
    """The ``WatchJob`` request."""
    return pb.WatchJobRequest(id=job_id, cancel_on_disconnect=cancel_on_disconnect)


def as_result(reply: Message) -> SynthesisResult:
    """A ``SynthesisResult`` message as the contract's model."""
    return from_proto(reply, SynthesisResult, answer=True)


def as_job(reply: Message) -> JobPublic:
    """A ``JobPublic`` message as the contract's model."""
    return from_proto(reply, JobPublic, answer=True)


def as_robots(reply: pb.RobotList) -> list[RobotPublic]:
    """A ``RobotList`` message as the contract's hands."""
    return [from_proto(robot, RobotPublic, answer=True) for robot in reply.robots]
