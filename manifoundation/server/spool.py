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
import fcntl
import os
import shutil
import tempfile
import time
import uuid
from collections.abc import Sequence
from dataclasses import dataclass, field

from manifoundation.contract import JobKind, JobRequest, kind_of
from manifoundation.contract.codec import MSGPACK, dump_model

SPOOL_BYTES = 1 << 20
"""Payloads larger than this live in the embedded queue's spool, not in memory."""
SUFFIX = ".job"


def request_payload(request: JobRequest) -> bytes:
    """A job's payload: ``request`` packed as the worker reads it."""
    return dump_model(request, MSGPACK)


PREFIX = "mani-spool-"
LOCK = ".lock"
_held: dict[str, int] = {}  # spool directory -> the descriptor of its lock, held while the spool is in use


def new_spool() -> str:
    """A fresh, private spool directory, locked while in use (removed by `remove_spool`); first the spools that
    processes which ended without removing theirs (killed) left behind are removed (`stale_spools`)."""
    for stale in stale_spools():
        shutil.rmtree(stale, ignore_errors=True)
    directory = tempfile.mkdtemp(prefix=PREFIX)
    fd = os.open(os.path.join(directory, LOCK), os.O_CREAT | os.O_RDWR, 0o600)
    fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    _held[directory] = fd
    return directory


def remove_spool(directory: str) -> None:
    """The spool directory and every payload left in it; its lock let go."""
    shutil.rmtree(directory, ignore_errors=True)
    fd = _held.pop(directory, None)
    if fd is not None:
        os.close(fd)


STALE_AFTER_S = 60.0
"""A spool unchanged for less than this is never taken for stale (one being made has no lock held yet)."""


def stale_spools(root: str | None = None, min_age_s: float = STALE_AFTER_S) -> list[str]:
    """This user's spool directories in ``root`` (default: the temporary directory), unchanged for ``min_age_s``,
    that no process holds: their lock can be taken (a process's locks go with it, however it ended; a live spool's
    lock is held, seen from any process namespace sharing the directory)."""
    out = []
    now = time.time()
    with contextlib.suppress(OSError):
        for entry in os.scandir(root or tempfile.gettempdir()):
            if not entry.name.startswith(PREFIX) or not entry.is_dir(follow_symlinks=False):
                continue
            info = entry.stat(follow_symlinks=False)
            if info.st_uid != os.getuid() or entry.path in _held or now - info.st_mtime < min_age_s:
                continue
            try:
                fd = os.open(os.path.join(entry.path, LOCK), os.O_RDWR)
            except OSError:
                continue  # no lock file (not a spool, or one being made): left alone
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
                out.append(entry.path)
            except OSError:
                pass  # held: in use
            finally:
                os.close(fd)
    return out


def write_payload(directory: str, payload: bytes) -> str:
    """``payload`` as a new file of the spool ``directory``; its path."""
    path = os.path.join(directory, uuid.uuid4().hex + SUFFIX)
    with open(path, "xb") as out:
        out.write(payload)
    return path


def payload_files(directory: str) -> list[str]:
    """The names of the payloads in the spool ``directory`` (not its lock)."""
    return [name for name in os.listdir(directory) if name.endswith(SUFFIX)]


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

    ``path``: its payload's file; ``robot``: the hand it names (None: none); ``kind``: the job's kind."""

    path: str
    robot: str | None
    kind: JobKind = JobKind.SYNTHESIS

    @classmethod
    def write(cls, directory: str, request: JobRequest) -> SpooledRequest:
        """``request`` packed into the spool ``directory``."""
        return cls(write_payload(directory, request_payload(request)), robot_of(request), kind_of(request))


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
