"""The Redis backend under faults, each on a private redis-server: Redis restarts while jobs run (with AOF),
a poison job among innocent batch-mates, a dead worker's jobs redelivered by heartbeat, a hung (SIGSTOPped)
Redis."""

from __future__ import annotations

import asyncio
import contextlib
import os
import re
import signal
import time
from pathlib import Path

import pytest

from manifoundation.contract import JobState
from manifoundation.server.queue import QueueUnavailable, create_queue
from manifoundation.server.queue.redis import RedisQueue

from .helpers import (
    assert_only_the_poison_dead_lettered,
    live_workers,
    redis_workers,
    run,
    running,
    small_request,
    until,
)
from .redis_server import redis_server

FAST = {"heartbeat_interval": 0.2, "visibility_timeout": 1.5}


def client(url: str, **options: object) -> RedisQueue:
    queue = create_queue(url, queue_prefix="mani:", **options)
    assert isinstance(queue, RedisQueue)
    return queue


@pytest.mark.parametrize(
    "sig", [signal.SIGTERM, pytest.param(signal.SIGKILL, marks=pytest.mark.slow)], ids=["sigterm", "kill-9"]
)  # the same recovery path; kill -9 in the slow run
def test_jobs_running_through_a_redis_restart_finish(tmp_path: Path, sig: int) -> None:
    """Redis (AOF) goes away while a batch runs and comes back: the worker writes the results it could not
    write while Redis was down; nothing stays "running" and nothing runs twice."""

    async def main() -> None:
        with redis_server(tmp_path, appendonly=True) as server:
            queue = client(server.url)
            await queue.start()
            options = {"stage_seconds": 0.1, "iterations": 3}
            with redis_workers(server.url, "mani:", pipeline_options=options, batch_size=4, **FAST):
                try:
                    await live_workers(queue, 1)
                    ids = await queue.submit([small_request(i) for i in range(4)])
                    await asyncio.gather(*(until(queue, i, running) for i in ids))
                    server.stop(sig)
                    await asyncio.sleep(3.0)  # the batch (≈ 2 s) ends while Redis is down
                    server.start()
                    jobs = await asyncio.gather(*(queue.wait(i, 20) for i in ids))
                    assert [(j.state, j.deliveries) for j in jobs] == [(JobState.SUCCEEDED, 1)] * 4
                finally:
                    await queue.close()

    run(main())


@pytest.mark.slow  # the embedded twin (tests/worker/test_embedded.py) holds the same rule in the default suite
def test_poison_job_fails_no_batch_mate(tmp_path: Path) -> None:
    """A job that kills its worker in a micro-batch of 4: only it is dead-lettered; its batch-mates are
    re-delivered one at a time, run alone and succeed."""

    async def main() -> None:
        with redis_server(tmp_path) as server:
            queue = client(server.url)
            await queue.start()
            try:
                ids = await queue.submit([small_request(s) for s in (1, 2, 666, 3)])  # queued before any worker
                opts = {"crash_seed": 666}
                with redis_workers(server.url, "mani:", pipeline_options=opts, batch_size=4, **FAST):
                    jobs = await asyncio.gather(*(queue.wait(i, 90) for i in ids))
                await assert_only_the_poison_dead_lettered(queue, list(jobs), ids[2])
            finally:
                await queue.close()

    run(main())


@pytest.mark.slow  # the API's twin (tests/api/test_faults.py: a hung Redis gives 503) runs in the default suite
def test_a_hung_redis_answers_unavailable_within_the_timeout(tmp_path: Path) -> None:
    """SIGSTOPped Redis (the port open, nothing answering): every call fails with QueueUnavailable within
    OP_ROUNDS × redis_timeout, and the queue works again once Redis resumes."""

    async def main() -> None:
        with redis_server(tmp_path) as server:
            queue = client(server.url, redis_timeout=0.5)
            await queue.start()
            try:
                [job_id] = await queue.submit([small_request()])
                server.pause()
                t0 = time.monotonic()
                assert not await queue.ping()
                assert time.monotonic() - t0 < 1.5
                calls = {
                    "submit": queue.submit([small_request()]),
                    "get": queue.get(job_id),
                    "list_recent": queue.list_recent(10),
                    "stats": queue.stats(),
                    "list_robots": queue.list_robots(),
                    "room": queue.room(),
                }
                for name, call in calls.items():
                    t0 = time.monotonic()
                    with pytest.raises(QueueUnavailable):
                        await call
                    assert time.monotonic() - t0 < 2.5, name
                server.resume()
                assert (await queue.get(job_id)).state is JobState.QUEUED
                assert len(await queue.submit([small_request()])) == 1
            finally:
                server.resume()
                await queue.close()

    run(main())


def test_a_dead_workers_job_is_redelivered_by_heartbeat_not_visibility_timeout(tmp_path: Path) -> None:
    """kill -9 of the worker running a job, visibility timeout 60 s: a live worker sees the dead one's heartbeat
    key expire (1 s here) and takes the job over within seconds."""

    async def main() -> None:
        with redis_server(tmp_path) as server:
            queue = client(server.url)
            await queue.start()
            slow = {"stage_seconds": 0.2, "iterations": 10}
            settings = {"heartbeat_interval": 0.2, "visibility_timeout": 60, "batch_size": 1}
            with redis_workers(server.url, "mani:", 2, pipeline_options=slow, **settings):
                try:
                    await live_workers(queue, 2)
                    [job_id] = await queue.submit([small_request(1, max_iterations=3)])
                    job = await until(queue, job_id, running)
                    victim = next(w for w in await queue.workers() if w.id == job.worker)
                    os.kill(victim.pid, signal.SIGKILL)
                    t0 = time.monotonic()
                    job = await queue.wait(job_id, 30)
                    assert job.state is JobState.SUCCEEDED and job.deliveries == 2 and job.worker != victim.id
                    assert time.monotonic() - t0 < 10, "re-delivered by the visibility timeout, not the heartbeat"
                finally:
                    await queue.close()

    run(main())


def test_redis_at_maxmemory_is_said_plainly_without_its_internals(tmp_path: Path) -> None:
    """A Redis out of memory refuses the submission script's writes: the caller's 503 says so in plain words, not
    with the Lua script's SHA (issue 62, item 9)."""

    async def main() -> str:
        with redis_server(tmp_path, extra=("--maxmemory", "2mb", "--maxmemory-policy", "noeviction")) as server:
            queue = client(server.url)
            await queue.start()
            try:
                big = [small_request(i) for i in range(64)]
                for _ in range(200):
                    await queue.submit(big)
            except QueueUnavailable as exc:
                return str(exc)
            finally:
                await queue.close()
        raise AssertionError("Redis never refused a write")

    message = asyncio.run(main())
    assert "out of memory" in message and "maxmemory" in message, message
    assert not re.search(r"[0-9a-f]{40}", message) and "script" not in message, message


def _fill(url: str, n: int = 0) -> int:
    """Fill a noeviction Redis with filler keys `filler:n`, `filler:n+1`, … until it refuses a write; the next free
    index (call again with it to top Redis up when its memory use has dropped)."""
    import redis

    raw = redis.Redis.from_url(url)
    try:
        for size in (16_384, 1024, 64):  # down to the last few bytes: even a small outcome is refused
            with contextlib.suppress(redis.exceptions.OutOfMemoryError):
                while n < 100_000:
                    raw.set(f"filler:{n}", b"x" * size)
                    n += 1
    finally:
        raw.close()
    return n


def _free(url: str, n: int) -> None:
    import redis

    raw = redis.Redis.from_url(url)
    raw.delete(*[f"filler:{i}" for i in range(n)])
    raw.close()


@pytest.mark.parametrize("when", ["delivery", "outcome"])
def test_writes_refused_at_maxmemory_are_retried_not_left_for_the_visibility_timeout(tmp_path: Path, when: str) -> None:
    """Redis reaches maxmemory (noeviction) when a worker takes a batch (its BEGIN writes are refused) or while the
    batch runs (its outcome writes are refused). The worker retries them with a short back-off, so once memory is
    freed the jobs end within seconds, not after the visibility timeout (issue 62, item 9: a job and its 4
    batch-mates sat ~52 s)."""

    async def main() -> tuple[float, list[JobState]]:
        extra = ("--maxmemory", "4mb", "--maxmemory-policy", "noeviction")
        with redis_server(tmp_path, extra=extra) as server:
            queue = client(server.url)
            await queue.start()
            iterations = 16 if when == "outcome" else 2  # ≈ 6 s: still running once Redis is full, under load too
            ids = await queue.submit([small_request(i) for i in range(4)])
            filled = await asyncio.to_thread(_fill, server.url) if when == "delivery" else 0
            options = {"stage_seconds": 0.1, "iterations": iterations}
            log = open(tmp_path / "worker.log", "wb")  # noqa: SIM115
            try:
                with redis_workers(
                    server.url, "mani:", pipeline_options=options, batch_size=4,
                    heartbeat_interval=0.2, visibility_timeout=20, stderr=log, log_level="INFO",
                ):  # fmt: skip
                    if when == "outcome":
                        await asyncio.gather(*(until(queue, i, running) for i in ids))
                        filled = await asyncio.to_thread(_fill, server.url)
                        jobs = await asyncio.gather(*(queue.get(i, with_result=False) for i in ids))
                        assert all(job.state is JobState.RUNNING for job in jobs), (
                            "the batch ended before Redis was full"
                        )
                    for _ in range(150):  # until the worker meets a refusal (≤ 30 s, load or not)
                        if "maxmemory" in (tmp_path / "worker.log").read_text(errors="replace"):
                            break
                        await asyncio.sleep(0.2)
                        filled = await asyncio.to_thread(_fill, server.url, filled)  # memory use may have dropped
                    await asyncio.to_thread(_free, server.url, filled)
                    freed = time.monotonic()
                    jobs = await asyncio.gather(*(queue.wait(i, 30) for i in ids))
                    return time.monotonic() - freed, [job.state for job in jobs]
            finally:
                log.close()
                await queue.close()

    after_free, states = run(main())
    refusals = (tmp_path / "worker.log").read_text().count("maxmemory")
    assert states == [JobState.SUCCEEDED] * 4, states
    assert after_free < 5.0, f"the jobs ended {after_free:.1f} s after memory was freed (visibility timeout: 20 s)"
    assert refusals, "the worker met no refusal: Redis was not full when it wrote"
