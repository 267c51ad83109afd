"""`Client`: the synchronous SDK over HTTP, `SyncAPI`'s calls over an `HttpTransport`.

The calls and their logic live in `manifoundation.sdk._api` (shared with `GrpcClient`); every request is built and
every answer read in `BaseClient` (`manifoundation.sdk._core`, shared with `AsyncClient`). `HttpTransport` only
sends, retries and sleeps.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
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
from manifoundation.sdk._api import Batch, Job, SyncAPI, Transport
from manifoundation.sdk._core import BaseClient, Call, HttpSettings
from manifoundation.sdk.errors import TimeoutError
from manifoundation.sdk.sse import SSEDecoder
from manifoundation.sdk.tracking import JOB_EVENT_TYPES, parse_event

__all__ = ["Batch", "Client", "HttpTransport", "Job"]

T = TypeVar("T")


class HttpTransport(BaseClient, Transport):
    """`Client`'s transport: each call one HTTP exchange through an ``httpx.Client``, with retries (429/503 and
    connection errors, backoff + jitter, Retry-After honoured); requests built and answers read by `BaseClient`.

    Args:
        base_url, api_key, settings: see `BaseClient`.
        transport: an ``httpx.BaseTransport`` to send through (tests: the app in process).
        sleep: how to wait between retries and polls.
    """

    def __init__(
        self,
        base_url: str | None = None,
        api_key: str | None = None,
        *,
        transport: httpx.BaseTransport | None = None,
        sleep: Callable[[float], None] = time.sleep,
        **settings: Unpack[HttpSettings],
    ) -> None:
        super().__init__(base_url, api_key, **settings)
        self._http = httpx.Client(transport=transport, timeout=self.timeout)
        self._sleep = sleep

    def sleep(self, seconds: float) -> None:
        """Wait between retries and polls."""
        self._sleep(seconds)

    def close(self) -> None:
        """Close the connection pool."""
        self._http.close()

    def send(self, request: httpx.Request, *, stream: bool = False, retry: bool = True) -> httpx.Response:
        """Send with retries; the answer that stands (read in full when it is an error)."""
        attempt = 0 if retry else self.retry_policy.max_retries
        while True:
            try:
                response = self._http.send(request, stream=stream)
            except httpx.TransportError as exc:
                delay = self.retry_delay(attempt, request, exc=exc)
                if delay is None:
                    raise self.transport_error(request, exc) from exc
            else:
                delay = self.retry_delay(attempt, request, response=response)
                if delay is None:
                    if stream and not response.is_success:
                        response.read()
                    return response
                response.close()
            self._sleep(delay)
            attempt += 1

    def run(self, call: Call[T]) -> T:
        """Send one call and read its answer."""
        return call.parse(self.send(call.request, retry=call.retry))

    # ---- the calls (`Transport`) ----------------------------------------------------------------------------

    def synthesize(self, request: SynthesisRequest) -> SynthesisResult | JobCreated:
        return self.run(self._call_synthesize(request))

    def submit(self, request: SynthesisRequest) -> str:
        return self.run(self._call_submit(request)).id

    def submit_plan(self, request: PlanRequest) -> str:
        return self.run(self._call_submit_plan(request)).id

    def job(self, job_id: str, with_result: bool = True) -> JobPublic:
        return self.run(self._call_job(job_id))

    def cancel(self, job_id: str) -> JobPublic:
        return self.run(self._call_cancel(job_id))

    def events(self, job_id: str, timeout: float | None) -> Iterator[JobPublic]:
        """``GET /v1/jobs/{id}/events`` (Server-Sent Events); ``timeout``: the longest silence between two."""
        request = self.build_request(
            "GET", f"/v1/jobs/{job_id}/events", accept="text/event-stream", read_timeout=timeout
        )
        response = self.send(request, stream=True)
        try:
            self.raise_for_status(response)
            decoder = SSEDecoder()
            for line in response.iter_lines():
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
            response.close()

    def submit_batch(self, requests: list[SynthesisRequest]) -> str:
        return self.run(self._call_submit_batch(requests))

    def batch(self, batch_id: str, offset: int, limit: int) -> BatchPublic:
        return self.run(self._call_batch(batch_id, offset, limit))

    def jobs(self, limit: int) -> list[JobPublic]:
        return self.run(self._call_jobs(limit))

    def robots(self) -> list[RobotPublic]:
        return self.run(self._call_robots())

    def robot(self, name: str) -> RobotPublic:
        return self.run(self._call_robot(name))

    def register_robot(self, body: RobotRegister) -> RobotPublic:
        return self.run(self._call_register_robot(body))

    def robot_preview(self, name: str) -> RobotPreview:
        return self.run(self._call_robot_preview(name))

    def delete_robot(self, name: str) -> None:
        self.run(self._call_delete_robot(name))

    def health(self) -> HealthPublic:
        return self.run(self._call_health())

    def ready(self) -> ReadyPublic:
        return self.run(self._call_ready())


class Client(SyncAPI):
    """Talk to a ManiFoundation service over HTTP from synchronous code.

    Example::

        from manifoundation.sdk import Client, object_from_file

        with Client("http://127.0.0.1:8000") as client:
            result = client.synthesize(object_from_file("examples/data/box.npz"), "force_closure", "leap")
            print(result.best.quality)

    Every call of the one surface (`manifoundation.sdk._api.SyncAPI`, the same as `GrpcClient`'s): ``synthesize``,
    ``submit``, ``submit_plan``, ``plan``, ``job`` (a `Job`), ``submit_batch`` and ``batch`` (a `Batch`),
    ``robots``, ``robot``, ``register_robot``, ``add_robot``, and the ones only HTTP serves: ``jobs``,
    ``robot_preview``, ``delete_robot``, ``health``, ``ready``. Close it with ``close()`` or a ``with`` block.

    Args:
        base_url, api_key, settings (``timeout``, ``retries``, ``encoding``, ``headers``, ``poll_interval``): see
            `BaseClient`.
        transport: an ``httpx.BaseTransport`` to send through (tests: the app in process).
        sleep: how to wait between retries and polls (tests may pass a no-op).
    """

    def __init__(
        self,
        base_url: str | None = None,
        api_key: str | None = None,
        *,
        transport: httpx.BaseTransport | None = None,
        sleep: Callable[[float], None] = time.sleep,
        **settings: Unpack[HttpSettings],
    ) -> None:
        http = HttpTransport(base_url, api_key, transport=transport, sleep=sleep, **settings)
        super().__init__(http)
        self.base_url = http.base_url
        self.encoding = http.encoding
        self.poll_interval = http.poll_interval

    def __repr__(self) -> str:
        return f"Client(base_url={self.base_url!r}, encoding={self.encoding!r})"
