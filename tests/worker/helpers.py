"""Shared helpers of the workers tests: small valid requests, an asyncio runner, workers' JSON log lines."""

from __future__ import annotations

import asyncio
import contextlib
import json
import os
import subprocess
import sys
import time
from collections.abc import Awaitable, Callable, Iterator
from typing import Any, TypeVar

import numpy as np

from manifoundation.contract import JobPublic, JobState, SynthesisRequest, WorkerPublic
from manifoundation.server.queue import JobQueue

STAGED = "research.staged_pipeline:StagedPipeline"
T = TypeVar("T")


def small_request(seed: int = 0, hand: str = "test_gripper", **options: Any) -> SynthesisRequest:
    """A valid 64-point sphere request (force closure)."""
    rng = np.random.default_rng(seed)
    points = rng.normal(size=(64, 3))
    points = 0.03 * points / np.linalg.norm(points, axis=1, keepdims=True)
    return SynthesisRequest.model_validate(
        {
            "object": {"points": points, "normals": points / 0.03},
            "task": {"kind": "force_closure"},
            "robot": {"name": hand},
            "options": {"seed": seed, "method": "direct_grasp", **options},
        }
    )


def run(coro: Awaitable[T]) -> T:
    return asyncio.run(coro)  # type: ignore[arg-type]


async def until(queue: JobQueue, job_id: str, check: Callable[[JobPublic], bool], timeout: float = 20) -> JobPublic:
    """Poll a job until ``check`` holds (fails the test after ``timeout`` s)."""
    deadline = time.monotonic() + timeout
    while True:
        job = await queue.get(job_id, with_result=False)
        if check(job):
            return job
        if time.monotonic() > deadline:
            raise AssertionError(f"job {job_id} stuck in {job.state} / {job.progress}")
        await asyncio.sleep(0.01)


async def assert_only_the_poison_dead_lettered(queue: JobQueue, jobs: list[JobPublic], poison_id: str) -> None:
    """The job that killed its worker failed as WorkerLost and is the only dead letter; each of its batch-mates
    was given back once and succeeded on its second delivery."""
    mates = {j.id: j for j in jobs}
    poison = mates.pop(poison_id)
    assert poison.state is JobState.FAILED and poison.error and poison.error.type == "WorkerLost"
    assert [(j.state, j.deliveries) for j in mates.values()] == [(JobState.SUCCEEDED, 2)] * len(mates)
    assert [d.job_id for d in await queue.dead_letters()] == [poison_id]


def running(job: JobPublic) -> bool:
    return job.state is JobState.RUNNING and job.progress.stage.value != "queued"


@contextlib.contextmanager
def redis_workers(
    url: str, prefix: str, concurrency: int = 1, *, stderr: Any = None, **settings: Any
) -> Iterator[subprocess.Popen[bytes]]:
    """`mani worker` (the supervisor and its worker processes) on ``url``/``prefix`` running the staged pipeline;
    ``settings``: any `QueueSettings` field (``pipeline_options`` as a dict); ``stderr``: where their JSON log
    lines go (a file, to read them; default: the test's own stderr)."""
    env = dict(os.environ, MANI_REDIS_URL=url, MANI_QUEUE_PREFIX=prefix, MANI_PIPELINE=STAGED, MANI_LOG_LEVEL="WARNING")
    for name, value in settings.items():
        env[f"MANI_{name.upper()}"] = json.dumps(value) if isinstance(value, dict) else str(value)
    cmd = [sys.executable, "-m", "manifoundation.cli.main", "worker", "--concurrency", str(concurrency)]
    proc = subprocess.Popen(cmd, env=env, stderr=stderr)
    try:
        yield proc
    finally:
        proc.terminate()
        try:
            proc.wait(timeout=30)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


async def live_workers(queue: JobQueue, count: int, timeout: float = 30) -> list[WorkerPublic]:
    """Wait until ``count`` workers send heartbeats."""
    end = time.monotonic() + timeout
    while True:
        workers = await queue.workers()
        if len(workers) >= count:
            return workers
        if time.monotonic() > end:
            raise AssertionError(f"{len(workers)} of {count} workers came up")
        await asyncio.sleep(0.05)


def log_lines(text: str) -> list[dict[str, Any]]:
    """The JSON log lines of a worker's stderr (other output skipped)."""
    return [json.loads(line) for line in text.splitlines() if line.startswith("{")]


async def logged(
    read: Callable[[], str], check: Callable[[dict[str, Any]], bool], count: int = 1, timeout: float = 20
) -> list[dict[str, Any]]:
    """The log lines satisfying ``check``, once there are ``count``; ``read`` answers what was written since its last
    call (``capfd.readouterr().err``, an open file's ``read``). A worker writes its "job finished" line just after
    it hands the outcome back, so the line may trail the job's end by a moment."""
    deadline = time.monotonic() + timeout
    text = ""
    while True:
        text += read()
        found = [entry for entry in log_lines(text[: text.rfind("\n") + 1]) if check(entry)]  # whole lines only
        if len(found) >= count:
            return found
        if time.monotonic() > deadline:
            raise AssertionError(f"no such log line in:\n{text[-3000:]}")
        await asyncio.sleep(0.05)
