"""uvicorn's HTTP protocol with a bound on the request head: a connection must send its request line and headers
within ``head_timeout`` seconds, else it gets 408 and is closed.

uvicorn bounds the idle time between requests (``timeout_keep_alive``) and our routes bound the body
(`manifoundation.server.api.negotiation.body_chunks`), but nothing bounds the head: a client sending one header byte
every few seconds, or connecting and sending nothing, held its connection for ever. The clock starts when the connection
is made or when a request's first byte arrives (uvicorn's keep-alive timer covers the wait before that byte),
and stops when the headers are complete. Built on the httptools protocol that ``uvicorn[standard]`` installs.
"""

from __future__ import annotations

import asyncio
from typing import Any

from uvicorn.protocols.http.httptools_impl import HttpToolsProtocol

from manifoundation.contract import ErrorBody, ErrorType


def _timeout_response(seconds: float) -> bytes:
    body = ErrorBody.of(ErrorType.REQUEST_TIMEOUT, f"request headers not received within {seconds:g} s")
    data = body.model_dump_json(exclude_none=True).encode()
    head = (
        "HTTP/1.1 408 Request Timeout\r\ncontent-type: application/json\r\n"
        f"content-length: {len(data)}\r\nconnection: close\r\n\r\n"
    )
    return head.encode() + data


class BoundedHeadProtocol(HttpToolsProtocol):
    """`HttpToolsProtocol` that answers 408 and closes a connection whose request head is late (module doc)."""

    head_timeout: float = 10.0

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self._head_timer: asyncio.TimerHandle | None = None

    def connection_made(self, transport: asyncio.Transport) -> None:  # type: ignore[override]
        super().connection_made(transport)
        self._arm()

    def connection_lost(self, exc: Exception | None) -> None:
        self._disarm()
        super().connection_lost(exc)

    def on_message_begin(self) -> None:
        super().on_message_begin()
        self._arm()

    def on_headers_complete(self) -> None:
        self._disarm()
        super().on_headers_complete()

    def _arm(self) -> None:
        if self._head_timer is None:
            self._head_timer = self.loop.call_later(self.head_timeout, self._late)

    def _disarm(self) -> None:
        if self._head_timer is not None:
            self._head_timer.cancel()
            self._head_timer = None

    def _late(self) -> None:
        self._head_timer = None
        if self.transport.is_closing():
            return
        if self.cycle is not None and not self.cycle.response_complete:
            self.cycle.keep_alive = False  # a pipelined head is late behind a running request: close after it
            return
        self.transport.write(_timeout_response(self.head_timeout))
        self.transport.close()


def bounded_head_protocol(head_timeout: float) -> type[BoundedHeadProtocol]:
    """A `BoundedHeadProtocol` class with its bound (uvicorn takes the protocol as a class)."""
    return type("BoundedHeadProtocol", (BoundedHeadProtocol,), {"head_timeout": head_timeout})
