"""Whether the Redis behind the queue keeps its data across a restart, checked at start-up.

Without AOF (``appendonly no``) and without RDB snapshots (``save ""``) a Redis restart loses every queued and
running job, every result and every registered robot; with RDB snapshots only, whatever was written since the last
snapshot. `mani serve` (through `RedisQueue.start`) and `mani worker` log a warning then. A Redis whose CONFIG
command is disabled or renamed (managed services) cannot be asked: that is logged at INFO and tolerated.
"""

from __future__ import annotations

import logging
from typing import Any

from redis.exceptions import ResponseError

log = logging.getLogger("manifoundation.server.queue.persistence")


def persistence_problem(config: dict[Any, Any]) -> str | None:
    """What a restart of a Redis with this ``CONFIG GET appendonly save`` answer would lose; None: nothing."""
    values = {(k.decode() if isinstance(k, bytes) else k): (v.decode() if isinstance(v, bytes) else v)
              for k, v in config.items()}  # fmt: skip
    if values.get("appendonly", "no") == "yes":
        return None
    if values.get("save", ""):
        return ("Redis has RDB snapshots but no AOF (appendonly no): a restart loses the jobs, results and robots "
                "written since the last snapshot; run redis-server --appendonly yes")  # fmt: skip
    return ("Redis has no persistence (appendonly no, save ''): a restart loses every job, result and registered "
            "robot; run redis-server --appendonly yes")  # fmt: skip


def _report(config: dict[Any, Any] | None, error: Exception | None, url: str) -> str | None:
    if error is not None:
        log.info("could not check Redis persistence at %s (CONFIG unavailable: %s)", url, error)
        return None
    problem = persistence_problem(config or {})
    if problem:
        log.warning(problem, extra={"redis": url})
    return problem


def check_persistence(client: Any, url: str) -> str | None:
    """Log a warning when the Redis behind ``client`` (sync redis-py) would lose data on a restart; returns it."""
    try:
        config = client.config_get("appendonly") | client.config_get("save")
    except ResponseError as exc:  # unknown command: CONFIG disabled or renamed
        return _report(None, exc, url)
    return _report(config, None, url)


async def check_persistence_async(client: Any, url: str) -> str | None:
    """`check_persistence` for an asyncio client."""
    try:
        config = (await client.config_get("appendonly")) | (await client.config_get("save"))
    except ResponseError as exc:
        return _report(None, exc, url)
    return _report(config, None, url)
