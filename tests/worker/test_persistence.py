"""`mani serve` (RedisQueue.start) and `mani worker` warn at start when Redis would lose the queue on a restart,
and tolerate a Redis whose CONFIG command is disabled; without AOF a restart loses everything (as documented)."""

from __future__ import annotations

import logging
import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

from manifoundation.server.queue import JobNotFound, create_queue

from .helpers import STAGED, run, small_request
from .redis_server import redis_server


@pytest.mark.parametrize(
    ("appendonly", "extra", "expected"),
    [
        (False, (), "no persistence"),
        (False, ("--save", "3600 1"), "RDB snapshots but no AOF"),
        (True, (), None),
        (False, ("--rename-command", "CONFIG", ""), None),
    ],
    ids=["none", "rdb-only", "aof", "config-disabled"],
)
def test_serve_warns_without_persistence(
    tmp_path: Path, caplog: pytest.LogCaptureFixture, appendonly: bool, extra: tuple[str, ...], expected: str | None
) -> None:
    async def main() -> None:
        queue = create_queue(server.url, queue_prefix="mani:")
        await queue.start()
        [job_id] = await queue.submit([small_request()])  # the queue works either way
        assert (await queue.get(job_id)).state.value == "queued"
        await queue.close()

    with redis_server(tmp_path, appendonly=appendonly, extra=extra) as server, caplog.at_level(logging.INFO):
        run(main())
    warnings = [r.getMessage() for r in caplog.records if r.levelno >= logging.WARNING]
    if expected is None:
        assert not [w for w in warnings if "persistence" in w or "AOF" in w], warnings
    else:
        assert any(expected in w for w in warnings), warnings


def test_worker_warns_without_persistence(tmp_path: Path) -> None:
    with redis_server(tmp_path) as server:
        env = dict(os.environ, MANI_REDIS_URL=server.url, MANI_PIPELINE=STAGED, MANI_LOG_LEVEL="WARNING")
        log_path = tmp_path / "worker.log"
        with log_path.open("wb") as sink:
            proc = subprocess.Popen([sys.executable, "-m", "manifoundation.cli.main", "worker"], env=env, stderr=sink)
            try:
                end = time.monotonic() + 30
                while "no persistence" not in log_path.read_text():
                    assert time.monotonic() < end, log_path.read_text()
                    time.sleep(0.1)
            finally:
                proc.terminate()
                proc.wait(30)


def test_a_restart_without_aof_loses_the_jobs(tmp_path: Path) -> None:
    """What manifoundation/server/api/README.md says: without persistence a Redis restart forgets every job."""

    async def main() -> None:
        queue = create_queue(server.url, queue_prefix="mani:")
        await queue.start()
        try:
            [job_id] = await queue.submit([small_request()])
            server.stop()
            server.start()
            with pytest.raises(JobNotFound):
                await queue.get(job_id)
        finally:
            await queue.close()

    with redis_server(tmp_path) as server:
        run(main())
