"""EmbeddedQueue with real spawned worker processes running the staged test pipeline."""

from __future__ import annotations

import asyncio
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from manifoundation.contract import JobState, ObjectIn, RobotRegister, Stage, SynthesisRequest
from manifoundation.server.queue import JobNotFound, QueueFull, RobotInvalid, create_queue
from manifoundation.server.queue.embedded import EmbeddedQueue
from manifoundation.server.spool import SpooledRequest, payload_files, request_payload

from .helpers import STAGED, assert_only_the_poison_dead_lettered, logged, run, running, small_request, until

URDF = """<robot name="g"><link name="base"/><link name="tip"/>
<joint name="j" type="revolute"><parent link="base"/><child link="tip"/><limit lower="0" upper="1"/></joint></robot>"""


def embedded(**options: object) -> EmbeddedQueue:
    options.setdefault("concurrency", 1)
    options.setdefault("pipeline", STAGED)
    queue = create_queue(None, redis_url=None, log_level="WARNING", **options)
    assert isinstance(queue, EmbeddedQueue)
    return queue


def test_queue_package_is_torch_free() -> None:
    code = (
        "import sys, manifoundation.server.queue, manifoundation.server.queue.embedded, "
        "manifoundation.server.queue.redis; assert 'torch' not in sys.modules"
    )
    subprocess.run([sys.executable, "-c", code], check=True)


def test_round_trip_progress_batch_and_robots() -> None:
    async def main() -> None:
        queue = embedded(pipeline_options={"stage_seconds": 0.05, "iterations": 3})
        await queue.start()
        try:
            [job_id] = await queue.submit([small_request(1)])
            seen = await until(queue, job_id, lambda j: j.progress.stage is Stage.REFINEMENT)
            assert seen.state is JobState.RUNNING and seen.progress.max_iterations == 3
            job = await queue.wait(job_id, 10)
            assert job.state is JobState.SUCCEEDED and job.deliveries == 1
            assert job.result is not None and job.result.hand == "test_gripper"
            assert job.progress.stage is Stage.DONE and {"queue", "total"} <= set(job.timings)
            assert set(job.result.timings) >= {"network", "refinement", "verification"}
            batch = await queue.create_batch([small_request(i) for i in range(3)])
            ids = await queue.batch_job_ids(batch)
            done = await asyncio.gather(*(queue.wait(i, 10) for i in ids))
            assert [j.state for j in done] == [JobState.SUCCEEDED] * 3 and {j.batch_id for j in done} == {batch}
            assert [j.id for j in await queue.list_recent(4)] == [*ids[::-1], job_id]
            stats = await queue.stats()
            assert stats.completed_total == 4 and stats.depth == 0 and stats.workers == 1
            [worker] = await queue.workers()
            assert worker.model_loaded and worker.jobs_done == 4 and worker.pid != os.getpid()
            assert [r.name for r in await queue.list_robots()] == ["test_gripper"]
            robot = await queue.register_robot(RobotRegister(name="mine", urdf=URDF, fingertips=["tip"]))
            assert robot.dof == 1 and not robot.builtin
            assert {r.name for r in await queue.list_robots()} == {"test_gripper", "mine"}
            with pytest.raises(RobotInvalid, match="unknown links"):
                await queue.register_robot(RobotRegister(name="bad", urdf=URDF, fingertips=["nope"]))
            with pytest.raises(JobNotFound):
                await queue.get("0" * 32)
        finally:
            await queue.close()

    run(main())


def test_cancel_full_deadline_and_expiry() -> None:
    async def main() -> None:
        queue = embedded(concurrency=0, max_queue=2, result_ttl=0.3)
        await queue.start()
        try:
            a, b = await queue.submit([small_request(), small_request()])
            with pytest.raises(QueueFull) as full:
                await queue.submit([small_request()])
            assert full.value.retry_after > 0
            assert (await queue.cancel(a)).state is JobState.CANCELLED
            [late] = await queue.submit([small_request()], deadline=time.time() + 0.05)
            expired = await queue.wait(late, 5)
            assert expired.state is JobState.EXPIRED and expired.error and expired.error.type == "DeadlineExceeded"
            await asyncio.sleep(0.5)  # the cancelled job's record outlives its TTL
            gone = await queue.get(a)
            assert gone.state is JobState.EXPIRED and gone.error and gone.error.type == "ResultExpired"
            assert (await queue.get(b)).state is JobState.QUEUED
        finally:
            await queue.close()

    run(main())


def test_results_are_bounded_by_bytes() -> None:
    """Finished jobs' results beyond ``max_result_bytes`` are evicted oldest first (and then answer "expired"),
    however few they are: the API's memory stays bounded whatever the results' size."""

    async def main() -> None:
        queue = embedded(concurrency=0, max_result_bytes=2500)
        await queue.start()
        try:
            ids = await queue.submit([small_request(i) for i in range(4)])
            with queue._lock:
                for job_id in ids:
                    queue._finish(queue._jobs[job_id], result=b"x" * 1000)
            await asyncio.sleep(0.3)  # the pump sweeps every 50 ms
            states = [(await queue.get(i, with_result=False)).state for i in ids]
            assert states == [JobState.EXPIRED] * 2 + [JobState.SUCCEEDED] * 2
            assert queue._result_bytes == 2000
        finally:
            await queue.close()

    run(main())


def test_cancel_running_failure_isolation_and_kill_redelivery() -> None:
    async def main() -> None:
        queue = embedded(pipeline_options={"stage_seconds": 0.1, "iterations": 20, "fail_seed": 13}, batch_size=2)
        await queue.start()
        try:
            [job_id] = await queue.submit([small_request(1)])
            await until(queue, job_id, running)
            await queue.cancel(job_id)
            job = await queue.wait(job_id, 10)
            assert job.state is JobState.CANCELLED and job.error and job.error.type == "Cancelled"
            # a failing job in a batch fails alone; the worker survives
            ok, bad = await queue.submit([small_request(2, max_iterations=1), small_request(13)])
            assert (await queue.wait(ok, 10)).state is JobState.SUCCEEDED
            failed = await queue.wait(bad, 10)
            assert failed.state is JobState.FAILED and failed.error and "injected failure" in failed.error.error
            # kill -9 the worker mid-job: re-delivered to the replacement and completed once
            [job_id] = await queue.submit([small_request(3, max_iterations=3)])
            running_job = await until(queue, job_id, running)
            [worker] = await queue.workers()
            assert running_job.worker == worker.id
            os.kill(worker.pid, signal.SIGKILL)
            job = await queue.wait(job_id, 30)
            assert job.state is JobState.SUCCEEDED and job.deliveries == 2 and job.worker != worker.id
        finally:
            await queue.close()

    run(main())


def test_poison_job_goes_to_dead_letters() -> None:
    async def main() -> None:
        queue = embedded(pipeline_options={"crash_seed": 666}, max_deliveries=2)
        await queue.start()
        try:
            [job_id] = await queue.submit([small_request(666)])
            job = await queue.wait(job_id, 60)
            assert job.state is JobState.FAILED and job.deliveries == 2
            assert job.error and job.error.type == "WorkerLost" and "delivery 2 of 2" in job.error.error
            [letter] = await queue.dead_letters()
            assert letter.job_id == job_id and letter.error == job.error
            [after] = await queue.submit([small_request(1)])
            assert (await queue.wait(after, 30)).state is JobState.SUCCEEDED
        finally:
            await queue.close()

    run(main())


def test_poison_job_fails_no_batch_mate() -> None:
    """A job that kills its worker in a micro-batch of 4: only it is dead-lettered; its three batch-mates are
    given back, run alone, and succeed on their second delivery."""

    async def main() -> None:
        queue = embedded(pipeline_options={"crash_seed": 666}, batch_size=4)
        await queue.start()
        try:
            ids = await queue.submit([small_request(s) for s in (1, 2, 666, 3)])
            jobs = await asyncio.gather(*(queue.wait(i, 60) for i in ids))
            await assert_only_the_poison_dead_lettered(queue, list(jobs), ids[2])
        finally:
            await queue.close()

    run(main())


def test_request_id_in_the_record_and_the_worker_logs(capfd: pytest.CaptureFixture[str]) -> None:
    """The submitting request's id is kept on each job (every job of a batch) and rides to the worker process,
    whose log lines for the job carry it next to the job id (the worker writes to the inherited stderr)."""

    async def main() -> None:
        queue = create_queue(None, redis_url=None, concurrency=1, pipeline=STAGED, log_level="INFO")
        assert isinstance(queue, EmbeddedQueue)
        await queue.start()  # spawned now: its stderr is the one capfd captures
        try:
            [job_id] = await queue.submit([small_request(1)], request_id="abc-123")
            batch = await queue.create_batch([small_request(i) for i in range(2)], request_id="abc-456")
            batch_ids = await queue.batch_job_ids(batch)
            [plain] = await queue.submit([small_request(2)])
            ids = [job_id, *batch_ids, plain]
            records = {i: queue._jobs[i].request_id for i in ids}
            assert records == {job_id: "abc-123", **dict.fromkeys(batch_ids, "abc-456"), plain: None}
            done = await asyncio.gather(*(queue.wait(i, 20) for i in ids))
            assert {j.state for j in done} == {JobState.SUCCEEDED}
            lines = await logged(lambda: capfd.readouterr().err, lambda e: e.get("job_id") in ids, count=2 * len(ids))
        finally:
            await queue.close()
        for entry in lines:  # "job started" and "job finished" of each
            assert entry.get("request_id") == records[entry["job_id"]] and entry["worker"], entry
        assert {(e["msg"], e["job_id"]) for e in lines} >= {("job started", job_id), ("job finished", job_id)}

    run(main())


def test_cancel_of_an_unknown_job_answers_and_leaves_the_queue_usable() -> None:
    """Cancelling an id the queue never saw raises JobNotFound at once; it used to deadlock on the queue's lock."""
    import threading

    outcome: list[str] = []

    async def main() -> None:
        queue = embedded(concurrency=0)
        await queue.start()
        try:
            with pytest.raises(JobNotFound):
                await queue.cancel("nope")
            [job_id] = await queue.submit([small_request()])
            assert (await queue.get(job_id)).state is JobState.QUEUED
            assert (await queue.cancel(job_id)).state is JobState.CANCELLED
            outcome.append("answered")
        finally:
            await queue.close()

    thread = threading.Thread(target=run, args=(main(),), daemon=True)  # a deadlock must fail, not hang, the suite
    thread.start()
    thread.join(30)
    assert not thread.is_alive(), "EmbeddedQueue.cancel deadlocked"
    assert outcome == ["answered"]


def test_a_silent_worker_is_replaced_and_its_jobs_redelivered() -> None:
    """Issue 62 #6: a SIGSTOPped embedded worker held its jobs "running" for good and counted as live. Now a worker
    without a heartbeat for `heartbeat_timeout` is killed, dropped from `workers()` and its jobs re-delivered, as on
    Redis."""

    async def main() -> None:
        queue = embedded(pipeline_options={"stage_seconds": 0.1, "iterations": 20}, heartbeat_interval=0.3)
        await queue.start()
        stopped = None
        try:
            [job_id] = await queue.submit([small_request(1, max_iterations=10)])
            await until(queue, job_id, running)
            [worker] = await queue.workers()
            stopped = worker.pid
            os.kill(stopped, signal.SIGSTOP)
            start = time.monotonic()
            job = await queue.wait(job_id, 30)
            assert job.state is JobState.SUCCEEDED and job.deliveries == 2 and job.worker != worker.id
            assert time.monotonic() - start < 10  # heartbeat timeout (1 s) + the job (about 1.3 s) + a respawn
            assert worker.id not in {w.id for w in await queue.workers()}
            assert subprocess.run(["ps", "-o", "stat=", "-p", str(stopped)], capture_output=True).stdout.strip() \
                in (b"", b"Z")  # killed (reaped, or a zombie until then)  # fmt: skip
            stopped = None
        finally:
            if stopped is not None:  # the test failed: never leave our stopped process behind
                os.kill(stopped, signal.SIGKILL)
            await queue.close()

    run(main())


def _cloud_request(points: int, seed: int = 0) -> SynthesisRequest:
    """`small_request` with ``points`` points (200 000: a 4.8 MB cloud with its normals)."""
    rng = np.random.default_rng(seed)
    p = rng.normal(size=(points, 3))
    p /= np.linalg.norm(p, axis=1, keepdims=True)
    return small_request(seed).model_copy(update={"object": ObjectIn(points=0.03 * p, normals=p)})


def test_large_payloads_wait_in_the_spool_not_in_memory() -> None:
    """A request whose cloud is over SPOOL_BYTES waits as a file of the queue's spool (its record holds no
    payload), byte for byte the payload it would have had; one a body process spooled already is adopted as it is;
    a refused submission leaves no file of its own making and the caller's; cancelling removes the file, closing
    the queue the spool (issue 62, item 3: the API held every queued batch's payloads)."""

    async def main() -> None:
        queue = embedded(concurrency=0, max_queue=3)
        await queue.start()
        spool = queue.spool
        assert spool is not None and payload_files(spool) == []
        try:
            big = _cloud_request(100_000)
            big_id, small_id = await queue.submit([big, small_request()])
            [name] = payload_files(spool)
            with open(os.path.join(spool, name), "rb") as spooled_file:
                assert spooled_file.read() == request_payload(big)
            assert queue._jobs[big_id].payload == b"" and queue._jobs[big_id].spooled is not None
            small = queue._jobs[small_id]
            assert small.payload == request_payload(small_request()) and small.spooled is None
            adopted = SpooledRequest.write(spool, _cloud_request(100_000, seed=1))
            batch = await queue.create_batch([adopted])
            [adopted_id] = await queue.batch_job_ids(batch)
            assert queue._jobs[adopted_id].spooled == adopted.path and len(payload_files(spool)) == 2
            theirs = SpooledRequest.write(spool, _cloud_request(100_000, seed=2))
            with pytest.raises(QueueFull):
                await queue.submit([_cloud_request(100_000, seed=3), theirs])
            kept = sorted([name, os.path.basename(adopted.path), os.path.basename(theirs.path)])
            assert sorted(payload_files(spool)) == kept
            os.unlink(theirs.path)
            await queue.cancel(big_id)
            assert sorted(payload_files(spool)) == [os.path.basename(adopted.path)]
        finally:
            await queue.close()
        assert not os.path.exists(spool)

    run(main())


def test_spooled_jobs_reach_the_worker_whole_and_their_files_go() -> None:
    """Spooled payloads (the queue's own and one a body process wrote) are read and sent to a real worker, which
    decodes and runs them; nothing is left in the spool once they ended."""

    async def main() -> None:
        queue = embedded()
        await queue.start()
        try:
            assert queue.spool is not None
            adopted = SpooledRequest.write(queue.spool, _cloud_request(200_000, seed=1))
            ids = await queue.submit([_cloud_request(200_000), adopted, small_request()])
            done = await asyncio.gather(*(queue.wait(i, 30) for i in ids))
            assert [j.state for j in done] == [JobState.SUCCEEDED] * 3, [j.error for j in done]
            assert payload_files(queue.spool) == []
        finally:
            await queue.close()

    run(main())
