"""``/mcp`` on the service: authorize each request as ``/v1`` does, then hand it to the MCP SDK's app (started on
first use: `manifoundation.server.api.mcp.host`).

A ``GET /mcp`` is a session's event stream, which the SDK keeps open for as long as the client stays: each key may
hold ``MANI_MCP_MAX_STREAMS`` at once (429 beyond), and each is ended after ``MANI_MCP_STREAM_MAX_S`` by telling
the SDK's response that the client left (a client that still listens opens a new one, as SSE clients do).

A ``POST /mcp`` body is limited to ``MANI_MCP_MAX_BODY_BYTES`` (413 before reading, when declared larger). The SDK
parses bodies on the event loop, so a large one (over ``MANI_PARSE_OFFLOAD_BYTES``, or of unknown length) waits for
one of the service's large-body slots and is decoded in a body process first
(`manifoundation.server.api.mcp.uploads`): an ``upload_object`` call reaches the SDK with its arrays emptied and its
object already validated; any other call goes on as sent up to ``uploads.CALL_MAX_BYTES`` (1 MiB), 413 beyond.
"""

from __future__ import annotations

import asyncio
import contextlib
import time
from collections import Counter

from starlette.requests import Request
from starlette.types import Message, Receive, Scope, Send

from manifoundation.server.api.deps import authorize
from manifoundation.server.api.encoding import respond
from manifoundation.server.api.errors import BadRequest, PayloadTooLarge, RateLimited, Unavailable, from_exception
from manifoundation.server.api.mcp import uploads
from manifoundation.server.api.negotiation import body_chunks, declared_length
from manifoundation.server.api.services import AppServices
from manifoundation.server.worker.heap import HeapTrimmer

PATH = "/mcp"
MAX_DECLARED = 1 << 62
"""No limit on a declared length as `declared_length` parses it: `McpEndpoint._check` names the MCP limit."""
CALLER_KEY = "mani_caller"
"""Where `McpEndpoint` leaves the request's `Caller` in the ASGI scope's state for the tools."""


class McpEndpoint:
    """The ASGI app behind the ``/mcp`` route: the same keys and limits as ``/v1``, then the SDK's app."""

    def __init__(self, services: AppServices) -> None:
        self.services = services
        self.streams: Counter[str | None] = Counter()
        """Open event streams per tenant (None: the service runs without keys)."""
        self.heap = HeapTrimmer()
        """Trims the C heap after large bodies (at most every 2 s): glibc keeps their freed arrays otherwise."""

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        request = Request(scope, receive)
        stream = scope.get("method") == "GET"
        async with contextlib.AsyncExitStack() as held:
            try:
                caller = await authorize(request, self.services.settings)
                declared = declared_length(request, MAX_DECLARED)  # 400 if malformed; its limit: `_check`
                self._check(caller.tenant, stream, declared)
                if stream:  # counted in the same step as the check (no await between): a burst cannot overshoot
                    self.streams[caller.tenant] += 1
                    held.callback(self._closed, caller.tenant)
                body: bytes | None = None
                if not stream and self.services.bodies.large(declared):
                    await held.enter_async_context(self.services.bodies.slot())  # 503 after MANI_BODY_TIMEOUT
                    body = await self._decoded(request, scope)
                if self.services.mcp is None:
                    raise Unavailable("the service is not started")
                app = await self.services.mcp.app()
            except Exception as exc:
                error = from_exception(exc)
                await respond(request, error.body(), status=error.status, headers=error.headers)(scope, receive, send)
                return
            scope.setdefault("state", {})[CALLER_KEY] = caller
            if body is not None:
                scope, receive = _with_body(scope, receive, body)
            if not stream:
                try:
                    await app(scope, receive, send)
                finally:  # the server keeps a connection's last scope until its next request: not the arrays
                    scope["state"].pop(uploads.STAGED_KEY, None)
                if body is not None:  # its arrays were let go (or stored): give glibc's freed pages back
                    self.heap.maybe_trim()
                return
            ending = _EndingStream(receive, send, self.services.settings.mcp_stream_max_s)
            await app(scope, ending.receive, ending.send)

    def _closed(self, tenant: str | None) -> None:
        self.streams[tenant] -= 1
        if not self.streams[tenant]:
            del self.streams[tenant]

    async def _decoded(self, request: Request, scope: Scope) -> bytes:
        """Read a large body into a body process (`stage_upload`); the body the SDK is to read instead. A staged
        upload's object is left in ``scope``'s state. Raises 400 (large and not JSON), 413 (large and not an
        upload, or over the limit), 408 (too slow)."""
        settings = self.services.settings
        chunks = body_chunks(request, settings.mcp_max_body_bytes, settings.body_timeout, settings.body_idle_timeout)
        kind, value = await self.services.bodies.run(uploads.DECODER, chunks, uploads.CALL_MAX_BYTES)
        if kind == "decode":
            raise BadRequest(str(value))
        if kind == "other":
            raise PayloadTooLarge(
                f"MCP calls other than {uploads.TOOL} are limited to {uploads.CALL_MAX_BYTES} bytes (this one: "
                f"{value}); upload the object once and use its object_id"
            )
        if kind == "as_is":
            return bytes(value)
        staged: uploads.Staged = value
        scope.setdefault("state", {})[uploads.STAGED_KEY] = staged
        return staged.call

    def _check(self, tenant: str | None, stream: bool, declared: int | None) -> None:
        """Refuse a body declared over the MCP limit (413) and an event stream over the key's count (429)."""
        settings = self.services.settings
        if declared is not None and declared > settings.mcp_max_body_bytes:
            raise PayloadTooLarge(
                f"MCP bodies are limited to {settings.mcp_max_body_bytes} bytes (MANI_MCP_MAX_BODY_BYTES); send "
                "large clouds to /v1 (msgpack), or upload a file through `mani mcp` (stdio)"
            )
        if stream and self.streams[tenant] >= settings.mcp_max_streams:
            raise RateLimited(f"at most {settings.mcp_max_streams} open MCP event streams per key "
                              "(MANI_MCP_MAX_STREAMS): close one first", retry_after=5.0)  # fmt: skip


def _with_body(scope: Scope, receive: Receive, body: bytes) -> tuple[Scope, Receive]:
    """``scope`` and ``receive`` for an app that is to read ``body`` (its length in the headers) as the request's
    body; after it, ``receive`` waits for the client's disconnect as before."""
    headers = [(k, v) for k, v in scope["headers"] if k.lower() not in (b"content-length", b"transfer-encoding")]
    scope = {**scope, "headers": [*headers, (b"content-length", str(len(body)).encode())]}
    sent = False

    async def replay() -> Message:
        nonlocal sent
        if sent:
            return await receive()
        sent = True
        return {"type": "http.request", "body": body, "more_body": False}

    return scope, replay


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
