"""The embedded queue's payloads and the memory they leave: large requests packed off the event loop and kept in the
queue's spool (`manifoundation.server.spool`), and the C heap trimmed once enough payloads were let go.

Why apart from the queue: both are about the bytes of large requests (issue 62, item 3: 3 × 57.6 MB gRPC batches
stalled the loop while packing and left the API at 368 MB after the queue drained, 90 MB before them).
"""

from __future__ import annotations

import asyncio
import contextlib
import os
from collections.abc import Sequence

from manifoundation.contract import ErrorBody, ErrorType, JobRequest
from manifoundation.server.spool import SPOOL_BYTES, SpooledBatch, SpooledRequest, read_payload, request_payload
from manifoundation.server.worker.heap import HeapTrimmer

PACK_INLINE_BYTES = 1 << 20
"""Requests whose arrays add up to more than this are packed in a thread, not on the event loop."""
TRIM_AFTER_FREED_BYTES = 32 * 1024 * 1024
"""Once the payloads of ended jobs add up to this (or the queue is idle), the C heap's free pages go back to the
OS (`HeapTrimmer`, at most every 2 s): glibc keeps freed multi-MB payloads in its arenas, so an API that took a
few large batches would otherwise stay at their peak."""


def _cloud_bytes(request: JobRequest) -> int:
    """The size of a request's point cloud (its points; 0 for a request without one)."""
    points = getattr(getattr(request, "object", None), "points", None)
    return int(getattr(points, "nbytes", 0))


async def packed(requests: Sequence[JobRequest | SpooledRequest], spool: str | None) -> list[bytes | SpooledRequest]:
    """The queue's payloads of ``requests``: bytes, or for a request whose cloud is over `SPOOL_BYTES` its payload
    written to the ``spool`` directory (None: none, all in memory); a request already spooled as it is. Large ones
    (200 000 points pack in ≈ 6 ms) are packed in a thread."""

    def one(request: JobRequest | SpooledRequest) -> bytes | SpooledRequest:
        if isinstance(request, SpooledRequest):
            return request
        if spool is not None and _cloud_bytes(request) > SPOOL_BYTES:
            return SpooledRequest.write(spool, request)
        return request_payload(request)

    def pack_all() -> list[bytes | SpooledRequest]:
        out: list[bytes | SpooledRequest] = []
        try:
            for request in requests:
                out.append(one(request))
        except BaseException:
            discard_spooled(out, requests)
            raise
        return out

    plain = [r for r in requests if not isinstance(r, SpooledRequest)]
    if sum(_cloud_bytes(r) for r in plain) > PACK_INLINE_BYTES:
        return await asyncio.to_thread(pack_all)
    return pack_all()


def discard_spooled(
    payloads: Sequence[bytes | SpooledRequest], requests: Sequence[JobRequest | SpooledRequest]
) -> None:
    """Remove the files `packed` spooled for ``requests`` (``payloads``: its answer, or the part made before it
    failed); a request that came spooled keeps its file (its caller's)."""
    spooled = [p for p, r in zip(payloads, requests, strict=False) if isinstance(p, SpooledRequest) and p is not r]
    SpooledBatch(spooled).discard()


class FreedPayloads:
    """Bytes of payloads let go since the C heap was last trimmed; trims after every ``TRIM_AFTER_FREED_BYTES`` and
    once the queue is idle."""

    def __init__(self) -> None:
        self.freed = 0
        self._heap = HeapTrimmer()

    @property
    def trims(self) -> int:
        """How many times the heap was trimmed."""
        return self._heap.trims

    def add(self, nbytes: int) -> None:
        """A payload of ``nbytes`` was let go."""
        self.freed += nbytes

    def maybe_trim(self, idle: bool) -> None:
        """Trim the heap when enough was freed (anything, when ``idle``) and the trimmer's interval allows."""
        if self.freed >= (1 if idle else TRIM_AFTER_FREED_BYTES) and self._heap.maybe_trim():
            self.freed = 0


def unreadable_error(exc: OSError) -> ErrorBody:
    """The error of a job whose spooled payload could not be read (the disk failed, or the file was removed)."""
    return ErrorBody.of(ErrorType.UNAVAILABLE, f"the job's payload could not be read from the spool: {exc}")


def read_spooled(frames: list[bytes | int]) -> list[bytes]:
    """``frames`` with each spooled payload (an open descriptor, `open_payload`) read and closed; all are closed even
    when one read fails."""
    out: list[bytes] = []
    try:
        for frame in frames:
            out.append(read_payload(frame) if isinstance(frame, int) else frame)
    finally:
        for frame in frames[len(out) + 1 :]:
            if isinstance(frame, int):
                with contextlib.suppress(OSError):
                    os.close(frame)
    return out
