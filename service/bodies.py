"""Large request bodies, kept off the event loop: a few at a time, decoded and validated in worker processes.

Decoding a 50 MB JSON body (millions of floats into Python lists, then into arrays) holds the GIL for seconds, so
a thread would still stall every other request; a process does not. Bodies up to ``offload_bytes`` are decoded
inline (the common case, ~2 ms); larger ones take one of ``slots`` slots before they are even read (so at most
``slots`` large bodies are in memory at once) and are decoded in a small spawned process pool. A request that
waits longer than ``wait_s`` for a slot gets 503 with Retry-After. The children import `clients` only (no
torch, no server code).
"""

from __future__ import annotations

import asyncio
import contextlib
import multiprocessing as mp
from collections.abc import AsyncIterator
from concurrent.futures import ProcessPoolExecutor
from typing import Any, TypeVar

from pydantic import BaseModel, ValidationError

from clients.codec import DecodeError, load_model
from clients.validation import field_errors

ModelT = TypeVar("ModelT", bound=BaseModel)


def decode(cls: type[ModelT], data: bytes, content_type: str | None) -> tuple[str, Any]:
    """Decode and validate in a child process; answers ``(kind, value)`` with plain, picklable values:
    ``("ok", model)``, ``("decode", message)``, ``("invalid", [FieldError, ...])``, ``("bad", message)``."""
    try:
        return "ok", load_model(cls, data, content_type)
    except DecodeError as exc:
        return "decode", str(exc)
    except ValidationError as exc:
        return "invalid", field_errors(exc)
    except (ValueError, TypeError, RecursionError) as exc:
        return "bad", f"body could not be read: {exc}"


class BodyPool:
    """The slots and the process pool for large bodies (one per app; closed in the lifespan)."""

    def __init__(self, offload_bytes: int, slots: int, wait_s: float) -> None:
        self.offload_bytes = offload_bytes
        self.wait_s = wait_s
        self._slots = asyncio.Semaphore(slots)
        self._workers = slots
        self._pool: ProcessPoolExecutor | None = None

    def large(self, declared: int | None) -> bool:
        """Whether a body of ``declared`` bytes (None: not declared) takes a slot."""
        return declared is None or declared > self.offload_bytes

    @contextlib.asynccontextmanager
    async def slot(self) -> AsyncIterator[None]:
        """Hold one large-body slot. Raises `service.errors.Unavailable` after ``wait_s``."""
        from service.errors import Unavailable

        try:
            await asyncio.wait_for(self._slots.acquire(), self.wait_s)
        except TimeoutError as exc:
            raise Unavailable("too many large bodies are being read; retry later", retry_after=2) from exc
        try:
            yield
        finally:
            self._slots.release()

    async def decode(self, cls: type[ModelT], data: bytes, content_type: str | None) -> tuple[str, Any]:
        """`decode` in the process pool (started on first use)."""
        if self._pool is None:
            self._pool = ProcessPoolExecutor(max_workers=self._workers, mp_context=mp.get_context("spawn"))
        return await asyncio.get_running_loop().run_in_executor(self._pool, decode, cls, data, content_type)

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=False, cancel_futures=True)
            self._pool = None
