"""The real service app in the test process, behind httpx transports that can also script answers.

`InProcessService` builds ``manifoundation.server.api.app.create_app(Settings(...), queue=ScriptedQueue())`` on first
use and runs it as a server would (its lifespan started once, on one event loop of its own) but in a thread of the test
process and without a socket: requests reach it through ``httpx.ASGITransport``. `transport` (for `Client`) and
`async_transport` (for `AsyncClient`, whose event loop is another one) record every request in ``seen`` and, while
``script`` has steps, answer the next one instead of the app: an ``httpx.Response`` to return, or an exception to
raise (transport faults, and answers the app is not made to give).

Responses come back whole (an event stream once the job has ended), as from `starlette.testclient`.
"""

from __future__ import annotations

import asyncio
import concurrent.futures
import threading
from collections.abc import Coroutine
from typing import Any, TypeVar

import httpx
from fastapi import FastAPI
from starlette.types import Message

from manifoundation.server.api.app import create_app
from manifoundation.server.api.settings import Settings
from tests.client.sdk.queues import ScriptedQueue

T = TypeVar("T")

DEFAULTS: dict[str, Any] = {
    "rate_limit_per_s": 0,  # off: the tests send bursts; the ones about 429s script them or fill the queue
    "sync_wait_max": 0.1,  # a held job turns POST /v1/synthesize into a 202 quickly
    "sse_interval": 0.01,
    "log_level": "WARNING",
}
"""Settings of every test app (`InProcessService.configure` adds to them)."""


class InProcessService:
    """The real app over a `ScriptedQueue`, started on first use; `close` stops it.

    Attributes:
        queue: the queue behind the app (tests set how its jobs end and read what the app submitted).
        script: answers given, in order, before the app is asked: ``httpx.Response`` or an exception to raise.
        seen: every request sent, scripted or not.
    """

    def __init__(self) -> None:
        self.queue = ScriptedQueue()
        self.script: list[httpx.Response | Exception] = []
        self.seen: list[httpx.Request] = []
        self._settings = dict(DEFAULTS)
        self._app: FastAPI | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._thread: threading.Thread | None = None
        self._lifespan: _Lifespan | None = None

    def configure(self, **settings: Any) -> None:
        """Set `manifoundation.server.api.settings.Settings` fields of the app; only before its first request."""
        if self._app is not None:
            raise RuntimeError("the app is already running: configure it before the first request")
        self._settings.update(settings)

    def start(self) -> FastAPI:
        """The running app: built, and its lifespan started, on the first call."""
        if self._app is None:
            app = create_app(Settings(**self._settings), queue=self.queue)
            loop = asyncio.new_event_loop()
            thread = threading.Thread(target=loop.run_forever, name="sdk-test-app", daemon=True)
            thread.start()
            self._app, self._loop, self._thread = app, loop, thread
            self._lifespan = _Lifespan(app)
            self._run(self._lifespan.startup(), timeout=30)
        return self._app

    def transport(self) -> httpx.BaseTransport:
        """A transport for `Client`: scripted answers first, then the app (started now if it is not yet)."""
        self.start()
        return _Transport(self)

    def async_transport(self) -> httpx.AsyncBaseTransport:
        """A transport for `AsyncClient`, on any event loop: scripted answers first, then the app."""
        self.start()
        return _AsyncTransport(self)

    def close(self) -> None:
        """Run the app's shutdown and stop its thread (a no-op when it never started)."""
        loop, thread, lifespan = self._loop, self._thread, self._lifespan
        if loop is None or thread is None or lifespan is None:
            return
        try:
            self._run(lifespan.shutdown(), timeout=30)
        finally:
            self._run(_cancel_the_rest(), timeout=30)
            loop.call_soon_threadsafe(loop.stop)
            thread.join(timeout=30)
            loop.close()
            self._app, self._loop, self._thread, self._lifespan = None, None, None, None

    # ---- plumbing -------------------------------------------------------------------------------------------

    def _run(self, coro: Coroutine[Any, Any, T], timeout: float | None) -> T:
        """Run ``coro`` on the app's loop and wait for it here."""
        assert self._loop is not None
        return asyncio.run_coroutine_threadsafe(coro, self._loop).result(timeout)

    def scripted(self, request: httpx.Request) -> httpx.Response | None:
        """Record ``request``; the next scripted answer (raised when it is an exception), or None: ask the app."""
        self.seen.append(request)
        if not self.script:
            return None
        step = self.script.pop(0)
        if isinstance(step, Exception):
            raise step
        return step

    def submit(self, request: httpx.Request) -> concurrent.futures.Future[httpx.Response]:
        """Hand ``request`` to the app on its loop; the future holds its whole answer."""
        assert self._loop is not None and self._app is not None
        return asyncio.run_coroutine_threadsafe(_exchange(httpx.ASGITransport(self._app), request), self._loop)


async def _exchange(asgi: httpx.ASGITransport, request: httpx.Request) -> httpx.Response:
    """The app's answer to ``request``, its body read (on the app's loop)."""
    response = await asgi.handle_async_request(request)
    content = await response.aread()
    return httpx.Response(response.status_code, headers=response.headers, content=content)


def _read_timeout(request: httpx.Request) -> float | None:
    """The request's read timeout (the SDK sets one per call), bounding the whole exchange here."""
    timeout: dict[str, float | None] = request.extensions.get("timeout", {})
    return timeout.get("read")


class _Transport(httpx.BaseTransport):
    def __init__(self, service: InProcessService) -> None:
        self.service = service

    def handle_request(self, request: httpx.Request) -> httpx.Response:
        answer = self.service.scripted(request)
        if answer is not None:
            return answer
        future = self.service.submit(request)
        try:
            return future.result(_read_timeout(request))
        except concurrent.futures.TimeoutError as exc:
            future.cancel()
            raise httpx.ReadTimeout("the app did not answer in time", request=request) from exc


class _AsyncTransport(httpx.AsyncBaseTransport):
    def __init__(self, service: InProcessService) -> None:
        self.service = service

    async def handle_async_request(self, request: httpx.Request) -> httpx.Response:
        answer = self.service.scripted(request)
        if answer is not None:
            return answer
        future = self.service.submit(request)
        try:
            return await asyncio.wait_for(asyncio.wrap_future(future), _read_timeout(request))
        except TimeoutError as exc:
            raise httpx.ReadTimeout("the app did not answer in time", request=request) from exc


class _Lifespan:
    """The ASGI lifespan protocol, spoken to the app as a server does: startup once, later shutdown once."""

    def __init__(self, app: FastAPI) -> None:
        self.app = app
        self._to_app: asyncio.Queue[Message] | None = None
        self._from_app: asyncio.Queue[Message] | None = None
        self._task: asyncio.Task[None] | None = None

    async def startup(self) -> None:
        self._to_app, self._from_app = asyncio.Queue(), asyncio.Queue()
        scope = {"type": "lifespan", "asgi": {"version": "3.0", "spec_version": "2.0"}}
        self._task = asyncio.create_task(self.app(scope, self._to_app.get, self._from_app.put))
        await self._to_app.put({"type": "lifespan.startup"})
        await self._expect("lifespan.startup.complete")

    async def shutdown(self) -> None:
        assert self._to_app is not None and self._task is not None
        await self._to_app.put({"type": "lifespan.shutdown"})
        await self._expect("lifespan.shutdown.complete")
        await self._task

    async def _expect(self, kind: str) -> None:
        assert self._from_app is not None and self._task is not None
        answer = asyncio.ensure_future(self._from_app.get())
        await asyncio.wait({answer, self._task}, return_when=asyncio.FIRST_COMPLETED, timeout=30)
        if not answer.done():
            answer.cancel()
            failed = self._task.done() and not self._task.cancelled()
            raise RuntimeError(f"the app's lifespan sent no {kind}") from (self._task.exception() if failed else None)
        message = answer.result()
        if message["type"] != kind:
            raise RuntimeError(f"the app's lifespan answered {message} instead of {kind}")


async def _cancel_the_rest() -> None:
    """Cancel every task still on the app's loop (e.g. an event stream of a job that never ended)."""
    tasks = [task for task in asyncio.all_tasks() if task is not asyncio.current_task()]
    for task in tasks:
        task.cancel()
    await asyncio.gather(*tasks, return_exceptions=True)
