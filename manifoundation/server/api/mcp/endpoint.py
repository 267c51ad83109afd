"""``/mcp`` on the service: authorize each request as ``/v1`` does, then hand it to the MCP SDK's app, which is
started on first use (importing the SDK costs about a second: `mani serve` does not pay it until an agent calls).

The SDK's app and its session manager live in one task (`McpHost._serve`: an anyio task group must be left by the
task that entered it) from the first ``/mcp`` request to the app's shutdown (`McpHost.close`, from the lifespan).

A ``GET /mcp`` is a session's event stream, which the SDK keeps open for as long as the client stays: each key may
hold ``MANI_MCP_MAX_STREAMS`` at once (429 beyond), and each is ended after ``MANI_MCP_STREAM_MAX_S`` by telling
the SDK's response that the client left (a client that still listens opens a new one, as SSE clients do).

A ``POST /mcp`` body is parsed by the SDK on the event loop: bodies are limited to ``MANI_MCP_MAX_BODY_BYTES`` (413
before reading, when declared larger), and a large one (over ``MANI_PARSE_OFFLOAD_BYTES``, or of unknown length)
holds one of the service's large-body slots while the SDK reads and parses it, so that a few of them at once cannot
stall every other request.
"""

from __future__ import annotations

import asyncio
import contextlib
import importlib
import time
from collections import Counter
from typing import Any

from starlette.requests import Request
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from manifoundation.server.api.deps import authorize
from manifoundation.server.api.encoding import respond
from manifoundation.server.api.errors import PayloadTooLarge, RateLimited, Unavailable, from_exception

PATH = "/mcp"
CALLER_KEY = "mani_caller"
"""Where `McpEndpoint` leaves the request's `Caller` in the ASGI scope's state for the tools."""


class McpHost:
    """The MCP SDK's ASGI app, started on first use and stopped with the service."""

    def __init__(self, state: Any) -> None:
        self.state = state
        self._task: asyncio.Task[None] | None = None
        self._ready = asyncio.Event()
        self._stop = asyncio.Event()
        self._app: ASGIApp | None = None
        self._failure: BaseException | None = None

    async def app(self) -> ASGIApp:
        """The running app (started now if it is not yet)."""
        if getattr(self.state, "shutting_down", False) or self._stop.is_set():
            raise Unavailable("the service is shutting down")
        if self._task is None:
            self._task = asyncio.create_task(self._serve(), name="mcp-streamable-http")
        await self._ready.wait()
        if self._app is None:
            raise Unavailable(f"the MCP server did not start: {self._failure}")
        return self._app

    async def _serve(self) -> None:
        try:
            http = await asyncio.to_thread(
                importlib.import_module, "manifoundation.server.api.mcp.http"
            )  # off the event loop
            server, app = http.build_app(self.state)
            async with server.session_manager.run():
                self._app = app
                self._ready.set()
                await self._stop.wait()
        except Exception as exc:  # answered as 503 to every caller, never a crash of the service
            self._failure = exc
        finally:
            self._app = None
            self._ready.set()

    async def close(self) -> None:
        """Stop the app (the lifespan calls this at shutdown)."""
        self._stop.set()
        if self._task is not None:
            with contextlib.suppress(asyncio.CancelledError):
                await self._task


class McpEndpoint:
    """The ASGI app behind the ``/mcp`` route: the same keys and limits as ``/v1``, then the SDK's app."""

    def __init__(self, state: Any) -> None:
        self.state = state
        self.streams: Counter[str | None] = Counter()
        """Open event streams per tenant (None: the service runs without keys)."""

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        request = Request(scope, receive)
        stream = scope.get("method") == "GET"
        async with contextlib.AsyncExitStack() as held:
            try:
                caller = await authorize(request, self.state.settings)
                self._check(caller.tenant, stream, _declared_length(request))
                if not stream and self.state.bodies.large(_declared_length(request)):
                    await held.enter_async_context(self.state.bodies.slot())  # 503 after MANI_BODY_TIMEOUT
                app = await self.state.mcp.app()
            except Exception as exc:
                error = from_exception(exc)
                await respond(request, error.body(), status=error.status, headers=error.headers)(scope, receive, send)
                return
            scope.setdefault("state", {})[CALLER_KEY] = caller
            if not stream:
                await app(scope, receive, send)
                return
            self.streams[caller.tenant] += 1
            try:
                ending = _EndingStream(receive, send, self.state.settings.mcp_stream_max_s)
                await app(scope, ending.receive, ending.send)
            finally:
                self.streams[caller.tenant] -= 1
                if not self.streams[caller.tenant]:
                    del self.streams[caller.tenant]

    def _check(self, tenant: str | None, stream: bool, declared: int | None) -> None:
        """Refuse a body declared over the MCP limit (413) and an event stream over the key's count (429)."""
        settings = self.state.settings
        if declared is not None and declared > settings.mcp_max_body_bytes:
            raise PayloadTooLarge(
                f"MCP bodies are limited to {settings.mcp_max_body_bytes} bytes (MANI_MCP_MAX_BODY_BYTES); send "
                "large clouds to /v1 (msgpack), or upload a file through `mani mcp` (stdio)"
            )
        if stream and self.streams[tenant] >= settings.mcp_max_streams:
            raise RateLimited(f"at most {settings.mcp_max_streams} open MCP event streams per key "
                              "(MANI_MCP_MAX_STREAMS): close one first", retry_after=5.0)  # fmt: skip


def _declared_length(request: Request) -> int | None:
    """The body's declared length, or None (no or a malformed Content-Length: the SDK's own limit still holds)."""
    value = request.headers.get("content-length")
    return int(value) if value is not None and value.isdigit() else None


class _EndingStream:
    """An event stream's ``receive`` and ``send`` that end it cleanly after ``seconds``: the response's body is
    closed (its last, empty chunk: a client sees the stream end, not a broken connection), then the app is told
    that the client left, which stops it as a disconnect does; whatever it still sends is dropped."""

    def __init__(self, receive: Receive, send: Send, seconds: float) -> None:
        self._receive, self._send = receive, send
        self._deadline = time.monotonic() + seconds
        self._lock = asyncio.Lock()
        self._started = self._ended = False

    async def send(self, message: Message) -> None:
        async with self._lock:
            if self._ended:
                return
            self._started = self._started or message["type"] == "http.response.start"
            if message["type"] == "http.response.body" and not message.get("more_body", False):
                self._ended = True
            await self._send(message)

    async def receive(self) -> Message:
        left = self._deadline - time.monotonic()
        if left > 0:
            try:
                return await asyncio.wait_for(self._receive(), timeout=left)
            except TimeoutError:
                pass
        async with self._lock:
            if self._started and not self._ended:
                self._ended = True
                await self._send({"type": "http.response.body", "body": b"", "more_body": False})
        return {"type": "http.disconnect"}
