"""A registration's deadline stops the work, not only the wait: the worker still loading the robot then answers,
ends itself and is replaced, and a job sent beside it meets its own deadline; on both backends, real workers
(the staged pipeline's ``slow_robot`` takes a minute to load)."""

from __future__ import annotations

import asyncio
import time

import pytest

from manifoundation.contract import JobState, RobotRegister
from manifoundation.server.queue import JobQueue, RobotDeadlineExceeded, create_queue
from manifoundation.server.queue.records import REGISTRATION_GRACE_S
from manifoundation.server.worker.overrun import HARD_STOP_S

from .helpers import STAGED, live_workers, redis_workers, run, small_request, until

URDF = '<robot name="r"><link name="a"/><link name="b"/><joint name="j" type="revolute"><parent link="a"/>' \
       '<child link="b"/><limit lower="0" upper="1"/></joint></robot>'  # fmt: skip
OPTIONS = {"slow_robot": "slow", "robot_seconds": 60.0}
DEADLINE_S = 2.0


def robot(name: str) -> RobotRegister:
    return RobotRegister(name=name, urdf=URDF, fingertips=["b"])


async def _check(queue: JobQueue) -> None:
    before = {w.id for w in await live_workers(queue, 2)}
    t0 = time.monotonic()
    registering = asyncio.ensure_future(queue.register_robot(robot("slow"), timeout=DEADLINE_S, owner="k"))
    await asyncio.sleep(0.3)  # the registration is with a worker now
    [job_id] = await queue.submit([small_request(1)], deadline=time.time() + DEADLINE_S)
    job = await until(queue, job_id, lambda j: j.state.terminal, timeout=10)
    assert job.state is JobState.SUCCEEDED, job.error  # the other worker ran it: it never queued behind the robot
    with pytest.raises(RobotDeadlineExceeded, match=r"registration deadline of 2 s passed .* stopped and replaced"):
        await registering
    assert DEADLINE_S - 0.1 < time.monotonic() - t0 < DEADLINE_S + HARD_STOP_S + 1.0
    end = time.monotonic() + 30
    while True:  # the worker that loaded it is gone, another took its place
        now = {w.id for w in await queue.workers()}
        if len(now) == 2 and len(now - before) == 1:
            break
        assert time.monotonic() < end, f"workers {before} -> {now}"
        await asyncio.sleep(0.1)
    assert (await queue.register_robot(robot("quick"), timeout=DEADLINE_S, owner="k")).name == "quick"
    assert [r.name for r in await queue.list_robots(owner="k") if not r.builtin] == ["quick"]
    [job_id] = await queue.submit([small_request(2)], deadline=time.time() + DEADLINE_S)
    assert (await until(queue, job_id, lambda j: j.state.terminal, timeout=10)).state is JobState.SUCCEEDED


def test_embedded_registration_stopped_at_its_deadline() -> None:
    async def main() -> None:
        queue = create_queue(None, redis_url=None, concurrency=2, pipeline=STAGED, pipeline_options=OPTIONS)
        await queue.start()
        try:
            await _check(queue)
        finally:
            await queue.close()

    run(main())


def test_redis_registration_stopped_at_its_deadline(redis_url: str, redis_prefix: str) -> None:
    async def main() -> None:
        queue = create_queue(redis_url, queue_prefix=redis_prefix, concurrency=0)
        await queue.start()
        try:
            await _check(queue)
        finally:
            await queue.close()

    options = {"pipeline_options": OPTIONS, "heartbeat_interval": 0.5}
    with redis_workers(redis_url, redis_prefix, concurrency=2, **options):
        run(main())


def test_late_registration_is_not_loaded() -> None:
    """A registration whose deadline passed while it waited for a worker is answered at once, not loaded."""
    from manifoundation.contract.codec import pack
    from manifoundation.server.worker.core import WorkerCore
    from research.staged_pipeline import StagedPipeline

    core = WorkerCore(StagedPipeline(**OPTIONS))  # type: ignore[arg-type]
    t0 = time.monotonic()
    answer = core.validate_robot(pack(robot("slow").model_dump(mode="python", exclude_none=True)), time.time() - 1)
    assert answer["type"] == "DeadlineExceeded" and "no worker was free" in answer["error"]
    assert time.monotonic() - t0 < 1.0
    assert REGISTRATION_GRACE_S > HARD_STOP_S  # the service waits past the hard stop before answering itself
