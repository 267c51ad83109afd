"""`GrpcClient`: the SDK over the service's gRPC port (``mani serve`` answers gRPC on 50051 beside HTTP).

The same inputs (`make_request`), results (`SynthesisResult`, `JobPublic`, `RobotPublic`, numpy arrays) and
exceptions (`manifoundation.sdk.errors`, mapped once in `manifoundation.sdk.grpc_errors`) as `Client`; messages are
converted
by the contract's one conversion (`manifoundation.contract.protos.convert`). Needs the ``[grpc]`` extra::

    pip install 'manifoundation-client[grpc]'

    from manifoundation.sdk.grpc_client import GrpcClient

    with GrpcClient("127.0.0.1:50051") as client:
        result = client.synthesize(object_from_file("box.npz"), delta_pose([0, 0, 0.05]), "leap")

Deadlines: `synthesize` gives its call the request's ``options.timeout``, which the service makes the job's
deadline too (the job ends *expired* when the call gives up: `TimeoutError` names it); the other unary calls get
the client's ``timeout``; streams run until their job ends unless given a ``timeout`` for the whole stream.
Refusals the service sends (a full queue, a rate limit, shutting down) are retried with the `RetryPolicy`, honouring
its retry delay; a service that cannot be reached is retried for the calls that change nothing.
"""

from __future__ import annotations

import itertools
import time
from collections.abc import Callable, Iterator
from typing import Any, Unpack

from manifoundation.sdk.extras import missing_extra

try:
    import grpc
    from google.protobuf.message import Message
except ModuleNotFoundError as exc:  # the [grpc] extra is not installed
    raise missing_extra(exc, "grpc", "GrpcClient") from exc

from manifoundation.contract import ContactsIn, JobPublic, RobotPublic, SynthesisRequest, SynthesisResult
from manifoundation.contract.plans import PlanRequest, PlanResult
from manifoundation.contract.protos.v1 import manifoundation_pb2 as pb
from manifoundation.contract.protos.v1 import manifoundation_pb2_grpc as pb_grpc
from manifoundation.sdk import _grpc_core as core
from manifoundation.sdk._grpc_core import DEFAULT_TARGET, MAX_MESSAGE_BYTES, GrpcBase, GrpcSettings
from manifoundation.sdk.grpc_job import GrpcJob
from manifoundation.sdk.objects import ObjectLike
from manifoundation.sdk.plans import PoseLike
from manifoundation.sdk.requests import RobotLike
from manifoundation.sdk.tasks import TaskLike

__all__ = ["DEFAULT_TARGET", "MAX_MESSAGE_BYTES", "GrpcClient", "GrpcJob"]


class GrpcClient(GrpcBase):
    """Talk to a ManiFoundation service over gRPC, from synchronous code.

    Args:
        target: ``host:port`` of the service's gRPC port.
        api_key: sent as ``authorization: Bearer ...`` metadata (None: no auth).
        credentials: ``grpc.ssl_channel_credentials(...)`` for TLS (None: plaintext).
        sleep: how to wait between retries (tests may record instead).
        settings: ``timeout`` (of one unary call other than `synthesize`, seconds; default 30), ``retries`` (a
            `RetryPolicy`, or the number of retries with the default backoff), ``max_message_bytes``: see
            `manifoundation.sdk._grpc_core.GrpcBase`.
    """

    def __init__(
        self,
        target: str = DEFAULT_TARGET,
        api_key: str | None = None,
        *,
        credentials: grpc.ChannelCredentials | None = None,
        sleep: Callable[[float], None] = time.sleep,
        **settings: Unpack[GrpcSettings],
    ) -> None:
        super().__init__(target, api_key, **settings)
        if credentials is None:
            self._channel = grpc.insecure_channel(target, options=self.options)
        else:
            self._channel = grpc.secure_channel(target, credentials, options=self.options)
        self._stub = pb_grpc.ManiFoundationStub(self._channel)
        self._sleep = sleep

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
        request, message = core.synthesis(object, task, robot, contacts, options)
        reply = self._unary(self._stub.Synthesize, message, timeout=request.options.timeout, idempotent=False)
        return core.as_result(reply)

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
        _, message = core.synthesis(object, task, robot, contacts, options)
        return GrpcJob(self, self._unary(self._stub.SubmitJob, message, idempotent=False).id)

    def submit_plan(
        self,
        object: ObjectLike | PlanRequest,
        start: PoseLike | None = None,
        waypoints: list[PoseLike] | None = None,
        robot: RobotLike = "allegro",
        **fields: Any,
    ) -> GrpcJob:
        """Queue a manipulation plan (``SubmitPlan``) and return at once with its `GrpcJob` (``job.plan_result()``
        waits for it). Arguments as `manifoundation.sdk.make_plan` (or one whole `PlanRequest`)."""
        _, message = core.planning(object, start, waypoints, robot, fields)
        return GrpcJob(self, self._unary(self._stub.SubmitPlan, message, idempotent=False).id)

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
        request, _ = core.planning(object, start, waypoints, robot, fields)
        return self.submit_plan(request).plan_result(core.plan_wait(request, wait))

    def job(self, job_id: str) -> GrpcJob:
        """A handle on an existing job (submitted over either transport)."""
        return GrpcJob(self, job_id)

    def get(self, job_id: str, *, with_result: bool = True) -> JobPublic:
        """The job now: state, stage and progress, timings, and its result or error when finished."""
        return core.as_job(self._unary(self._stub.GetJob, core.get_job(job_id, with_result)))

    def cancel(self, job_id: str) -> JobPublic:
        """Ask the service to cancel the job (no effect when it already finished)."""
        return core.as_job(self._unary(self._stub.CancelJob, core.job_ref(job_id)))

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
        request = core.watch_job(job_id, cancel_on_disconnect)
        call = self._stub.WatchJob(request, timeout=timeout, metadata=self.metadata)
        with self.following(call, job_id, timeout):
            self.check(call.initial_metadata())
            for message in call:
                job = core.as_job(message)
                yield job
                if job.state.terminal:
                    return

    # ---- robots ---------------------------------------------------------------------------------------------

    def robots(self) -> list[RobotPublic]:
        """The built-in hands and the ones this key registered."""
        return core.as_robots(self._unary(self._stub.ListRobots, pb.ListRobotsRequest()))

    # ---- plumbing -------------------------------------------------------------------------------------------

    def _unary(self, rpc: Any, request: Message, *, timeout: float | None = None, idempotent: bool = True) -> Any:
        """One unary call with retries; its answer, or the SDK's exception for its failure."""
        for attempt in itertools.count():
            try:
                reply, call = rpc.with_call(request, timeout=timeout or self.timeout, metadata=self.metadata)
            except grpc.RpcError as exc:
                self._sleep(self.next_delay(attempt, exc, idempotent))
                continue
            self.check(call.initial_metadata())
            return reply
        raise AssertionError("unreachable")
