"""`mani worker`: run Redis Streams worker processes (scale-out; the embedded backend runs its own inside
`mani serve`). A small supervisor starts ``--concurrency`` worker processes (`manifoundation.server.worker.worker`),
restarts one that dies (a crashed job is re-delivered to a live worker), and on SIGTERM/SIGINT forwards SIGTERM so each
finishes its current batch, then exits.

Example::

    MANI_REDIS_URL=redis://localhost:6379/0 mani worker --concurrency 2 --batch-size 4 --max-wait-ms 5
"""

from __future__ import annotations

import argparse
import logging
import os
import signal
import sys
import time
from collections.abc import Callable
from typing import Any

from manifoundation.server.worker.supervisor import Child, CrashLoop, spawn_ready, stop_all

log = logging.getLogger("manifoundation.server.worker.cli")
GRACE_S = 120.0


def register(subparsers: Any) -> None:
    """Add the ``worker`` sub-command to `mani`'s sub-parsers."""
    parser = subparsers.add_parser(
        "worker",
        help="run queue workers against Redis (scale-out)",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--redis", metavar="URL", help="Redis URL (default: $MANI_REDIS_URL)")
    parser.add_argument(
        "--queue", metavar="PREFIX", help="key prefix of the queue (default: $MANI_QUEUE_PREFIX, mani:)"
    )
    parser.add_argument("--concurrency", type=int, metavar="N", help="worker processes (default 1)")
    parser.add_argument("--batch-size", type=int, metavar="B", help="jobs taken at once (network micro-batch)")
    parser.add_argument("--max-wait-ms", type=float, metavar="MS", help="wait this long to fill a batch")
    parser.add_argument("--pipeline", metavar="MODULE:ATTR", help="pipeline (default: the models pipeline)")
    parser.set_defaults(func=main)


def main(args: argparse.Namespace) -> int:
    """Run the supervisor until SIGTERM/SIGINT; exit code 0, or 2 on bad settings."""
    from pydantic import ValidationError

    from manifoundation.server.queue import queue_settings
    from manifoundation.server.worker.logs import setup_logging

    overrides = {
        "redis_url": args.redis, "queue_prefix": args.queue, "concurrency": args.concurrency,
        "batch_size": args.batch_size, "max_wait_ms": args.max_wait_ms, "pipeline": args.pipeline,
    }  # fmt: skip
    try:
        settings = queue_settings(None, **{k: v for k, v in overrides.items() if v is not None})
    except ValidationError as exc:
        print(f"mani worker: invalid settings: {exc}", file=sys.stderr)
        return 2
    if not settings.redis_url:
        print(
            "mani worker: needs --redis or MANI_REDIS_URL (embedded workers run inside `mani serve`)", file=sys.stderr
        )
        return 2
    setup_logging(settings.log_level, f"supervisor-{os.getpid()}")
    warn_without_persistence(settings.redis_url, settings.redis_timeout)
    return supervise(settings.model_dump_json(), max(1, settings.concurrency))


def warn_without_persistence(url: str, timeout: float) -> None:
    """Log a warning when the Redis at ``url`` would lose the queue on a restart (no AOF, no snapshots)."""
    import redis

    from manifoundation.server.queue.persistence import check_persistence
    from manifoundation.server.queue.redis import _safe_url

    client = redis.Redis.from_url(url, socket_connect_timeout=timeout, socket_timeout=timeout)
    try:
        check_persistence(client, _safe_url(url))
    except redis.RedisError as exc:  # not up yet: the workers wait for it
        log.warning("Redis at %s does not answer yet: %s", _safe_url(url), exc)
    finally:
        client.close()


def supervise(settings_json: str, concurrency: int) -> int:
    """Keep ``concurrency`` worker processes alive until told to stop."""
    return keep_alive(lambda _slot: spawn_ready("manifoundation.server.worker.worker", settings_json), concurrency)


def keep_alive(start: Callable[[int], Child], concurrency: int) -> int:
    """Run ``start(slot)`` for each slot and start it again whenever its process exits, until SIGTERM/SIGINT;
    a slot that keeps dying before its worker is ready waits its `CrashLoop` back-off, without holding up the
    others."""
    stopping = False

    def stop(*_: object) -> None:
        nonlocal stopping
        stopping = True

    signal.signal(signal.SIGTERM, stop)
    signal.signal(signal.SIGINT, stop)
    children = [start(slot) for slot in range(concurrency)]
    crash_loop = CrashLoop()
    restart_at: dict[int, float] = {}  # slot -> when its exited worker is started again
    log.info("started %d workers", concurrency)
    while not stopping:
        time.sleep(0.1)
        now = time.monotonic()
        for slot, child in enumerate(children):
            if slot in restart_at:
                if now >= restart_at[slot]:
                    del restart_at[slot]
                    children[slot] = start(slot)
                continue
            code = child.process.poll()
            if code is not None and not stopping:
                log.warning("worker pid %d exited with code %s; restarting", child.process.pid, code)
                restart_at[slot] = now + crash_loop.delay(slot, now - child.born, child.ready())
    stop_all([child.process for child in children], GRACE_S)
    log.info("workers stopped")
    return 0
