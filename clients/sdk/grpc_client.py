"""`GrpcClient`: the SDK over the service's gRPC port (``mani serve`` answers gRPC on 50051 beside HTTP).

The same inputs (`make_request`), results (`SynthesisResult`, `JobPublic`, `RobotPublic`, numpy arrays) and
exceptions (`clients.sdk.errors`, mapped once in `clients.sdk.grpc_errors`) as `Client`; messages are converted
by the contract's one conversion (`clients.protos.convert`). Needs the ``[grpc]`` extra::

    pip install 'manifoundation-client[grpc]'

    from clients.sdk.grpc_client import GrpcClient

    with GrpcClient("127.0.0.1:50051") as client:
        result = client.synthesize(object_from_file("box.npz"), delta_pose([0, 0, 0.05]), "leap")

Deadlines: `synthesize` gives its call the request's ``options.timeout``, which the service makes the job's
deadline too (the job ends *expired* when the call gives up: `TimeoutError` names it); the other unary calls get
the client's ``timeout``; streams run until their job ends unless given a ``timeout`` for the whole stream.
Refusals the service sends (a full queue, a rate limit, shutting down) are retried with the `RetryPolicy`, honouring
its retry delay; a service that cannot be reached is retried for the calls that change nothing.
"""

from __future__ import annotations

import random
import time
from collections.abc import Callable, Iterator
from typing import Any, TypeVar

from clients.sdk.extras import missing_extra

try:
    import grpc
    from google.protobuf.message import Message
except ModuleNotFoundError as exc:  # the [grpc] extra is not installed
    raise missing_extra(exc, "grpc", "GrpcClient") from exc

from clients.protos import metadata as keys
from clients.protos.convert import from_proto, to_proto
from clients.protos.manifoundation.v1 import manifoundation_pb2 as pb
from clients.protos.manifoundation.v1 import manifoundation_pb2_grpc as pb_grpc
from clients.schemas import ContactsIn, JobPublic, RobotPublic, SynthesisRequest, SynthesisResult
from clients.schemas.plans import PlanRequest, PlanResult
from clients.sdk.compat import VersionCheck
from clients.sdk.errors import TimeoutError
from clients.sdk.grpc_errors import RETRYABLE, error_from, pairs, retry_after, sent_by_service
from clients.sdk.grpc_job import GrpcJob
from clients.sdk.objects import ObjectLike
from clients.sdk.plans import PoseLike, make_plan
from clients.sdk.requests import RobotLike, make_request
from clients.sdk.retry import DEFAULT_RETRY, RetryPolicy
from clients.sdk.tasks import TaskLike

ReplyT = TypeVar("ReplyT", bound=Message)
DEFAULT_TARGET = "127.0.0.1:50051"
MAX_MESSAGE_BYTES = 64 * 1024 * 1024
"""Largest message sent or received: the service's default limit (``MANI_GRPC_MAX_MESSAGE_BYTES``)."""
USER_AGENT = "manifoundation-sdk/0.1"


class GrpcClient:
    """Talk to a ManiFoundation service over gRPC, from synchronous code.

    Args:
        target: ``host:port`` of the service's gRPC port.
        api_key: sent as ``authorization: Bearer ...`` metadata (None: no auth).
        timeout: deadline of one unary call other than `synthesize`, seconds.
        retries: a `RetryPolicy`, or the number of retries with the default backoff.
        credentials: ``grpc.ssl_channel_credentials(...)`` for TLS (None: plaintext).
        max_message_bytes: largest message sent or received.
        sleep: how to wait between retries (tests may record instead).
    """

    def __init__(
        self,
        target: str = DEFAULT_TARGET,
        api_key: str | None = None,
        *,
        timeout: float = 30.0,
        retries: RetryPolicy | int = DEFAULT_RETRY,
        credentials: grpc.ChannelCredentials | None = None,
        max_message_bytes: int = MAX_MESSAGE_BYTES,
        sleep: Callable[[float], None] = time.sleep,
    ) -> None:
        self.target = target
        self.timeout = timeout
        self.retry_policy = retries if isinstance(retries, RetryPolicy) else RetryPolicy(max_retries=int(retries))
        self.versions = VersionCheck(f"grpc://{target}")
        self._metadata = ((keys.AUTHORIZATION, f"Bearer {api_key}"),) if api_key else ()
        options = [
            ("grpc.max_send_message_length", max_message_bytes),
            ("grpc.max_receive_message_length", max_message_bytes),
            ("grpc.primary_user_agent", USER_AGENT),
        ]
        if credentials is None:
            self._channel = grpc.insecure_channel(target, options=options)
        else:
            self._channel = grpc.secure_channel(target, credentials, options=options)
        self._stub = pb_grpc.ManiFoundationStub(self._channel)
        self._sleep = sleep
        self._rng = random.Random()

    def __repr__(self) -> str:
        return f"GrpcClient(target={self.target!r})"

    def close(self) -> None:
        """Close the channel."""
        self._channel.close()

    def __enter__(self) -> GrpcClient:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # ---- synthesis ------------------------------------------------------------------------------------------

    def synthesize(
        self,
        object: ObjectLike | SynthesisRequest,
        task: TaskLike = "force_closure",
        robot: RobotLike = "leap",
        *,
        contacts: ContactsIn | dict[str, Any] | None = None,
        **options: Any,
    ) -> SynthesisResult:
        """Synthesise contacts, forces and a hand pose, and wait for the answer (arguments as `Client.synthesize`).

        Raises:
            ValidationError: invalid input (checked before sending, and by the service).
            TimeoutError: no result within ``options.timeout`` (``exc.job_id``: the job, which then expired).
            JobFailed: the job failed, was cancelled or expired.
        """
        request = make_request(object, task, robot, contacts=contacts, **options)
        message = to_proto(request, pb.SynthesisRequest)
        reply = self._unary(self._stub.Synthesize, message, timeout=request.options.timeout, idempotent=False)
        return from_proto(reply, SynthesisResult, answer=True)

    def submit(
        self,
        object: ObjectLike | SynthesisRequest,
        task: TaskLike = "force_closure",
        robot: RobotLike = "leap",
        *,
        contacts: ContactsIn | dict[str, Any] | None = None,
        **options: Any,
    ) -> GrpcJob:
        """Queue a synthesis and return at once with its `GrpcJob` (same arguments as `synthesize`)."""
        request = make_request(object, task, robot, contacts=contacts, **options)
        reply = self._unary(self._stub.SubmitJob, to_proto(request, pb.SynthesisRequest), idempotent=False)
        return GrpcJob(self, reply.id)

    def submit_plan(
        self,
        object: ObjectLike | PlanRequest,
        start: PoseLike | None = None,
        waypoints: list[PoseLike] | None = None,
        robot: RobotLike = "allegro",
        **fields: Any,
    ) -> GrpcJob:
        """Queue a manipulation plan (``SubmitPlan``) and return at once with its `GrpcJob` (``job.plan_result()``
        waits for it). Arguments as `clients.sdk.make_plan` (or one whole `PlanRequest`)."""
        request = make_plan(object, start, waypoints or [], robot, **fields)
        reply = self._unary(self._stub.SubmitPlan, to_proto(request, pb.PlanRequest), idempotent=False)
        return GrpcJob(self, reply.id)

    def plan(
        self,
        object: ObjectLike | PlanRequest,
        start: PoseLike | None = None,
        waypoints: list[PoseLike] | None = None,
        robot: RobotLike = "allegro",
        *,
        wait: float | None = None,
        **fields: Any,
    ) -> PlanResult:
        """Plan a manipulation and wait for it (as `Client.plan`: the dense trajectory, the repaired waypoints
        and a verified contact answer per step).

        Raises:
            ValidationError: invalid input; JobFailed: e.g. ``InfeasibleWaypoint`` / ``NoPathFound``;
                TimeoutError: not finished within ``wait`` (default: the plan's ``options.timeout`` + 60 s).
        """
        request = make_plan(object, start, waypoints or [], robot, **fields)
        job = self.submit_plan(request)
        return job.plan_result(request.options.timeout + 60.0 if wait is None else wait)

    def job(self, job_id: str) -> GrpcJob:
        """A handle on an existing job (submitted over either transport)."""
        return GrpcJob(self, job_id)

    def get(self, job_id: str, *, with_result: bool = True) -> JobPublic:
        """The job now: state, stage and progress, timings, and its result or error when finished."""
        request = pb.GetJobRequest(id=job_id, without_result=not with_result)
        return from_proto(self._unary(self._stub.GetJob, request), JobPublic, answer=True)

    def cancel(self, job_id: str) -> JobPublic:
        """Ask the service to cancel the job (no effect when it already finished)."""
        return from_proto(self._unary(self._stub.CancelJob, pb.JobRef(id=job_id)), JobPublic, answer=True)

    def watch(
        self, job_id: str, *, timeout: float | None = None, cancel_on_disconnect: bool = False
    ) -> Iterator[JobPublic]:
        """The job on every change of state or stage, ending with it in full once it finished.

        Args:
            timeout: for the whole stream, seconds (None: until the job ends).
            cancel_on_disconnect: cancel the job when this stream is dropped before it ends.

        Raises:
            TimeoutError: the job had not ended after ``timeout``.
        """
        request = pb.WatchJobRequest(id=job_id, cancel_on_disconnect=cancel_on_disconnect)
        call = self._stub.WatchJob(request, timeout=timeout, metadata=self._metadata)
        try:
            self._check(call.initial_metadata())
            for message in call:
                job = from_proto(message, JobPublic, answer=True)
                yield job
                if job.state.terminal:
                    return
        except grpc.RpcError as exc:
            self._check_failed(exc)
            failure = error_from(exc, self.target, job_id)
            if isinstance(failure, TimeoutError):
                raise TimeoutError(f"job {job_id} still running after {timeout} s", job_id=job_id) from exc
            raise failure from exc
        finally:
            call.cancel()

    # ---- robots ---------------------------------------------------------------------------------------------

    def robots(self) -> list[RobotPublic]:
        """The built-in hands and the ones this key registered."""
        reply = self._unary(self._stub.ListRobots, pb.ListRobotsRequest())
        return [from_proto(robot, RobotPublic, answer=True) for robot in reply.robots]

    # ---- plumbing -------------------------------------------------------------------------------------------

    def _unary(self, rpc: Any, request: Message, *, timeout: float | None = None, idempotent: bool = True) -> Any:
        """One unary call with retries; its answer, or the SDK's exception for its failure."""
        attempt = 0
        while True:
            try:
                reply, call = rpc.with_call(request, timeout=timeout or self.timeout, metadata=self._metadata)
            except grpc.RpcError as exc:
                self._check_failed(exc)
                delay = self._retry_delay(attempt, exc, idempotent)
                if delay is None:
                    job_id = pairs(exc.initial_metadata()).get(keys.JOB_ID)
                    raise error_from(exc, self.target, job_id) from exc
                self._sleep(delay)
                attempt += 1
                continue
            self._check(call.initial_metadata())
            return reply

    def _retry_delay(self, attempt: int, exc: grpc.RpcError, idempotent: bool) -> float | None:
        """Seconds before the next try, or None: the failure stands."""
        code = exc.code()
        if attempt >= self.retry_policy.max_retries or code not in RETRYABLE:
            return None
        if sent_by_service(exc) or (idempotent and code is grpc.StatusCode.UNAVAILABLE):
            after = retry_after(pairs(exc.trailing_metadata()))
            return self.retry_policy.delay(attempt, after, self._rng)
        return None

    def _check(self, metadata: Any) -> None:
        """The version handshake on an answer's metadata (`clients.sdk.compat`)."""
        self.versions.see(pairs(metadata).get)

    def _check_failed(self, exc: grpc.RpcError) -> None:
        """The version handshake on a failed call (its initial metadata, else its trailers)."""
        found = {**pairs(exc.trailing_metadata()), **pairs(exc.initial_metadata())}
        self.versions.see(found.get)
