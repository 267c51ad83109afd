"""Reading bodies: a body once read leaves nothing behind for the cycle collector, limits hold chunk by chunk."""

from __future__ import annotations

import asyncio
import gc
from typing import Any

import pytest
from starlette.requests import Request

from manifoundation.server.api.errors import PayloadTooLarge
from manifoundation.server.api.negotiation import body_chunks, read_bytes


def _request(chunks: list[bytes]) -> Request:
    messages = [{"type": "http.request", "body": c, "more_body": i < len(chunks) - 1} for i, c in enumerate(chunks)]

    async def receive() -> dict[str, Any]:
        return messages.pop(0)

    return Request({"type": "http", "method": "POST", "path": "/", "headers": [], "query_string": b""}, receive)


def test_a_read_body_is_not_kept_in_a_reference_cycle() -> None:
    """The old reader (`asyncio.wait_for` per chunk) left each body's chunks in a cycle of StopAsyncIteration,
    its traceback and wait_for's future: freed only by a full collection, so RSS grew by a body per request."""
    chunks = [bytes([i]) * 65536 for i in range(8)]
    ours = {id(c) for c in chunks}
    gc.collect()
    gc.disable()
    try:
        assert asyncio.run(read_bytes(_request(list(chunks)), limit=1 << 20)) == b"".join(chunks)
        gc.set_debug(gc.DEBUG_SAVEALL)
        gc.collect()
        held = [o for o in gc.garbage if isinstance(o, list) and any(id(x) in ours for x in o)]
    finally:
        gc.set_debug(0)
        gc.garbage.clear()
        gc.enable()
    assert not held, "a read body is held by a reference cycle"


def test_the_limit_holds_while_streaming() -> None:
    async def take() -> list[bytes]:
        return [c async for c in body_chunks(_request([b"x" * 600, b"y" * 600]), limit=1000)]

    with pytest.raises(PayloadTooLarge):
        asyncio.run(take())
