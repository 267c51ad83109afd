"""Large request bodies, kept off the event loop: a few at a time, decoded and validated in worker processes.

Decoding a 50 MB JSON body (millions of floats into Python lists, then into arrays) holds the GIL for seconds, so
a thread would still stall every other request; a process does not. Bodies up to ``offload_bytes`` are decoded
inline (the common case, ~2 ms); larger ones take one of ``slots`` slots before they are even read and are
streamed, chunk by chunk as they arrive, to one of ``slots`` child processes (`manifoundation.server.api.body_child`):
the API process never holds a large body, only the decoded request (its arrays: a third to a fifth of the JSON) —
and of a large batch not even that, where the queue has a spool (`BodyPool.spool_batch`). A
request that waits longer than ``wait_s`` for a slot gets 503 with Retry-After. The children import the
contract and `manifoundation.server.spool` only (no torch, no queue or worker code).
"""

from __future__ import annotations

import asyncio
import contextlib
import importlib
import json
import pickle
import sys
from collections.abc import AsyncIterator
from typing import Any, TypeVar

from pydantic import BaseModel, ValidationError

from manifoundation.contract.codec import DecodeError, load_model
from manifoundation.contract.validation import field_errors

ModelT = TypeVar("ModelT", bound=BaseModel)

DECODE_AS = "manifoundation.server.api.bodies:decode_as"
"""The decoder a child runs for `BodyPool.decode`."""
SPOOL_BATCH = "manifoundation.server.api.bodies:spool_batch_as"
"""The decoder a child runs for `BodyPool.spool_batch`."""
PROTOBUF = "application/x-protobuf"
"""The "content type" of a gRPC request message: the contract's protobuf message of the model's name."""


def decode(cls: type[ModelT], data: bytes, content_type: str | None) -> tuple[str, Any]:
    """Decode and validate (inline or in a child process); answers ``(kind, value)`` with plain, picklable values:
    ``("ok", model)``, ``("empty", "")``, ``("decode", message)``, ``("invalid", [FieldError, ...])``,
    ``("bad", message)``."""
    if not data:
        return "empty", ""
    try:
        if content_type == PROTOBUF:
            return _from_protobuf(cls, data)
        return "ok", load_model(cls, data, content_type)
    except DecodeError as exc:
        return "decode", str(exc)
    except ValidationError as exc:
        return "invalid", field_errors(exc)
    except (ValueError, TypeError, RecursionError) as exc:
        return "bad", f"body could not be read: {exc}"


def decode_as(data: bytes, cls_path: str, content_type: str | None) -> tuple[str, Any]:
    """`decode` for the model named ``"module:Name"`` (how a child process is told which model to decode)."""
    module, _, name = cls_path.partition(":")
    cls: type[BaseModel] = getattr(importlib.import_module(module), name)
    return decode(cls, data, content_type)


def spool_batch_as(data: bytes, directory: str, content_type: str | None) -> tuple[str, Any]:
    """`decode` of a `BatchCreate`, its requests then packed into the queue's spool ``directory``
    (`manifoundation.server.spool`): ``("ok", SpooledBatch)``, `decode`'s errors, or ``("unavailable", message)``
    when the spool could not be written (nothing is left written)."""
    from manifoundation.contract import BatchCreate
    from manifoundation.server.spool import spool_batch

    kind, value = decode(BatchCreate, data, content_type)
    if kind != "ok":
        return kind, value
    try:
        return "ok", spool_batch(value.requests, directory)
    except OSError as exc:  # the disk, not the body: 503
        return "unavailable", f"the queue's spool could not take the batch: {exc}"


def _from_protobuf(cls: type[ModelT], data: bytes) -> tuple[str, Any]:
    """A gRPC request message (``manifoundation.v1.<cls name>``) validated as the contract's ``cls``."""
    from google.protobuf.message import DecodeError as ProtobufDecodeError

    from manifoundation.contract.protos.convert import from_proto
    from manifoundation.contract.protos.v1 import manifoundation_pb2 as pb

    try:
        message = getattr(pb, cls.__name__).FromString(data)
    except ProtobufDecodeError as exc:
        return "decode", f"the message could not be parsed as {cls.__name__}: {exc}"
    return "ok", from_proto(message, cls)  # type: ignore[type-var]


class BodyPool:
    """The slots and the decoding processes for large bodies (one per app; closed in the lifespan).

    The processes are plain ``python -m manifoundation.server.api.body_child`` children on pipes (no `multiprocessing`:
    no re-import of the parent's main module, no feeder threads holding copies of the body); one body at a time
    each, at most ``slots`` of them, started on first use. A child that fails or whose request is abandoned
    half-way is killed and replaced.
    """

    def __init__(self, offload_bytes: int, slots: int, wait_s: float) -> None:
        self.offload_bytes = offload_bytes
        self.wait_s = wait_s
        self._size = slots
        self._slots = asyncio.Semaphore(slots)
        self._idle: list[asyncio.subprocess.Process] = []
        self._loop: asyncio.AbstractEventLoop | None = None

    def large(self, declared: int | None) -> bool:
        """Whether a body of ``declared`` bytes (None: not declared) takes a slot."""
        return declared is None or declared > self.offload_bytes

    @contextlib.asynccontextmanager
    async def slot(self) -> AsyncIterator[None]:
        """Hold one large-body slot. Raises `manifoundation.server.api.errors.Unavailable` after ``wait_s``."""
        from manifoundation.server.api.errors import Unavailable

        if self._loop is not asyncio.get_running_loop():  # a new event loop (tests): start afresh
            self.close()
            self._slots = asyncio.Semaphore(self._size)
            self._loop = asyncio.get_running_loop()
        try:
            await asyncio.wait_for(self._slots.acquire(), self.wait_s)
        except TimeoutError as exc:
            raise Unavailable("too many large bodies are being read; retry later", retry_after=2) from exc
        try:
            yield
        finally:
            self._slots.release()

    async def decode(
        self, cls: type[ModelT], chunks: AsyncIterator[bytes], content_type: str | None
    ) -> tuple[str, Any]:
        """`decode` in a child process of the body ``chunks`` streamed to it as they come (call while holding a
        `slot`). The exceptions of ``chunks`` (408, 413) pass through; the child is then killed."""
        return await self.run(DECODE_AS, chunks, f"{cls.__module__}:{cls.__qualname__}", content_type)

    async def spool_batch(
        self, chunks: AsyncIterator[bytes], content_type: str | None, directory: str
    ) -> tuple[str, Any]:
        """`decode` of a `BatchCreate` in a child process, which packs its requests into the queue's spool
        ``directory`` (`spool_batch_as`): this process never holds the batch's arrays (call while holding a
        `slot`)."""
        return await self.run(SPOOL_BATCH, chunks, directory, content_type)

    async def run(self, decoder: str, chunks: AsyncIterator[bytes], *args: str | int | None) -> tuple[str, Any]:
        """``decoder(body, *args)`` in a child process, the body ``chunks`` streamed to it as they come (call while
        holding a `slot`). ``decoder``: ``"module:function"``, a function of the body's bytes and ``args`` (JSON
        values) that answers a picklable ``(kind, value)`` and imports no queue or worker code. The exceptions of
        ``chunks`` (408, 413) pass through; the child is then killed."""
        from manifoundation.server.api.errors import Unavailable

        child = self._idle.pop() if self._idle else await self._spawn()
        try:
            assert child.stdin is not None and child.stdout is not None
            header = json.dumps({"decoder": decoder, "args": list(args)}).encode()
            child.stdin.write(len(header).to_bytes(4, "big") + header)
            async for chunk in chunks:
                child.stdin.write(len(chunk).to_bytes(4, "big"))
                child.stdin.write(chunk)
                await child.stdin.drain()  # the pipe's pace: at most a chunk or two in this process
            child.stdin.write(bytes(4))
            await child.stdin.drain()
            size = int.from_bytes(await child.stdout.readexactly(8), "big")
            answer: tuple[str, Any] = pickle.loads(await child.stdout.readexactly(size))
        except BaseException as exc:  # broken, or abandoned half-way (client gone, 408, 413): never reuse it
            _kill(child)
            if isinstance(exc, OSError | asyncio.IncompleteReadError):
                raise Unavailable("the body decoder failed; retry", retry_after=1) from exc
            raise
        self._idle.append(child)
        return answer

    async def _spawn(self) -> asyncio.subprocess.Process:
        return await asyncio.create_subprocess_exec(
            sys.executable,
            "-m",
            "manifoundation.server.api.body_child",
            stdin=asyncio.subprocess.PIPE,
            stdout=asyncio.subprocess.PIPE,
        )

    def close(self) -> None:
        """Stop the idle children (a busy one is killed by its request's end)."""
        for child in self._idle:
            _kill(child)
        self._idle.clear()


def _kill(child: asyncio.subprocess.Process) -> None:
    with contextlib.suppress(ProcessLookupError):
        child.kill()
