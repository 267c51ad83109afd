"""Job payloads at rest on disk: the embedded queue's spool.

A job's payload is its request packed as the worker reads it (`request_payload`). The embedded queue keeps
payloads over `SPOOL_BYTES` as files in a spool directory of its own rather than in the API process's memory, and
a large batch is packed straight into that directory by the body process that decoded it (`SpooledRequest`: what
the queue needs of a request without its arrays), so the API process never holds a large batch's arrays at all
(issue 62, item 3: 100 × 57.6 MB gRPC batches took the API to 410-490 MB, decoded batches and their payloads in
transit).

Torch-free and light: the body processes import it (`manifoundation.server.api.bodies`), as does the queue.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
import uuid
from collections.abc import Sequence
from dataclasses import dataclass, field

from manifoundation.contract import JobKind, JobRequest, kind_of
from manifoundation.contract.codec import pack

SPOOL_BYTES = 1 << 20
"""Payloads larger than this live in the embedded queue's spool, not in memory."""
SUFFIX = ".job"


def request_payload(request: JobRequest) -> bytes:
    """A job's payload: ``request`` packed as the worker reads it."""
    return pack(request.model_dump(mode="python", exclude_none=True))


def new_spool() -> str:
    """A fresh, private spool directory (removed by `remove_spool`)."""
    return tempfile.mkdtemp(prefix=f"mani-spool-{os.getpid()}-")


def remove_spool(directory: str) -> None:
    """The spool directory and every payload left in it."""
    shutil.rmtree(directory, ignore_errors=True)


def write_payload(directory: str, payload: bytes) -> str:
    """``payload`` as a new file of the spool ``directory``; its path."""
    path = os.path.join(directory, uuid.uuid4().hex + SUFFIX)
    with open(path, "xb") as out:
        out.write(payload)
    return path


def open_payload(path: str) -> int:
    """A file descriptor of a spooled payload: still readable once the file is removed (a job cancelled while
    its payload is being sent)."""
    return os.open(path, os.O_RDONLY)


def read_payload(fd: int) -> bytes:
    """The payload behind ``fd`` (`open_payload`), which is closed."""
    with open(fd, "rb", closefd=True) as source:
        return source.read()


def remove_payload(path: str) -> None:
    """A spooled payload's file (gone already: nothing to do)."""
    with contextlib.suppress(FileNotFoundError):
        os.unlink(path)


@dataclass(frozen=True, slots=True)
class SpooledRequest:
    """A validated request whose payload is already in a spool: what the queue needs of it without its arrays.

    ``path``: its payload's file; ``nbytes``: the payload's size; ``robot``: the hand it names (None: none);
    ``kind``: the job's kind."""

    path: str
    nbytes: int
    robot: str | None
    kind: JobKind = JobKind.SYNTHESIS

    @classmethod
    def write(cls, directory: str, request: JobRequest) -> SpooledRequest:
        """``request`` packed into the spool ``directory``."""
        payload = request_payload(request)
        robot = request.robot.name if request.robot is not None else None
        return cls(write_payload(directory, payload), len(payload), robot, kind_of(request))


@dataclass(slots=True)
class SpooledBatch:
    """A batch whose requests a body process packed into the queue's spool (`spool_batch`); until the queue takes
    it, its files are its own (`discard`)."""

    requests: list[SpooledRequest] = field(default_factory=list)

    def discard(self) -> None:
        """Remove its payloads (it was refused)."""
        for request in self.requests:
            remove_payload(request.path)


def spool_batch(requests: Sequence[JobRequest], directory: str) -> SpooledBatch:
    """``requests`` packed into the spool ``directory``, all or none (a failure removes what was written)."""
    batch = SpooledBatch()
    try:
        for request in requests:
            batch.requests.append(SpooledRequest.write(directory, request))
    except BaseException:
        batch.discard()
        raise
    return batch


def robot_of(request: JobRequest | SpooledRequest) -> str | None:
    """The hand a request (spooled or not) names."""
    if isinstance(request, SpooledRequest):
        return request.robot
    return request.robot.name if request.robot is not None else None


def job_kind(request: JobRequest | SpooledRequest) -> JobKind:
    """The kind of job a request (spooled or not) makes."""
    return request.kind if isinstance(request, SpooledRequest) else kind_of(request)
