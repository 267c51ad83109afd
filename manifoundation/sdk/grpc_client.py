"""`GrpcClient`: the SDK over the service's gRPC port (``mani serve`` answers gRPC on 50051 beside HTTP).

The one surface of `Client` (`manifoundation.sdk._api.SyncAPI`: the same calls, inputs, results, handles and
exceptions) over a `GrpcTransport`, which only sends each call as its RPC and converts the answer with the
contract's one conversion (`manifoundation.contract.protos.convert`); failures are mapped once in
`manifoundation.sdk.grpc_errors`. Needs the ``[grpc]`` extra::

    pip install 'manifoundation-client[grpc]'

    from manifoundation.sdk.grpc_client import GrpcClient

    with GrpcClient("127.0.0.1:50051") as client:
        result = client.synthesize(object_from_file("box.npz"), delta_pose([0, 0, 0.05]), "leap")

Deadlines: `synthesize` gives its call the request's ``options.timeout``, which the service makes the job's
deadline too (the job ends *expired* when the call gives up: `TimeoutError` names it); the other unary calls get
the client's ``timeout``; streams run until their job (batch) ends unless given a ``timeout`` for the whole stream.
Refusals the service sends (a full queue, a rate limit, shutting down) are retried with the `RetryPolicy`, honouring
its retry delay; a service that cannot be reached is retried for the calls that change nothing.
"""

from __future__ import annotations

import itertools
import time
from collections.abc import Callable, Iterator
from typing import Unpack

from manifoundation.sdk.extras import missing_extra

try:
    import grpc
    from google.protobuf.message import Message
except ModuleNotFoundError as exc:  # the [grpc] extra is not installed
    raise missing_extra(exc, "grpc", "GrpcClient") from exc

from manifoundation.contract import (
    BatchItem,
    BatchPublic,
    JobPublic,
    PlanRequest,
    RobotPublic,
    RobotRegister,
    SynthesisRequest,
    SynthesisResult,
)
from manifoundation.contract.protos.v1 import manifoundation_pb2 as pb
from manifoundation.contract.protos.v1 import manifoundation_pb2_grpc as pb_grpc
from manifoundation.sdk import _grpc_core as core
from manifoundation.sdk._api import SyncAPI, Transport
from manifoundation.sdk._grpc_core import DEFAULT_TARGET, MAX_MESSAGE_BYTES, GrpcBase, GrpcSettings, UnaryRpc
from manifoundation.sdk.grpc_job import GrpcJob

__all__ = ["DEFAULT_TARGET", "MAX_MESSAGE_BYTES", "GrpcClient", "GrpcJob", "GrpcTransport"]


class GrpcTransport(GrpcBase, Transport):
    """`GrpcClient`'s transport: each call its RPC on one blocking channel, retried as `GrpcBase` decides; jobs and
    batches are followed on ``WatchJob`` / ``WatchBatch``.

    Args:
        target, api_key, settings: see `GrpcBase`.
        channel: a ``grpc.Channel`` to send through (default: one made for ``target``, plaintext or with
            ``credentials``); the transport closes it.
        credentials: ``grpc.ssl_channel_credentials(...)`` for TLS (None: plaintext).
        sleep: how to wait between retries.
    """

    streams = True

    def __init__(
        self,
        target: str = DEFAULT_TARGET,
        api_key: str | None = None,
        *,
        channel: grpc.Channel | None = None,
        credentials: grpc.ChannelCredentials | None = None,
        sleep: Callable[[float], None] = time.sleep,
        **settings: Unpack[GrpcSettings],
    ) -> None:
        super().__init__(target, api_key, **settings)
        if channel is None:
            if credentials is None:
                channel = grpc.insecure_channel(target, options=self.options)
            else:
                channel = grpc.secure_channel(target, credentials, options=self.options)
        self._channel = channel
        self._stub = pb_grpc.ManiFoundationStub(channel)
        self._sleep = sleep

    def sleep(self, seconds: float) -> None:
        """Wait between retries."""
        self._sleep(seconds)

    def close(self) -> None:
        """Close the channel."""
        self._channel.close()

    def unary(
        self, rpc: UnaryRpc, request: core.Request, *, timeout: float | None = None, idempotent: bool = True
    ) -> Message:
        """One unary (or client-streaming) call with retries; its answer, or the SDK's exception for its failure."""
        for attempt in itertools.count():
            try:
                reply, call = rpc.with_call(core.sent(request), timeout=timeout or self.timeout, metadata=self.metadata)
            except grpc.RpcError as exc:
                self._sleep(self.next_delay(attempt, exc, idempotent))
                continue
            self.check(call.initial_metadata())
            return reply
        raise AssertionError("unreachable")

    # ---- the calls (`Transport`) ----------------------------------------------------------------------------

    def synthesize(self, request: SynthesisRequest) -> SynthesisResult:
        message = core.synthesis_message(request)
        return core.as_result(
            self.unary(self._stub.Synthesize, message, timeout=request.options.timeout, idempotent=False)
        )

    def submit(self, request: SynthesisRequest) -> str:
        return core.created_id(self.unary(self._stub.SubmitJob, core.synthesis_message(request), idempotent=False))

    def submit_plan(self, request: PlanRequest) -> str:
        return core.created_id(self.unary(self._stub.SubmitPlan, core.plan_message(request), idempotent=False))

    def job(self, job_id: str, with_result: bool = True) -> JobPublic:
        return core.as_job(self.unary(self._stub.GetJob, core.get_job(job_id, with_result)))

    def cancel(self, job_id: str) -> JobPublic:
        return core.as_job(self.unary(self._stub.CancelJob, core.job_ref(job_id)))

    def events(self, job_id: str, timeout: float | None, cancel_on_disconnect: bool = False) -> Iterator[JobPublic]:
        """``WatchJob``: the job on every change of state or stage, ending with it in full once it finished;
        ``timeout`` for the whole stream (`TimeoutError` naming the job)."""
        call = self._stub.WatchJob(
            core.watch_job(job_id, cancel_on_disconnect), timeout=timeout, metadata=self.metadata
        )
        with self.following(call, f"job {job_id}", timeout, job_id):
            self.check(call.initial_metadata())
            for message in call:
                job = core.as_job(message)
                yield job
                if job.state.terminal:
                    return

    def submit_batch(self, requests: list[SynthesisRequest]) -> str:
        rpc, request = core.batch_request(self._stub, requests)
        return core.as_batch(self.unary(rpc, request, idempotent=False)).id

    def batch(self, batch_id: str, offset: int, limit: int) -> BatchPublic:
        return core.as_batch(self.unary(self._stub.GetBatch, core.get_batch(batch_id, offset, limit)))

    def batch_items(self, batch_id: str, timeout: float | None) -> Iterator[BatchItem]:
        """``WatchBatch``: each item with its result or error as its job ends, until every job has."""
        call = self._stub.WatchBatch(core.batch_ref(batch_id), timeout=timeout, metadata=self.metadata)
        with self.following(call, f"batch {batch_id}", timeout):
            self.check(call.initial_metadata())
            for message in call:
                yield core.as_batch_item(message)

    def robots(self) -> list[RobotPublic]:
        return core.as_robots(self.unary(self._stub.ListRobots, pb.ListRobotsRequest()))

    def register_robot(self, body: RobotRegister) -> RobotPublic:
        return core.as_robot(self.unary(self._stub.RegisterRobot, core.robot_message(body), idempotent=False))


class GrpcClient(SyncAPI):
    """Talk to a ManiFoundation service over gRPC, from synchronous code: the calls of `Client`.

    ``synthesize``, ``submit``, ``submit_plan``, ``plan``, ``job`` (a `GrpcJob`: ``status``, ``cancel``, ``wait``,
    ``events``, ``plan_result``, ``finished``), ``submit_batch`` and ``batch`` (a `Batch`, its items followed on
    ``WatchBatch``), ``robots``, ``robot`` (found in ``ListRobots``), ``register_robot`` and ``add_robot``
    (``RegisterRobot``). ``jobs``, ``robot_preview``, ``delete_robot``, ``health`` and ``ready`` have no RPC: they
    raise `NeedsHttp` before sending (`manifoundation.sdk._api.HTTP_ONLY` says why; for a probe use
    ``grpc.health.v1``). Close it with ``close()`` or a ``with`` block. Deprecated (one release): ``get(id)``
    (use ``job(id).status()``), ``cancel(id)`` (``job(id).cancel()``), ``watch(id)`` (``job(id).events()``).

    Args:
        target: ``host:port`` of the service's gRPC port.
        api_key: sent as ``authorization: Bearer ...`` metadata (None: no auth).
        channel: a ``grpc.Channel`` to send through instead of one made for ``target`` (the client closes it).
        credentials: ``grpc.ssl_channel_credentials(...)`` for TLS (None: plaintext).
        sleep: how to wait between retries (tests may record instead).
        settings: ``timeout`` (of one unary call other than `synthesize`, seconds; default 30), ``retries`` (a
            `RetryPolicy`, or the number of retries with the default backoff), ``max_message_bytes``: see
            `manifoundation.sdk._grpc_core.GrpcBase`.
    """

    _job_type = GrpcJob

    def __init__(
        self,
        target: str = DEFAULT_TARGET,
        api_key: str | None = None,
        *,
        channel: grpc.Channel | None = None,
        credentials: grpc.ChannelCredentials | None = None,
        sleep: Callable[[float], None] = time.sleep,
        **settings: Unpack[GrpcSettings],
    ) -> None:
        self._grpc = GrpcTransport(target, api_key, channel=channel, credentials=credentials, sleep=sleep, **settings)
        super().__init__(self._grpc)
        self.target = target

    def __repr__(self) -> str:
        return f"GrpcClient(target={self.target!r})"

    # ---- deprecated -----------------------------------------------------------------------------------------

    def get(self, job_id: str, *, with_result: bool = True) -> JobPublic:
        """Deprecated: ``job(id).status()``. The job now (``GetJob``)."""
        core.deprecated("GrpcClient.get(id)", "GrpcClient.job(id).status()")
        return self._grpc.job(job_id, with_result)

    def cancel(self, job_id: str) -> JobPublic:
        """Deprecated: ``job(id).cancel()``. Ask the service to cancel the job (``CancelJob``)."""
        core.deprecated("GrpcClient.cancel(id)", "GrpcClient.job(id).cancel()")
        return self._grpc.cancel(job_id)

    def watch(
        self, job_id: str, *, timeout: float | None = None, cancel_on_disconnect: bool = False
    ) -> Iterator[JobPublic]:
        """Deprecated: ``job(id).events()``. The job on every change (``WatchJob``)."""
        core.deprecated("GrpcClient.watch(id)", "GrpcClient.job(id).events()")
        return self._grpc.events(job_id, timeout, cancel_on_disconnect)
