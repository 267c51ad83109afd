"""`AsyncGrpcClient`: the SDK over the service's gRPC port, from asyncio code (``grpc.aio``).

The calls, inputs, results, exceptions, deadlines, retries and version handshake of `GrpcClient`, awaited; every
decision lives in `manifoundation.sdk._grpc_core`, shared with it. Needs the ``[grpc]`` extra::

    from manifoundation.sdk.grpc_async_client import AsyncGrpcClient

    async with AsyncGrpcClient("127.0.0.1:50051") as client:
        results = await asyncio.gather(*(client.synthesize(obj, task, "leap") for task in tasks))
        job = await client.submit(obj)
        async for update in job.events():
            print(update.state, update.progress.stage)

A client belongs to the event loop it was made in (a ``grpc.aio`` channel does): make it inside the coroutine that
uses it.
"""

from __future__ import annotations

import asyncio
import itertools
from collections.abc import AsyncIterator, Awaitable, Callable
from typing import Any, Unpack

from manifoundation.sdk.extras import missing_extra

try:
    import grpc
    import grpc.aio
    from google.protobuf.message import Message
except ModuleNotFoundError as exc:  # the [grpc] extra is not installed
    raise missing_extra(exc, "grpc", "AsyncGrpcClient") from exc

from manifoundation.contract import ContactsIn, JobPublic, RobotPublic, SynthesisRequest, SynthesisResult
from manifoundation.contract.plans import PlanRequest, PlanResult
from manifoundation.contract.protos.v1 import manifoundation_pb2 as pb
from manifoundation.contract.protos.v1 import manifoundation_pb2_grpc as pb_grpc
from manifoundation.sdk import _grpc_core as core
from manifoundation.sdk._grpc_core import DEFAULT_TARGET, GrpcBase, GrpcSettings
from manifoundation.sdk.grpc_job import AsyncGrpcJob
from manifoundation.sdk.objects import ObjectLike
from manifoundation.sdk.plans import PoseLike
from manifoundation.sdk.requests import RobotLike
from manifoundation.sdk.tasks import TaskLike

__all__ = ["AsyncGrpcClient", "AsyncGrpcJob"]


class AsyncGrpcClient(GrpcBase):
    """Talk to a ManiFoundation service over gRPC, from asyncio code (many calls in flight on one channel).

    Args:
        target: ``host:port`` of the service's gRPC port.
        api_key: sent as ``authorization: Bearer ...`` metadata (None: no auth).
        credentials: ``grpc.ssl_channel_credentials(...)`` for TLS (None: plaintext).
        sleep: how to wait between retries (default `asyncio.sleep`; tests may record instead).
        settings: ``timeout``, ``retries``, ``max_message_bytes``, as `GrpcClient`'s.
    """

    def __init__(
        self,
        target: str = DEFAULT_TARGET,
        api_key: str | None = None,
        *,
        credentials: grpc.ChannelCredentials | None = None,
        sleep: Callable[[float], Awaitable[None]] = asyncio.sleep,
        **settings: Unpack[GrpcSettings],
    ) -> None:
        super().__init__(target, api_key, **settings)
        if credentials is None:
            self._channel = grpc.aio.insecure_channel(target, options=self.options)
        else:
            self._channel = grpc.aio.secure_channel(target, credentials, options=self.options)
        self._stub = pb_grpc.ManiFoundationStub(self._channel)
        self._sleep = sleep

    async def close(self) -> None:
        """Close the channel (calls still in flight are cancelled)."""
        await self._channel.close()

    async def __aenter__(self) -> AsyncGrpcClient:
        return self

    async def __aexit__(self, *exc: object) -> None:
        await self.close()

    # ---- synthesis ------------------------------------------------------------------------------------------

    async def synthesize(
        self,
        object: ObjectLike | SynthesisRequest,
        task: TaskLike = "force_closure",
        robot: RobotLike = "leap",
        *,
        contacts: ContactsIn | dict[str, Any] | None = None,
        **options: Any,
    ) -> SynthesisResult:
        """Synthesise and wait for the answer (``Synthesize``, its deadline the request's ``options.timeout``).

        Raises:
            ValidationError, TimeoutError (naming the expired job), JobFailed: as `GrpcClient.synthesize`.
        """
        request, message = core.synthesis(object, task, robot, contacts, options)
        reply = await self._unary(self._stub.Synthesize, message, timeout=request.options.timeout, idempotent=False)
        return core.as_result(reply)

    async def submit(
        self,
        object: ObjectLike | SynthesisRequest,
        task: TaskLike = "force_closure",
        robot: RobotLike = "leap",
        *,
        contacts: ContactsIn | dict[str, Any] | None = None,
        **options: Any,
    ) -> AsyncGrpcJob:
        """Queue a synthesis and return at once with its `AsyncGrpcJob` (same arguments as `synthesize`)."""
        _, message = core.synthesis(object, task, robot, contacts, options)
        return AsyncGrpcJob(self, (await self._unary(self._stub.SubmitJob, message, idempotent=False)).id)

    async def submit_plan(
        self,
        object: ObjectLike | PlanRequest,
        start: PoseLike | None = None,
        waypoints: list[PoseLike] | None = None,
        robot: RobotLike = "allegro",
        **fields: Any,
    ) -> AsyncGrpcJob:
        """Queue a manipulation plan and return at once with its `AsyncGrpcJob`; see `GrpcClient.submit_plan`."""
        _, message = core.planning(object, start, waypoints, robot, fields)
        return AsyncGrpcJob(self, (await self._unary(self._stub.SubmitPlan, message, idempotent=False)).id)

    async def plan(
        self,
        object: ObjectLike | PlanRequest,
        start: PoseLike | None = None,
        waypoints: list[PoseLike] | None = None,
        robot: RobotLike = "allegro",
        *,
        wait: float | None = None,
        **fields: Any,
    ) -> PlanResult:
        """Plan a manipulation and wait for it; arguments, default ``wait`` and errors as `GrpcClient.plan`."""
        request, _ = core.planning(object, start, waypoints, robot, fields)
        job = await self.submit_plan(request)
        return await job.plan_result(core.plan_wait(request, wait))

    def job(self, job_id: str) -> AsyncGrpcJob:
        """A handle on an existing job; see `GrpcClient.job`."""
        return AsyncGrpcJob(self, job_id)

    async def get(self, job_id: str, *, with_result: bool = True) -> JobPublic:
        """The job now (``GetJob``); see `GrpcClient.get`."""
        return core.as_job(await self._unary(self._stub.GetJob, core.get_job(job_id, with_result)))

    async def cancel(self, job_id: str) -> JobPublic:
        """Ask the service to cancel the job (``CancelJob``); see `GrpcClient.cancel`."""
        return core.as_job(await self._unary(self._stub.CancelJob, core.job_ref(job_id)))

    async def watch(
        self, job_id: str, *, timeout: float | None = None, cancel_on_disconnect: bool = False
    ) -> AsyncIterator[JobPublic]:
        """The job on every change of state or stage, ending with it in full once it finished (as
        `GrpcClient.watch`: ``timeout`` for the whole stream; `TimeoutError` when the job had not ended by then)."""
        request = core.watch_job(job_id, cancel_on_disconnect)
        call = self._stub.WatchJob(request, timeout=timeout, metadata=self.metadata)
        with self.following(call, job_id, timeout):
            self.check(await call.initial_metadata())
            async for message in call:
                job = core.as_job(message)
                yield job
                if job.state.terminal:
                    return

    # ---- robots ---------------------------------------------------------------------------------------------

    async def robots(self) -> list[RobotPublic]:
        """The hands this key may use (``ListRobots``); see `GrpcClient.robots`."""
        return core.as_robots(await self._unary(self._stub.ListRobots, pb.ListRobotsRequest()))

    # ---- plumbing -------------------------------------------------------------------------------------------

    async def _unary(self, rpc: Any, request: Message, *, timeout: float | None = None, idempotent: bool = True) -> Any:
        """One awaited unary call, retried as `GrpcClient`'s (`GrpcBase.next_delay` decides); its answer."""
        for attempt in itertools.count():
            call = rpc(request, timeout=timeout or self.timeout, metadata=self.metadata)
            try:
                reply = await call
            except grpc.RpcError as exc:
                await self._sleep(self.next_delay(attempt, exc, idempotent))
                continue
            self.check(await call.initial_metadata())
            return reply
        raise AssertionError("unreachable")
