"""RedisQueue + `mani worker` against a real Redis (keys under the test's prefix), staged test pipeline."""

from __future__ import annotations

import asyncio
import os
import shutil
import signal
import socket
import subprocess
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
import redis

from manifoundation.contract import JobState, RobotRegister, Stage
from manifoundation.server.queue import JobNotFound, QueueFull, RobotInvalid, create_queue
from manifoundation.server.queue.redis import RedisQueue
from manifoundation.server.spool import SpooledRequest, new_spool, payload_files, remove_spool

from .helpers import live_workers, log_lines, logged, redis_workers, run, running, small_request, until

URDF = """<robot name="g"><link name="base"/><link name="tip"/>
<joint name="j" type="revolute"><parent link="base"/><child link="tip"/><limit lower="0" upper="1"/></joint></robot>"""
FAST = {"heartbeat_interval": 0.2, "visibility_timeout": 1.5}


def client(url: str, prefix: str, **options: object) -> RedisQueue:
    queue = create_queue(url, queue_prefix=prefix, **options)
    assert isinstance(queue, RedisQueue)
    return queue


def test_round_trip_progress_robots(redis_url: str, redis_prefix: str) -> None:
    async def main() -> None:
        queue = client(redis_url, redis_prefix)
        await queue.start()
        with redis_workers(redis_url, redis_prefix, pipeline_options={"stage_seconds": 0.05}, **FAST) as supervisor:
            try:
                await live_workers(queue, 1)
                [job_id] = await queue.submit([small_request(1)])
                seen = await until(queue, job_id, lambda j: j.progress.stage is Stage.REFINEMENT)
                assert seen.state is JobState.RUNNING and seen.progress.max_iterations == 3
                job = await queue.wait(job_id, 10)
                assert job.state is JobState.SUCCEEDED and job.deliveries == 1 and job.progress.stage is Stage.DONE
                assert job.result is not None and job.result.hand == "test_gripper" and "queue" in job.timings
                spool = new_spool()  # a request a body process packed already: Redis takes its bytes and its file
                spooled = SpooledRequest.write(spool, small_request(3, max_iterations=1))
                batch = await queue.create_batch([*(small_request(i, max_iterations=1) for i in range(3)), spooled])
                assert payload_files(spool) == []
                remove_spool(spool)
                ids = await queue.batch_job_ids(batch)
                done = await asyncio.gather(*(queue.wait(i, 10) for i in ids))
                assert [j.state for j in done] == [JobState.SUCCEEDED] * 4 and {j.batch_id for j in done} == {batch}
                assert [j.id for j in await queue.list_recent(5)] == [*ids[::-1], job_id]
                stats = await queue.stats()
                assert (stats.completed_total, stats.depth, stats.running, stats.workers) == (5, 0, 0, 1)
                assert [r.name for r in await queue.list_robots()] == ["test_gripper"]
                robot = await queue.register_robot(RobotRegister(name="mine", urdf=URDF, fingertips=["tip"]))
                assert robot.dof == 1 and {r.name for r in await queue.list_robots()} == {"test_gripper", "mine"}
                with pytest.raises(RobotInvalid, match="unknown links"):
                    await queue.register_robot(RobotRegister(name="bad", urdf=URDF, fingertips=["nope"]))
                with pytest.raises(JobNotFound):
                    await queue.get("0" * 32)
                # SIGTERM: the running job is finished, then the workers exit
                [job_id] = await queue.submit([small_request(5)])
                await until(queue, job_id, running)
                supervisor.send_signal(signal.SIGTERM)
                assert (await queue.wait(job_id, 20)).state is JobState.SUCCEEDED
                assert await asyncio.get_running_loop().run_in_executor(None, supervisor.wait, 30) == 0
            finally:
                await queue.close()

    run(main())


def test_full_queue_cancel_queued_deadline_and_expiry(redis_url: str, redis_prefix: str) -> None:
    async def main() -> None:
        queue = client(redis_url, redis_prefix, max_queue=3, result_ttl=0.5)
        await queue.start()
        try:
            a, b = await queue.submit([small_request(), small_request()])
            with pytest.raises(QueueFull):
                await queue.submit([small_request(), small_request()])  # all or none
            assert (await queue.stats()).depth == 2
            assert (await queue.cancel(a)).state is JobState.CANCELLED
            assert (await queue.stats()).depth == 1  # the cancelled entry left the stream
            [late] = await queue.submit([small_request()], deadline=time.time() + 0.1)
            await asyncio.sleep(0.2)
            job = await queue.get(late)
            assert job.state is JobState.EXPIRED and job.error and job.error.type == "DeadlineExceeded"
            with redis_workers(redis_url, redis_prefix, **FAST):
                done = await queue.wait(b, 20)
                assert done.state is JobState.SUCCEEDED and done.result is not None
                await asyncio.sleep(0.7)  # past result_ttl
                gone = await queue.get(b)
                assert gone.state is JobState.EXPIRED and gone.error and gone.error.type == "ResultExpired"
        finally:
            await queue.close()

    run(main())


def test_cancel_running_kill_redelivery_and_long_job_not_stolen(redis_url: str, redis_prefix: str) -> None:
    async def main() -> None:
        queue = client(redis_url, redis_prefix)
        await queue.start()
        options = {"stage_seconds": 0.2, "iterations": 20}
        with redis_workers(redis_url, redis_prefix, 2, pipeline_options=options, batch_size=1, **FAST):
            try:
                await live_workers(queue, 2)
                [job_id] = await queue.submit([small_request(1)])
                await until(queue, job_id, running)
                await queue.cancel(job_id)
                job = await queue.wait(job_id, 10)
                assert job.state is JobState.CANCELLED and job.error and job.error.type == "Cancelled"
                # 2 s jobs with a 1.5 s visibility timeout: heartbeats keep them with their worker
                long_ids = await queue.submit([small_request(i, max_iterations=8) for i in range(2)])
                jobs = await asyncio.gather(*(queue.wait(i, 20) for i in long_ids))
                assert [(j.state, j.deliveries) for j in jobs] == [(JobState.SUCCEEDED, 1)] * 2
                # kill -9 the worker running a job: re-delivered and completed once
                [job_id] = await queue.submit([small_request(3, max_iterations=3)])
                job = await until(queue, job_id, running)
                victim = next(w for w in await queue.workers() if w.id == job.worker)
                os.kill(victim.pid, signal.SIGKILL)
                job = await queue.wait(job_id, 30)
                assert job.state is JobState.SUCCEEDED and job.deliveries == 2 and job.worker != victim.id
                assert (await queue.stats()).completed_total == 3
            finally:
                await queue.close()

    run(main())


def test_poison_job_dead_letters_after_n_deliveries(redis_url: str, redis_prefix: str) -> None:
    async def main() -> None:
        queue = client(redis_url, redis_prefix)
        await queue.start()
        opts = {"crash_seed": 666}
        fast = {"heartbeat_interval": 0.2, "visibility_timeout": 0.8}
        with redis_workers(redis_url, redis_prefix, pipeline_options=opts, max_deliveries=2, **fast):
            try:
                [job_id] = await queue.submit([small_request(666)])
                job = await queue.wait(job_id, 60)
                assert job.state is JobState.FAILED and job.deliveries == 2
                assert job.error and job.error.type == "WorkerLost" and "delivery 2 of 2" in job.error.error
                [letter] = await queue.dead_letters()
                assert letter.job_id == job_id and letter.error == job.error
                assert (await queue.stats()).dead_letters == 1
            finally:
                await queue.close()

    run(main())


@pytest.fixture
def own_redis() -> Iterator[tuple[str, list[subprocess.Popen[bytes]]]]:
    """A private redis-server on a free port (restartable by the test)."""
    binary = shutil.which("redis-server")
    if binary is None:
        pytest.skip("redis-server is not installed")
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        port = sock.getsockname()[1]
    cmd = [binary, "--port", str(port), "--bind", "127.0.0.1", "--save", "", "--appendonly", "no"]
    procs = [subprocess.Popen(cmd, stdout=subprocess.DEVNULL)]
    url = f"redis://127.0.0.1:{port}/0"
    _wait_up(url)
    yield url, procs
    for proc in procs:
        proc.terminate()
        proc.wait(10)


def _wait_up(url: str) -> None:
    end = time.monotonic() + 10
    while True:
        try:
            if redis.Redis.from_url(url).ping():
                return
        except redis.ConnectionError:
            if time.monotonic() > end:
                raise
            time.sleep(0.05)


@pytest.mark.slow  # restarts while jobs run are in the default suite (test_redis_faults.py)
def test_redis_restart_while_idle(own_redis: tuple[str, list[subprocess.Popen[bytes]]]) -> None:
    url, procs = own_redis

    async def main() -> None:
        queue = client(url, "mani:")
        await queue.start()
        with redis_workers(url, "mani:", **FAST):
            try:
                await live_workers(queue, 1)
                [job_id] = await queue.submit([small_request()])
                assert (await queue.wait(job_id, 20)).state is JobState.SUCCEEDED
                procs[0].terminate()
                procs[0].wait(10)
                await asyncio.sleep(1.0)  # workers and client see it gone
                assert not await queue.ping()
                procs.append(subprocess.Popen(procs[0].args, stdout=subprocess.DEVNULL))
                _wait_up(url)
                await asyncio.sleep(0.5)
                [job_id] = await queue.submit([small_request()])
                assert (await queue.wait(job_id, 30)).state is JobState.SUCCEEDED
                await live_workers(queue, 1)
            finally:
                await queue.close()

    run(main())


def test_request_id_in_the_record_the_stream_entry_and_the_worker_logs(
    redis_url: str, redis_prefix: str, tmp_path: Path
) -> None:
    """SUBMIT (Lua) keeps the submitting request's id in each job's hash and stream entry (every job of a batch);
    jobs without one, like records written before it existed, read as before; the worker logs it with the job id."""

    async def main() -> None:
        queue = client(redis_url, redis_prefix)
        r = redis.Redis.from_url(redis_url)
        await queue.start()
        try:
            [job_id] = await queue.submit([small_request(1)], request_id="abc-123")
            batch = await queue.create_batch([small_request(i) for i in range(3)], request_id="abc-456")
            batch_ids = await queue.batch_job_ids(batch)
            [plain] = await queue.submit([small_request(2)])
            assert r.hget(queue.keys.job(job_id), "request_id") == b"abc-123"
            assert [r.hget(queue.keys.job(i), "request_id") for i in batch_ids] == [b"abc-456"] * 3
            assert r.hget(queue.keys.job(plain), "request_id") is None
            entries = {f[b"id"].decode(): f.get(b"r") for _, f in r.xrange(queue.keys.stream)}
            assert entries == {job_id: b"abc-123", **dict.fromkeys(batch_ids, b"abc-456"), plain: None}
            assert {(await queue.get(i)).state for i in [job_id, *batch_ids, plain]} == {JobState.QUEUED}
            log_path = tmp_path / "workers.log"
            with (
                log_path.open("wb") as sink,
                log_path.open() as source,
                redis_workers(redis_url, redis_prefix, stderr=sink, log_level="INFO", **FAST),
            ):
                done = await asyncio.gather(*(queue.wait(i, 20) for i in [job_id, *batch_ids, plain]))
                assert {j.state for j in done} == {JobState.SUCCEEDED}
                finished = await logged(source.read, lambda e: e.get("msg") == "job finished", count=5)
            by_job = {e["job_id"]: e.get("request_id") for e in finished}
            assert by_job == {job_id: "abc-123", **dict.fromkeys(batch_ids, "abc-456"), plain: None}
            lines = log_lines(log_path.read_text())
            started = [e for e in lines if e.get("msg") == "job started" and e.get("job_id") == job_id]
            assert started and started[0]["request_id"] == "abc-123" and started[0]["worker"]
        finally:
            r.close()
            await queue.close()

    run(main())
