"""`AsyncClient`: the asyncio SDK over HTTP, `AsyncAPI`'s calls over an `AsyncHttpTransport`.

The calls and their logic live in `manifoundation.sdk._async_api` (shared with `AsyncGrpcClient`); every request
is built and every answer read in `BaseClient` (`manifoundation.sdk._core`, shared with `Client`).
`AsyncHttpTransport` only sends, retries and sleeps.
"""

from __future__ import annotations

import asyncio
from collections.abc import AsyncIterator, Awaitable, Callable
from typing import TypeVar, Unpack

import httpx

from manifoundation.contract import (
    BatchPublic,
    HealthPublic,
    JobCreated,
    JobPublic,
    PlanRequest,
    ReadyPublic,
    RobotPreview,
    RobotPublic,
    RobotRegister,
    SynthesisRequest,
    SynthesisResult,
)
from manifoundation.sdk._async_api import AsyncAPI, AsyncBatch, AsyncJob, AsyncTransport
from manifoundation.sdk._core import BaseClient, Call, HttpSettings
from manifoundation.sdk.errors import TimeoutError
from manifoundation.sdk.sse import SSEDecoder
from manifoundation.sdk.tracking import JOB_EVENT_TYPES, parse_event

__all__ = ["AsyncBatch", "AsyncClient", "AsyncHttpTransport", "AsyncJob"]

T = TypeVar("T")


class AsyncHttpTransport(BaseClient, AsyncTransport):
    """`AsyncClient`'s transport: `manifoundation.sdk.client.HttpTransport`, awaited on an ``httpx.AsyncClient``.

    Args:
        base_url, api_key, settings: see `BaseClient`.
        transport: an ``httpx.AsyncBaseTransport`` to send through (tests: the app in process).
        sleep: how to wait between retries and polls.
    """

    def __init__(
        self,
        base_url: str | None = None,
        api_key: str | None = None,
        *,
        transport: httpx.AsyncBaseTransport | None = None,
        sleep: Callable[[float], Awaitable[None]] = asyncio.sleep,
        **settings: Unpack[HttpSettings],
    ) -> None:
        super().__init__(base_url, api_key, **settings)
        self._http = httpx.AsyncClient(transport=transport, timeout=self.timeout)
        self._sleep = sleep

    async def sleep(self, seconds: float) -> None:
        """Wait between retries and polls."""
        await self._sleep(seconds)

    async def aclose(self) -> None:
        """Close the connection pool."""
        await self._http.aclose()

    async def send(self, request: httpx.Request, *, stream: bool = False, retry: bool = True) -> httpx.Response:
        """Send with retries (429/503 and connection errors, backoff + jitter, Retry-After honoured)."""
        attempt = 0 if retry else self.retry_policy.max_retries
        while True:
            try:
                response = await self._http.send(request, stream=stream)
            except httpx.TransportError as exc:
                delay = self.retry_delay(attempt, request, exc=exc)
                if delay is None:
                    raise self.transport_error(request, exc) from exc
            else:
                delay = self.retry_delay(attempt, request, response=response)
                if delay is None:
                    if stream and not response.is_success:
                        await response.aread()
                    return response
                await response.aclose()
            await self._sleep(delay)
            attempt += 1

    async def run(self, call: Call[T]) -> T:
        """Send one call and read its answer."""
        return call.parse(await self.send(call.request, retry=call.retry))

    # ---- the calls (`AsyncTransport`) -----------------------------------------------------------------------

    async def synthesize(self, request: SynthesisRequest) -> SynthesisResult | JobCreated:
        return await self.run(self._call_synthesize(request))

    async def submit(self, request: SynthesisRequest) -> str:
        return (await self.run(self._call_submit(request))).id

    async def submit_plan(self, request: PlanRequest) -> str:
        return (await self.run(self._call_submit_plan(request))).id

    async def job(self, job_id: str, with_result: bool = True) -> JobPublic:
        return await self.run(self._call_job(job_id))

    async def cancel(self, job_id: str) -> JobPublic:
        return await self.run(self._call_cancel(job_id))

    async def events(self, job_id: str, timeout: float | None) -> AsyncIterator[JobPublic]:
        """``GET /v1/jobs/{id}/events`` (Server-Sent Events); ``timeout``: the longest silence between two."""
        request = self.build_request(
            "GET", f"/v1/jobs/{job_id}/events", accept="text/event-stream", read_timeout=timeout
        )
        response = await self.send(request, stream=True)
        try:
            self.raise_for_status(response)
            decoder = SSEDecoder()
            async for line in response.aiter_lines():
                event = decoder.decode(line)
                if event is None or not event.data or event.event not in JOB_EVENT_TYPES:
                    continue
                job = parse_event(event.data)
                yield job
                if job.state.terminal:
                    return
        except httpx.TimeoutException as exc:
            raise TimeoutError(f"no progress from job {job_id} in {timeout} s", job_id=job_id) from exc
        finally:
            await response.aclose()

    async def submit_batch(self, requests: list[SynthesisRequest]) -> str:
        return await self.run(self._call_submit_batch(requests))

    async def batch(self, batch_id: str, offset: int, limit: int) -> BatchPublic:
        return await self.run(self._call_batch(batch_id, offset, limit))

    async def jobs(self, limit: int) -> list[JobPublic]:
        return await self.run(self._call_jobs(limit))

    async def robots(self) -> list[RobotPublic]:
        return await self.run(self._call_robots())

    async def robot(self, name: str) -> RobotPublic:
        return await self.run(self._call_robot(name))

    async def register_robot(self, body: RobotRegister) -> RobotPublic:
        return await self.run(self._call_register_robot(body))

    async def robot_preview(self, name: str) -> RobotPreview:
        return await self.run(self._call_robot_preview(name))

    async def delete_robot(self, name: str) -> None:
        await self.run(self._call_delete_robot(name))

    async def health(self) -> HealthPublic:
        return await self.run(self._call_health())

    async def ready(self) -> ReadyPublic:
        return await self.run(self._call_ready())


class AsyncClient(AsyncAPI):
    """Talk to a ManiFoundation service over HTTP from asyncio code (e.g. many requests in flight at once).

    Example::

        async with AsyncClient("http://127.0.0.1:8000") as client:
            results = await asyncio.gather(*(client.synthesize(obj, task, "leap") for task in tasks))

    The calls of `Client`, awaited (the one surface: `manifoundation.sdk._async_api.AsyncAPI`, the same as
    `AsyncGrpcClient`'s); ``job`` gives an `AsyncJob`, ``submit_batch`` and ``batch`` an `AsyncBatch`. Close it with
    ``await client.aclose()`` or an ``async with`` block.

    Args:
        base_url, api_key, settings (``timeout``, ``retries``, ``encoding``, ``headers``, ``poll_interval``): see
            `BaseClient`.
        transport: an ``httpx.AsyncBaseTransport`` to send through (tests: the app in process).
        sleep: how to wait between retries and polls.
    """

    def __init__(
        self,
        base_url: str | None = None,
        api_key: str | None = None,
        *,
        transport: httpx.AsyncBaseTransport | None = None,
        sleep: Callable[[float], Awaitable[None]] = asyncio.sleep,
        **settings: Unpack[HttpSettings],
    ) -> None:
        http = AsyncHttpTransport(base_url, api_key, transport=transport, sleep=sleep, **settings)
        super().__init__(http)
        self.base_url = http.base_url
        self.encoding = http.encoding
        self.poll_interval = http.poll_interval

    def __repr__(self) -> str:
        return f"AsyncClient(base_url={self.base_url!r}, encoding={self.encoding!r})"
