"""`AsyncGrpcClient`: the SDK over the service's gRPC port, from asyncio code (``grpc.aio``).

The one asyncio surface (`manifoundation.sdk._async_api.AsyncAPI`, the same as `AsyncClient`'s) over an
`AsyncGrpcTransport`; deadlines, retries, errors and the version handshake as `GrpcClient`'s, decided once in
`manifoundation.sdk._grpc_core`. Needs the ``[grpc]`` extra::

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
from collections.abc import AsyncIterator, Awaitable, Callable, Iterator
from typing import Protocol, Unpack

from manifoundation.sdk.extras import missing_extra

try:
    import grpc
    import grpc.aio
    from google.protobuf.message import Message
except ModuleNotFoundError as exc:  # the [grpc] extra is not installed
    raise missing_extra(exc, "grpc", "AsyncGrpcClient") from exc

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
from manifoundation.sdk._async_api import AsyncAPI, AsyncTransport
from manifoundation.sdk._grpc_core import DEFAULT_TARGET, GrpcBase, GrpcSettings
from manifoundation.sdk.grpc_job import AsyncGrpcJob

__all__ = ["AsyncGrpcClient", "AsyncGrpcJob", "AsyncGrpcTransport"]


class AsyncUnaryRpc(Protocol):
    """An awaited unary method of a ``grpc.aio`` stub."""

    def __call__(
        self, request: Message | Iterator[Message], *, timeout: float | None, metadata: tuple[tuple[str, str], ...]
    ) -> grpc.aio.UnaryUnaryCall | grpc.aio.StreamUnaryCall: ...


class AsyncGrpcTransport(GrpcBase, AsyncTransport):
    """`AsyncGrpcClient`'s transport: `manifoundation.sdk.grpc_client.GrpcTransport`, awaited on a ``grpc.aio``
    channel (``channel``: one to send through instead of one made for ``target``; the transport closes it)."""

    streams = True

    def __init__(
        self,
        target: str = DEFAULT_TARGET,
        api_key: str | None = None,
        *,
        channel: grpc.aio.Channel | None = None,
        credentials: grpc.ChannelCredentials | None = None,
        sleep: Callable[[float], Awaitable[None]] = asyncio.sleep,
        **settings: Unpack[GrpcSettings],
    ) -> None:
        super().__init__(target, api_key, **settings)
        if channel is None:
            if credentials is None:
                channel = grpc.aio.insecure_channel(target, options=self.options)
            else:
                channel = grpc.aio.secure_channel(target, credentials, options=self.options)
        self._channel = channel
        self._stub = pb_grpc.ManiFoundationStub(channel)
        self._sleep = sleep

    async def sleep(self, seconds: float) -> None:
        """Wait between retries."""
        await self._sleep(seconds)

    async def aclose(self) -> None:
        """Close the channel (calls still in flight are cancelled)."""
        await self._channel.close()

    async def unary(
        self, rpc: AsyncUnaryRpc, request: core.Request, *, timeout: float | None = None, idempotent: bool = True
    ) -> Message:
        """One awaited unary (or client-streaming) call, retried as `GrpcBase.next_delay` decides; its answer."""
        for attempt in itertools.count():
            call = rpc(core.sent(request), timeout=timeout or self.timeout, metadata=self.metadata)
            try:
                reply: Message = await call
            except grpc.RpcError as exc:
                await self._sleep(self.next_delay(attempt, exc, idempotent))
                continue
            self.check(await call.initial_metadata())
            return reply
        raise AssertionError("unreachable")

    # ---- the calls (`AsyncTransport`) -----------------------------------------------------------------------

    async def synthesize(self, request: SynthesisRequest) -> SynthesisResult:
        message = core.synthesis_message(request)
        reply = await self.unary(self._stub.Synthesize, message, timeout=request.options.timeout, idempotent=False)
        return core.as_result(reply)

    async def submit(self, request: SynthesisRequest) -> str:
        return core.created_id(
            await self.unary(self._stub.SubmitJob, core.synthesis_message(request), idempotent=False)
        )

    async def submit_plan(self, request: PlanRequest) -> str:
        return core.created_id(await self.unary(self._stub.SubmitPlan, core.plan_message(request), idempotent=False))

    async def job(self, job_id: str, with_result: bool = True) -> JobPublic:
        return core.as_job(await self.unary(self._stub.GetJob, core.get_job(job_id, with_result)))

    async def cancel(self, job_id: str) -> JobPublic:
        return core.as_job(await self.unary(self._stub.CancelJob, core.job_ref(job_id)))

    async def events(
        self, job_id: str, timeout: float | None, cancel_on_disconnect: bool = False
    ) -> AsyncIterator[JobPublic]:
        """``WatchJob``, as `GrpcTransport.events`."""
        call = self._stub.WatchJob(
            core.watch_job(job_id, cancel_on_disconnect), timeout=timeout, metadata=self.metadata
        )
        with self.following(call, f"job {job_id}", timeout, job_id):
            self.check(await call.initial_metadata())
            async for message in call:
                job = core.as_job(message)
                yield job
                if job.state.terminal:
                    return

    async def submit_batch(self, requests: list[SynthesisRequest]) -> str:
        rpc, request = core.batch_request(self._stub, requests)
        return core.as_batch(await self.unary(rpc, request, idempotent=False)).id

    async def batch(self, batch_id: str, offset: int, limit: int) -> BatchPublic:
        return core.as_batch(await self.unary(self._stub.GetBatch, core.get_batch(batch_id, offset, limit)))

    async def batch_items(self, batch_id: str, timeout: float | None) -> AsyncIterator[BatchItem]:
        """``WatchBatch``, as `GrpcTransport.batch_items`."""
        call = self._stub.WatchBatch(core.batch_ref(batch_id), timeout=timeout, metadata=self.metadata)
        with self.following(call, f"batch {batch_id}", timeout):
            self.check(await call.initial_metadata())
            async for message in call:
                yield core.as_batch_item(message)

    async def robots(self) -> list[RobotPublic]:
        return core.as_robots(await self.unary(self._stub.ListRobots, pb.ListRobotsRequest()))

    async def register_robot(self, body: RobotRegister) -> RobotPublic:
        return core.as_robot(await self.unary(self._stub.RegisterRobot, core.robot_message(body), idempotent=False))


class AsyncGrpcClient(AsyncAPI):
    """Talk to a ManiFoundation service over gRPC, from asyncio code (many calls in flight on one channel): the
    calls of `AsyncClient`, with `GrpcClient`'s transport rules.

    ``jobs``, ``robot_preview``, ``delete_robot``, ``health`` and ``ready`` raise `NeedsHttp` (no RPC; see
    `GrpcClient`). Close it with ``await client.aclose()`` or ``async with``. Deprecated (one release):
    ``close()`` (use ``aclose()``), ``get(id)``, ``cancel(id)``, ``watch(id)`` (use ``job(id).status()``,
    ``.cancel()``, ``.events()``).

    Args:
        target: ``host:port`` of the service's gRPC port.
        api_key: sent as ``authorization: Bearer ...`` metadata (None: no auth).
        channel: a ``grpc.aio.Channel`` to send through instead of one made for ``target`` (the client closes it).
        credentials: ``grpc.ssl_channel_credentials(...)`` for TLS (None: plaintext).
        sleep: how to wait between retries (default `asyncio.sleep`; tests may record instead).
        settings: ``timeout``, ``retries``, ``max_message_bytes``, as `GrpcClient`'s.
    """

    _job_type = AsyncGrpcJob

    def __init__(
        self,
        target: str = DEFAULT_TARGET,
        api_key: str | None = None,
        *,
        channel: grpc.aio.Channel | None = None,
        credentials: grpc.ChannelCredentials | None = None,
        sleep: Callable[[float], Awaitable[None]] = asyncio.sleep,
        **settings: Unpack[GrpcSettings],
    ) -> None:
        self._grpc = AsyncGrpcTransport(
            target, api_key, channel=channel, credentials=credentials, sleep=sleep, **settings
        )
        super().__init__(self._grpc)
        self.target = target

    def __repr__(self) -> str:
        return f"AsyncGrpcClient(target={self.target!r})"

    # ---- deprecated -----------------------------------------------------------------------------------------

    async def close(self) -> None:
        """Deprecated: ``aclose()`` (as httpx's async client). Close the channel."""
        core.deprecated("AsyncGrpcClient.close()", "AsyncGrpcClient.aclose()")
        await self.aclose()

    async def get(self, job_id: str, *, with_result: bool = True) -> JobPublic:
        """Deprecated: ``job(id).status()``. The job now (``GetJob``)."""
        core.deprecated("AsyncGrpcClient.get(id)", "AsyncGrpcClient.job(id).status()")
        return await self._grpc.job(job_id, with_result)

    async def cancel(self, job_id: str) -> JobPublic:
        """Deprecated: ``job(id).cancel()``. Ask the service to cancel the job (``CancelJob``)."""
        core.deprecated("AsyncGrpcClient.cancel(id)", "AsyncGrpcClient.job(id).cancel()")
        return await self._grpc.cancel(job_id)

    def watch(
        self, job_id: str, *, timeout: float | None = None, cancel_on_disconnect: bool = False
    ) -> AsyncIterator[JobPublic]:
        """Deprecated: ``job(id).events()``. The job on every change (``WatchJob``)."""
        core.deprecated("AsyncGrpcClient.watch(id)", "AsyncGrpcClient.job(id).events()")
        return self._grpc.events(job_id, timeout, cancel_on_disconnect)
