"""Soak (slow): 2 000 small jobs through Redis with 2 workers killed at random; nothing lost, nothing twice."""

from __future__ import annotations

import asyncio
import json
import os
import random
import signal
import subprocess
import sys
import time
from collections import Counter
from pathlib import Path
from typing import Any

import pytest

from manifoundation.contract import JobState
from manifoundation.server.queue import create_queue

from .helpers import STAGED, live_workers, run, small_request

JOBS = 2000


@pytest.mark.slow
def test_soak_random_kills(redis_url: str, redis_prefix: str, tmp_path: Path) -> None:
    log_path = tmp_path / "workers.log"
    env = dict(
        os.environ, MANI_REDIS_URL=redis_url, MANI_QUEUE_PREFIX=redis_prefix, MANI_PIPELINE=STAGED,
        MANI_PIPELINE_OPTIONS=json.dumps({"stage_seconds": 0.002, "iterations": 2}), MANI_LOG_LEVEL="INFO",
        MANI_HEARTBEAT_INTERVAL="0.2", MANI_VISIBILITY_TIMEOUT="1.0", MANI_MAX_DELIVERIES="5", MANI_BATCH_SIZE="4",
    )  # fmt: skip
    cmd = [sys.executable, "-m", "manifoundation.cli.main", "worker", "--concurrency", "2"]
    with log_path.open("wb") as log_file:
        supervisor = subprocess.Popen(cmd, env=env, stderr=log_file)
        try:
            outcome = run(_soak(redis_url, redis_prefix))
        finally:
            supervisor.send_signal(signal.SIGTERM)
            supervisor.wait(60)
    states, completed_total, kills = outcome
    assert kills >= 5
    assert len(states) == JOBS  # zero lost: every job is accounted for
    assert set(states.values()) <= {JobState.SUCCEEDED, JobState.FAILED}
    succeeded = sum(s is JobState.SUCCEEDED for s in states.values())
    assert completed_total == succeeded  # counted once each
    finished: Counter[str] = Counter()
    for line in log_path.read_text().splitlines():
        if line.startswith("{"):
            entry = json.loads(line)
            if entry.get("msg") == "job finished" and entry.get("state") == "succeeded":
                finished[entry["job_id"]] += 1
    assert max(finished.values()) == 1  # zero duplicated results
    # a worker killed between committing a result and writing its log line leaves one line fewer
    assert succeeded - kills <= sum(finished.values()) <= succeeded


async def _soak(url: str, prefix: str) -> tuple[dict[str, JobState], int, int]:
    queue = create_queue(url, queue_prefix=prefix, max_queue=JOBS)
    await queue.start()
    rng = random.Random(0)
    try:
        await live_workers(queue, 2)
        ids: list[str] = []
        for start in range(0, JOBS, 100):
            ids += await queue.submit([small_request(i, max_iterations=2) for i in range(start, start + 100)])
        kills, end = 0, time.monotonic() + 240
        pending = set(ids)
        while pending and time.monotonic() < end:
            await asyncio.sleep(rng.uniform(0.3, 1.0))
            workers = await queue.workers()
            busy = [w for w in workers if w.current_job]
            if busy and kills < 20:
                with contextlib_suppress():
                    os.kill(rng.choice(busy).pid, signal.SIGKILL)
                    kills += 1
            for job_id in list(pending)[:400]:
                if (await queue.get(job_id, with_result=False)).state.terminal:
                    pending.discard(job_id)
        done = await asyncio.gather(*(queue.wait(i, 120) for i in ids))
        failed = [j for j in done if j.state is JobState.FAILED]
        assert all(j.error and j.error.error for j in failed)  # failed with a reason
        stats = await queue.stats()
        return {j.id: j.state for j in done}, stats.completed_total, kills
    finally:
        await queue.close()


def contextlib_suppress() -> Any:
    import contextlib

    return contextlib.suppress(ProcessLookupError)
