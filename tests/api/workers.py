"""Real queue backends for the end-to-end tests: embedded (workers spawned by the queue) or Redis Streams
(workers as separate `mani worker` processes, keys under the test's prefix)."""

from __future__ import annotations

import contextlib
import json
import os
import subprocess
import sys
import uuid
from collections.abc import Iterator
from typing import Any

import pytest

from manifoundation.server.queue import JobQueue, create_queue

STAGED = "research.staged_pipeline:StagedPipeline"


@contextlib.contextmanager
def start_queue_and_workers(
    request: pytest.FixtureRequest,
    *,
    pipeline: str = STAGED,
    max_queue: int = 100,
    worker_logs: bool = False,
    **pipeline_options: Any,
) -> Iterator[JobQueue]:
    """A queue (not yet started: the app's lifespan starts it) with one worker behind it. ``worker_logs``: the
    worker logs at INFO to the test's own stderr (for ``capfd``) instead of warnings only to a pipe."""
    backend = request.param if hasattr(request, "param") else "embedded"
    options: dict[str, Any] = {"pipeline": pipeline, "pipeline_options": pipeline_options, "max_queue": max_queue}
    if worker_logs:
        options["log_level"] = "INFO"
    if backend == "embedded":
        yield create_queue(None, redis_url=None, concurrency=1, **options)
        return
    url = request.getfixturevalue("redis_url")
    prefix = f"mani-test:{uuid.uuid4().hex[:12]}:"  # module-scoped twin of conftest's `redis_prefix`
    env = dict(
        os.environ,
        MANI_REDIS_URL=url,
        MANI_QUEUE_PREFIX=prefix,
        MANI_PIPELINE=pipeline,
        MANI_PIPELINE_OPTIONS=json.dumps(pipeline_options),
        MANI_LOG_LEVEL="INFO" if worker_logs else "WARNING",
    )
    cmd = [sys.executable, "-m", "manifoundation.cli.main", "worker", "--redis", url, "--concurrency", "1"]
    stderr = None if worker_logs else subprocess.PIPE
    worker = subprocess.Popen(cmd, env=env, stdout=subprocess.DEVNULL, stderr=stderr)
    try:
        yield create_queue(url, queue_prefix=prefix, concurrency=0, **options)
    finally:
        worker.terminate()
        try:
            worker.wait(timeout=30)
        except subprocess.TimeoutExpired:
            worker.kill()
        _delete_prefix(url, prefix)


def _delete_prefix(url: str, prefix: str) -> None:
    import redis

    client = redis.Redis.from_url(url)
    keys = list(client.scan_iter(match=prefix + "*", count=1000))
    if keys:
        client.delete(*keys)
    client.close()
