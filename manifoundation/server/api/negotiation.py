"""JSON and msgpack both ways: read a body by its Content-Type, answer in the encoding the Accept header asks for.

Bodies are read here (not by FastAPI) so that msgpack works and the size limit holds while streaming: a body
over the limit is refused as soon as its Content-Length (or its running size) says so; a sender too slow is cut
off (408); a large body is decoded off the event loop (`manifoundation.server.api.bodies`). Answers are encoded by
`manifoundation.server.api.encoding` (re-exported here for the routes).
"""

from __future__ import annotations

import asyncio
from collections.abc import AsyncIterator
from typing import Any, TypeVar

from pydantic import BaseModel
from starlette.requests import Request

from manifoundation.contract import BatchCreate, FieldError
from manifoundation.contract.codec import JSON, MSGPACK, media_type
from manifoundation.contract.validation import summary
from manifoundation.server.api.bodies import decode
from manifoundation.server.api.encoding import accepted, respond
from manifoundation.server.api.errors import (
    BadRequest,
    InvalidInput,
    PayloadTooLarge,
    RequestTimeout,
    Unavailable,
    UnsupportedMediaType,
)
from manifoundation.server.api.services import services_of
from manifoundation.server.spool import SpooledBatch

__all__ = [
    "accepted", "body_chunks", "body_openapi", "bounded_chunks", "declared_length", "read_batch", "read_bytes",
    "read_model",
    "respond",
]  # fmt: skip

ModelT = TypeVar("ModelT", bound=BaseModel)
BODY_MEDIA_TYPES = (JSON, MSGPACK)


def declared_length(request: Request, limit: int) -> int | None:
    """The body's Content-Length (None when not declared). Raises 400 when malformed, 413 when over ``limit``:
    both before a byte of the body is read."""
    declared = request.headers.get("content-length")
    if declared is None:
        return None
    try:
        size = int(declared)
    except ValueError as exc:
        raise BadRequest("Content-Length is not a number") from exc
    if size < 0:
        raise BadRequest("Content-Length is negative")
    if size > limit:
        raise PayloadTooLarge(f"body of {size} bytes exceeds the limit of {limit} bytes")
    return size


async def body_chunks(request: Request, limit: int, timeout: float = 60.0, idle: float = 10.0) -> AsyncIterator[bytes]:
    """The raw body chunk by chunk, refusing more than ``limit`` bytes (413) and a sender slower than ``timeout``
    seconds in all or ``idle`` seconds between two chunks (408: a slow client never holds a connection for ever)."""
    declared_length(request, limit)
    async for chunk in bounded_chunks(request.stream(), limit, timeout, idle):
        yield chunk


async def bounded_chunks(
    chunks: AsyncIterator[bytes], limit: int, timeout: float, idle: float, *, whole: str = "body",
    unit: str = "body byte", limit_name: str = "",
) -> AsyncIterator[bytes]:  # fmt: skip
    """The non-empty ``chunks`` of a body as they arrive, refusing more than ``limit`` bytes in all (413, naming
    ``limit_name`` when given) and a sender slower than ``timeout`` seconds in all or ``idle`` seconds between two
    chunks (408); ``whole`` and ``unit`` name the body and what arrives in the messages (an HTTP body's bytes, a
    gRPC stream's pieces).

    `asyncio.timeout_at` around each wait, not `asyncio.wait_for`: the latter ends every body with a
    StopAsyncIteration whose traceback and wait_for's future form a reference cycle holding the reader's frame,
    and so every chunk of the body, until the garbage collector's rare full pass (one body of RSS per request).
    """
    total = 0
    loop = asyncio.get_running_loop()
    end = loop.time() + timeout
    stream = aiter(chunks)
    while True:
        try:
            async with asyncio.timeout_at(min(end, loop.time() + idle)):
                chunk = await anext(stream, None)
        except TimeoutError as exc:
            why = f"{whole} not received within {timeout:g} s" if loop.time() >= end else f"no {unit} for {idle:g} s"
            raise RequestTimeout(why) from exc
        if chunk is None:
            return
        total += len(chunk)
        if total > limit:
            named = f" ({limit_name})" if limit_name else ""
            raise PayloadTooLarge(f"{whole} exceeds the limit of {limit} bytes{named}")
        if chunk:
            yield chunk


async def read_bytes(request: Request, limit: int, timeout: float = 60.0, idle: float = 10.0) -> bytes:
    """The whole raw body, under `body_chunks`' limits."""
    return b"".join([chunk async for chunk in body_chunks(request, limit, timeout, idle)])


async def read_model(request: Request, cls: type[ModelT], limit: int) -> ModelT:
    """Read, decode and validate a body of ``cls`` (400 malformed, 408 too slow, 413 too big, 415 other type,
    422 invalid). A large body waits for a slot and is decoded in a worker process
    (`manifoundation.server.api.bodies`)."""
    content_type = _content_type(request)
    services = services_of(request)
    settings, bodies = services.settings, services.bodies
    timeouts = settings.body_timeout, settings.body_idle_timeout
    if bodies is None or not bodies.large(declared_length(request, limit)):
        return decoded(decode(cls, await read_bytes(request, limit, *timeouts), content_type))
    async with bodies.slot():
        return decoded(await bodies.decode(cls, body_chunks(request, limit, *timeouts), content_type))


async def read_batch(request: Request, limit: int, spool: str | None) -> BatchCreate | SpooledBatch:
    """`read_model` of a `BatchCreate`; a large one, where the queue has a ``spool``, packed straight into it by
    the body process that decodes it (`BodyPool.spool_batch`: its arrays never reach this process)."""
    services = services_of(request)
    settings, bodies = services.settings, services.bodies
    if spool is None or bodies is None or not bodies.large(declared_length(request, limit)):
        return await read_model(request, BatchCreate, limit)
    content_type = _content_type(request)
    chunks = body_chunks(request, limit, settings.body_timeout, settings.body_idle_timeout)
    async with bodies.slot():
        value: SpooledBatch = decoded(await bodies.spool_batch(chunks, content_type, spool))
        return value


def _content_type(request: Request) -> str | None:
    """The body's Content-Type (415 for one that is neither JSON nor msgpack)."""
    content_type = request.headers.get("content-type")
    base = (content_type or JSON).split(";", 1)[0].strip().lower()
    if base not in (JSON, "text/json") and media_type(base) != MSGPACK and not base.endswith("+json"):
        raise UnsupportedMediaType(f"Content-Type {base!r} is not supported; use {JSON} or {MSGPACK}")
    return content_type


def decoded(outcome: tuple[str, Any]) -> Any:
    """The model of a `manifoundation.server.api.bodies.decode` outcome, or the error it names (400, 422; 503 for a
    spool that could not be written)."""
    kind, value = outcome
    if kind == "ok":
        return value
    if kind == "invalid":
        return_errors: list[FieldError] = value
        raise InvalidInput(summary(return_errors), detail=return_errors)
    if kind == "empty":
        raise BadRequest("empty body; send a JSON or msgpack object")
    if kind == "unavailable":
        raise Unavailable(str(value), retry_after=5)
    raise BadRequest(str(value))


def body_openapi(schema_ref: str, description: str = "") -> dict[str, Any]:
    """``openapi_extra`` documenting a body of ``#/components/schemas/<schema_ref>`` in both encodings."""
    ref = {"$ref": f"#/components/schemas/{schema_ref}"}
    return {
        "requestBody": {
            "required": True,
            "description": description or f"{schema_ref} as JSON, or msgpack with typed-binary arrays.",
            "content": {JSON: {"schema": ref}, MSGPACK: {"schema": ref}},
        }
    }
