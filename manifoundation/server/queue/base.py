"""The queue interface that the service talks to and both backends implement.

Two backends (docs/architecture.md): embedded (in-process queue feeding spawned worker processes; the default, not
durable) and Redis Streams (a consumer group; durable as far as Redis's own persistence goes, scale-out). The
service only ever sees `JobQueue`. Everything here is torch-free.

Tenancy: every job, batch and registered robot may carry an ``owner`` (an opaque tenant id; the service derives it
from the API key). Reads given an ``owner`` see only that owner's jobs and batches (anything else is
`JobNotFound`, exactly like an unknown id); ``owner=None`` on a read sees everything (single-tenant, operators).
Robots are namespaced: ``owner=None`` is the shared (single-tenant) namespace, built-in hands are everyone's.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import AsyncIterator, Sequence
from dataclasses import dataclass

from manifoundation.contract import (
    DeadLetter,
    JobPublic,
    JobRequest,
    QueueStats,
    RobotPublic,
    RobotRegister,
    SynthesisRequest,
    WorkerPublic,
)
from manifoundation.server.spool import SpooledRequest


class QueueError(Exception):
    """Base of the queue's errors."""


class QueueFull(QueueError):
    """The queue holds its maximum number of pending jobs; try again after ``retry_after`` seconds."""

    def __init__(self, message: str, retry_after: float = 1.0) -> None:
        super().__init__(message)
        self.retry_after = retry_after


class JobNotFound(QueueError):
    """No job (or batch) with this id, or its record expired and was removed."""


class RobotInvalid(QueueError):
    """A worker rejected a robot description (hardened URDF loader); the message says why."""


class RobotDeadlineExceeded(QueueError):
    """A registration was still loading at its deadline: the worker loading it was stopped and replaced (or no
    worker answered by then); the message says which."""


class RobotLimitReached(QueueError):
    """A key already holds as many registered robots, or as many of their bytes, as its limits allow."""


@dataclass(frozen=True)
class RobotLimits:
    """What one key may hold: ``max_robots`` registered hands, ``max_bytes`` of descriptions and archives (the rule:
    `manifoundation.server.queue.robot_quota`)."""

    max_robots: int
    max_bytes: int


class QueueUnavailable(QueueError):
    """The backend cannot be reached (e.g. Redis down) or is shutting down."""


class JobQueue(ABC):
    """Submit, observe and cancel jobs (syntheses and plans); the service's only way to get work done."""

    backend: str = "abstract"
    spool: str | None = None
    """A directory a body process may pack a large batch's requests into (`manifoundation.server.spool`), handing
    the queue `SpooledRequest` s instead of requests; None: this backend takes requests only."""

    @abstractmethod
    async def start(self) -> None:
        """Connect / start workers. Called once in the service's lifespan."""

    @abstractmethod
    async def close(self) -> None:
        """Release connections; embedded backend: stop its workers gracefully."""

    @abstractmethod
    async def ping(self) -> bool:
        """Whether the backend answers."""

    @abstractmethod
    async def submit(
        self, requests: Sequence[JobRequest | SpooledRequest], *, batch_id: str | None = None,
        deadline: float | None = None, request_id: str | None = None, owner: str | None = None,
    ) -> list[str]:  # fmt: skip
        """Enqueue jobs atomically (all or none); returns their ids in order. Each job's kind is its request's
        (`manifoundation.contract.kind_of`): a synthesis, or a plan (answered in `JobPublic.plan`).

        ``owner``: the tenant the jobs belong to (None: nobody in particular); their registered robot is looked
        up in that owner's namespace.

        ``request_id``: the ``X-Request-ID`` of the HTTP request submitting them (the same for every job of a
        batch). Kept in each job's record (internal: not part of `JobPublic`) and put on every log line the
        worker writes while it runs the job, next to ``job_id``.

        A `SpooledRequest` (a payload already in `spool`) is the queue's once accepted; refused, its file is still
        the caller's.

        Raises:
            QueueFull: accepting them would exceed the queue's bound.
        """

    @property
    def capacity(self) -> int | None:
        """The most jobs the queue ever holds (``max_queue``); None: unbounded. A batch larger than this can never
        be accepted (the service answers 422 instead of 429 for ever)."""
        return None

    async def room(self, count: int = 1) -> bool:
        """Whether ``count`` more jobs would fit now (a cheap admission check before a body is read; `submit`
        still decides). Default: always."""
        return True

    @abstractmethod
    async def get(self, job_id: str, *, with_result: bool = True, owner: str | None = None) -> JobPublic:
        """The job's state, progress, timings, and result or error.

        Raises:
            JobNotFound: unknown id, or (``owner`` given) a job of another owner. An expired result still reports
                state ``expired``.
        """

    @abstractmethod
    async def wait(self, job_id: str, timeout: float) -> JobPublic:
        """Wait until the job is terminal or ``timeout`` seconds pass; returns its latest state either way."""

    def events(self, job_id: str, interval: float = 0.25) -> AsyncIterator[JobPublic]:
        """Progress updates of one job until it is terminal (default: polling `get`)."""
        return _poll_events(self, job_id, interval)

    @abstractmethod
    async def cancel(self, job_id: str, *, owner: str | None = None) -> JobPublic:
        """Cancel a queued or running job (honoured between pipeline stages); no-op when terminal.

        Raises:
            JobNotFound: as `get`.
        """

    @abstractmethod
    async def list_recent(self, limit: int = 50, *, owner: str | None = None) -> list[JobPublic]:
        """The most recently submitted jobs (of ``owner`` when given), newest first, without results."""

    @abstractmethod
    async def create_batch(
        self, requests: Sequence[SynthesisRequest | SpooledRequest], deadline: float | None = None, *,
        request_id: str | None = None, owner: str | None = None,
    ) -> str:  # fmt: skip
        """Submit a batch of requests (``request_id``, ``owner`` as in `submit`); returns the batch id."""

    @abstractmethod
    async def batch_job_ids(self, batch_id: str, *, owner: str | None = None) -> list[str]:
        """The job ids of a batch in request order. Raises `JobNotFound` (also for another owner's batch)."""

    @abstractmethod
    async def stats(self) -> QueueStats:
        """Queue depth, jobs by state, totals."""

    @abstractmethod
    async def workers(self) -> list[WorkerPublic]:
        """Live workers with their last heartbeat and current job."""

    @abstractmethod
    async def dead_letters(self, limit: int = 50) -> list[DeadLetter]:
        """Jobs that failed on every delivery, newest first."""

    @abstractmethod
    async def list_robots(self, *, owner: str | None = None) -> list[RobotPublic]:
        """Built-in hands (published by the workers at start-up) and the ones ``owner`` registered."""

    @abstractmethod
    async def register_robot(
        self,
        robot: RobotRegister,
        timeout: float = 30.0,
        *,
        owner: str | None = None,
        limits: RobotLimits | None = None,
    ) -> RobotPublic:
        """Have a worker validate the URDF with the hardened loader, then store it in ``owner``'s namespace for
        every worker (registering a name again replaces that owner's robot of that name).

        With ``limits``, ``owner``'s slot and bytes are reserved atomically in the store before the worker is
        asked (`manifoundation.server.queue.robot_quota`), and released when it answers.

        ``timeout`` is the registration's deadline, counted from now: the worker still loading the robot then ends
        itself and is replaced (`manifoundation.server.worker.overrun`), so a slow description holds no worker
        beyond it.

        Raises:
            RobotInvalid: the description was rejected (message says why).
            RobotDeadlineExceeded: not validated within ``timeout`` (its worker stopped and replaced).
            RobotLimitReached: ``owner`` holds as many robots or bytes as ``limits`` allow.
        """

    async def delete_robot(self, name: str, *, owner: str | None = None) -> None:
        """Remove ``owner``'s registered robot ``name`` (built-ins cannot be removed).

        Raises:
            JobNotFound: no such registered robot of ``owner``.
        """
        raise JobNotFound(f"no registered robot {name!r}")


async def _poll_events(queue: JobQueue, job_id: str, interval: float) -> AsyncIterator[JobPublic]:
    import asyncio

    last: tuple[object, ...] | None = None
    while True:
        job = await queue.get(job_id, with_result=False)
        key = (job.state, job.progress.stage, job.progress.iteration, job.progress.completed)
        if key != last:
            last = key
            yield job
        if job.state.terminal:
            return
        await asyncio.sleep(interval)
