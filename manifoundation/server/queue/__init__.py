"""Job queue backends (torch-free: the service imports this package).

Factory::

    create_queue(settings=None, **options) -> JobQueue

``settings`` is a `QueueSettings`, any object with matching attributes (e.g. the service's own settings: the fields it
shares with `QueueSettings`, such as ``redis_url``, are taken), a Redis URL string, or None (read ``MANI_*`` from the
environment). ``options`` override single fields (``concurrency=2``, ``max_queue=100``,
``pipeline="research.staged_pipeline:StagedPipeline"``, ...). With a ``redis_url`` the answer is a `RedisQueue` (durable
with AOF, scale-out: run `mani worker` processes against the same URL and ``queue_prefix``); without one an
`EmbeddedQueue` that spawns ``concurrency`` worker processes in `start()` (non-durable: jobs and results live in
memory). Call ``await queue.start()`` before use and ``await queue.close()`` at the end.
"""

from __future__ import annotations

from typing import Any

from manifoundation.server.queue.base import (
    JobNotFound,
    JobQueue,
    QueueError,
    QueueFull,
    QueueUnavailable,
    RobotDeadlineExceeded,
    RobotInvalid,
    RobotLimitReached,
    RobotLimits,
)
from manifoundation.server.worker.settings import QueueSettings


def queue_settings(settings: object | str | None = None, **options: Any) -> QueueSettings:
    """Resolve the factory's arguments into one validated `QueueSettings`."""
    if isinstance(settings, QueueSettings):
        base = settings.model_dump()
    elif settings is None:
        base = QueueSettings().model_dump()
    elif isinstance(settings, str):
        base = QueueSettings().model_dump() | {"redis_url": settings}
    else:
        base = QueueSettings().model_dump()
        for name in QueueSettings.model_fields:
            if hasattr(settings, name):
                base[name] = getattr(settings, name)
    return QueueSettings.model_validate(base | options)


def create_queue(settings: object | str | None = None, **options: Any) -> JobQueue:
    """A `RedisQueue` when a Redis URL is configured, else an `EmbeddedQueue` (see module doc)."""
    resolved = queue_settings(settings, **options)
    if resolved.redis_url:
        from manifoundation.server.queue.redis import RedisQueue

        return RedisQueue(resolved)
    from manifoundation.server.queue.embedded import EmbeddedQueue

    return EmbeddedQueue(resolved)


__all__ = [
    "JobNotFound",
    "JobQueue",
    "QueueError",
    "QueueFull",
    "QueueSettings",
    "QueueUnavailable",
    "RobotDeadlineExceeded",
    "RobotInvalid",
    "RobotLimitReached",
    "RobotLimits",
    "create_queue",
    "queue_settings",
]
