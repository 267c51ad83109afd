"""Embedded backend: an in-process queue feeding N spawned worker processes (the default; NOT durable).

Jobs, results and dead letters live in this process's memory: they are lost when it exits. Results are kept
``result_ttl`` seconds and at most ``max_results`` finished jobs (oldest evicted first); an evicted job still
answers state "expired" (a bounded list of tombstones), never "unknown". One pump thread talks to the workers
over one duplex pipe each (`workers.child`): it dispatches up to ``batch_size`` queued jobs to an idle worker,
takes progress and outcomes back, and notices a dead worker (EOF): its jobs go back to the queue until they have
been delivered ``max_deliveries`` times, then to the dead letters with the error; a replacement is spawned. A job
given back that way runs alone (a micro-batch of one), so a job that kills its worker fails no batch-mate.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import multiprocessing as mp
import os
import socket
import subprocess
import sys
import threading
import time
from collections import OrderedDict, deque
from multiprocessing.connection import Connection, wait
from typing import Any

from clients.codec import pack, unpack
from clients.schemas import (
    DeadLetter,
    ErrorBody,
    JobProgress,
    JobPublic,
    JobState,
    RobotPublic,
    RobotRegister,
    Stage,
    SynthesisRequest,
    SynthesisResult,
    WorkerPublic,
)
from workers.queue.base import JobNotFound, JobQueue, QueueFull, QueueStats, QueueUnavailable, RobotInvalid
from workers.queue.embedded_parts import ChildProcess, JobRecord, WorkerHandle, settle
from workers.queue.records import (
    cancelled_error,
    deadline_error,
    new_id,
    result_expired_error,
    scoped_robot,
    shutdown_error,
    state_for_error,
    worker_lost_error,
)
from workers.settings import QueueSettings

log = logging.getLogger("workers.queue.embedded")
_TOMBSTONES_PER_RESULT = 10


class EmbeddedQueue(JobQueue):
    """In-process queue + ``concurrency`` spawned worker processes (see module doc)."""

    backend = "embedded"

    def __init__(self, settings: QueueSettings | None = None, **overrides: Any) -> None:
        base = settings or QueueSettings()
        self.settings = base.model_copy(update=overrides) if overrides else base
        self._lock = threading.Lock()
        self._jobs: dict[str, JobRecord] = {}
        self._pending: deque[str] = deque()
        self._finished: OrderedDict[str, None] = OrderedDict()
        self._tombstones: OrderedDict[str, tuple[float, str | None, str | None]] = OrderedDict()
        self._batches: OrderedDict[str, tuple[str | None, list[str]]] = OrderedDict()
        self._waiters: dict[str, list[tuple[asyncio.AbstractEventLoop, asyncio.Future[None]]]] = {}
        self._workers: dict[str, WorkerHandle] = {}
        self._robots: dict[str, RobotPublic] = {}  # by `scoped_robot(owner, name)`; built-ins by name
        self._registered: dict[str, bytes] = {}  # owner-scoped name -> msgpack of its RobotRegister
        self._robot_replies: dict[str, tuple[asyncio.AbstractEventLoop, asyncio.Future[dict[str, Any]]]] = {}
        self._dead: deque[DeadLetter] = deque(maxlen=1000)
        self._totals = {"completed": 0, "failed": 0}
        self._wake_r, self._wake_w = mp.Pipe(duplex=False)
        self._pump: threading.Thread | None = None
        self._running = False

    # ---- lifecycle -------------------------------------------------------------------------------------------
    async def start(self) -> None:
        if self._running:
            return
        self._running = True
        with self._lock:
            for _ in range(self.settings.concurrency):
                self._spawn()
        self._pump = threading.Thread(target=self._pump_loop, name="mani-embedded-pump", daemon=True)
        self._pump.start()
        deadline = time.monotonic() + self.settings.start_timeout
        while time.monotonic() < deadline and any(w.info is None for w in list(self._workers.values())):
            await asyncio.sleep(0.02)

    async def close(self) -> None:
        if not self._running:
            return
        self._running = False
        with self._lock:
            workers = list(self._workers.values())
            for job_id in list(self._pending):
                self._finish(self._jobs[job_id], error=shutdown_error())
        for worker in workers:
            with contextlib.suppress(OSError):
                worker.send({"op": "stop"})
        self._wake()
        await asyncio.get_running_loop().run_in_executor(None, self._join, workers)
        if self._pump is not None:
            await asyncio.get_running_loop().run_in_executor(None, self._pump.join, 10)

    def _join(self, workers: list[WorkerHandle]) -> None:
        deadline = time.monotonic() + 10
        for worker in workers:
            worker.process.join(max(0.0, deadline - time.monotonic()))
            if worker.process.is_alive():
                worker.process.terminate()
                worker.process.join(2)
                worker.process.kill()

    def _spawn(self) -> WorkerHandle:
        worker_id = new_id()[:12]
        parent, child = socket.socketpair()
        process = subprocess.Popen(
            [sys.executable, "-m", "workers.child", worker_id, str(child.fileno())],
            pass_fds=(child.fileno(),),
            stdin=subprocess.PIPE,
            env=os.environ | {"MANI_WORKER_SETTINGS": self.settings.model_dump_json()},
        )
        child.close()
        assert process.stdin is not None
        process.stdin.close()
        worker = WorkerHandle(worker_id, ChildProcess(process), Connection(parent.detach()))
        self._workers[worker_id] = worker
        return worker

    async def ping(self) -> bool:
        return self._running

    # ---- submit / observe ------------------------------------------------------------------------------------
    async def submit(
        self, requests: list[SynthesisRequest], *, batch_id: str | None = None, deadline: float | None = None,
        request_id: str | None = None, owner: str | None = None,
    ) -> list[str]:  # fmt: skip
        if not self._running:
            raise QueueUnavailable("the embedded queue is not running")
        payloads = [pack(r.model_dump(mode="python", exclude_none=True)) for r in requests]
        with self._lock:
            if len(self._pending) + len(requests) > self.settings.max_queue:
                raise QueueFull(f"queue holds {len(self._pending)} jobs (max {self.settings.max_queue})", 1.0)
            ids = []
            for request, payload in zip(requests, payloads, strict=True):
                job = JobRecord(new_id(), payload, request.robot.name, deadline, batch_id, request_id, owner)
                self._jobs[job.id] = job
                self._pending.append(job.id)
                ids.append(job.id)
        self._wake()
        return ids

    @property
    def capacity(self) -> int | None:
        return self.settings.max_queue

    async def room(self, count: int = 1) -> bool:
        with self._lock:
            return len(self._pending) + count <= self.settings.max_queue

    async def get(self, job_id: str, *, with_result: bool = True, owner: str | None = None) -> JobPublic:
        with self._lock:
            job = self._jobs.get(job_id)
            if job is not None and (owner is None or job.owner == owner):
                public, raw = job.public(), job.result if with_result else None
                gone = None
            else:
                public, raw = None, None
                gone = None if job is not None else self._tombstones.get(job_id)
        if public is not None:
            if raw is not None:  # the one validation of a result on the service side, outside the lock
                public.result = SynthesisResult.model_validate(unpack(raw))
            return public
        if gone is None or (owner is not None and gone[2] != owner):
            raise JobNotFound(f"no job {job_id}")
        created, batch, _ = gone
        return JobPublic(id=job_id, state=JobState.EXPIRED, created_at=created, batch_id=batch,
                         error=result_expired_error())  # fmt: skip

    async def wait(self, job_id: str, timeout: float) -> JobPublic:
        loop = asyncio.get_running_loop()
        future: asyncio.Future[None] = loop.create_future()
        with self._lock:
            job = self._jobs.get(job_id)
            if job is None or job.state.terminal:
                future = None  # type: ignore[assignment]
            else:
                self._waiters.setdefault(job_id, []).append((loop, future))
        if future is not None:
            try:
                await asyncio.wait_for(future, timeout)
            except TimeoutError:
                pass
            finally:
                with self._lock:
                    waiters = self._waiters.get(job_id, [])
                    if (loop, future) in waiters:
                        waiters.remove((loop, future))
                    if not waiters:
                        self._waiters.pop(job_id, None)
        return await self.get(job_id)

    async def cancel(self, job_id: str, *, owner: str | None = None) -> JobPublic:
        await self.get(job_id, with_result=False, owner=owner)  # JobNotFound for an unknown or foreign job
        target: WorkerHandle | None = None
        with self._lock:
            job = self._jobs.get(job_id)
            if job is not None and job.state is JobState.QUEUED:
                self._finish(job, error=cancelled_error())
            elif job is not None and job.state is JobState.RUNNING and not job.cancel:
                job.cancel = True
                target = self._workers.get(job.worker or "")
        if target is not None:
            with contextlib.suppress(OSError):
                target.send({"op": "cancel", "id": job_id})
        return await self.get(job_id, with_result=False)

    async def list_recent(self, limit: int = 50, *, owner: str | None = None) -> list[JobPublic]:
        if limit <= 0:
            return []
        with self._lock:
            out: list[JobPublic] = []
            for job in reversed(self._jobs.values()):
                if owner is None or job.owner == owner:
                    out.append(job.public())
                    if len(out) == limit:
                        break
            return out

    async def create_batch(
        self, requests: list[SynthesisRequest], deadline: float | None = None, *, request_id: str | None = None,
        owner: str | None = None,
    ) -> str:  # fmt: skip
        batch_id = new_id()
        ids = await self.submit(requests, batch_id=batch_id, deadline=deadline, request_id=request_id, owner=owner)
        with self._lock:
            self._batches[batch_id] = (owner, ids)
            while len(self._batches) > self.settings.max_results:
                self._batches.popitem(last=False)
        return batch_id

    async def batch_job_ids(self, batch_id: str, *, owner: str | None = None) -> list[str]:
        with self._lock:
            found = self._batches.get(batch_id)
        if found is None or (owner is not None and found[0] != owner):
            raise JobNotFound(f"no batch {batch_id}")
        return list(found[1])

    async def stats(self) -> QueueStats:
        with self._lock:
            by_state = dict.fromkeys(JobState, 0)
            for job in self._jobs.values():
                by_state[job.state] += 1
            return QueueStats(
                depth=by_state[JobState.QUEUED],
                running=by_state[JobState.RUNNING],
                by_state=by_state,
                completed_total=self._totals["completed"],
                failed_total=self._totals["failed"],
                dead_letters=len(self._dead),
                workers=sum(1 for w in self._workers.values() if w.info),
            )

    async def workers(self) -> list[WorkerPublic]:
        with self._lock:
            out = []
            for w in self._workers.values():
                if w.info is not None:
                    current = next(iter(w.inflight), None)
                    out.append(w.info.model_copy(update={"current_job": current, "jobs_done": w.jobs_done}))
            return out

    async def dead_letters(self, limit: int = 50) -> list[DeadLetter]:
        with self._lock:
            return list(self._dead)[::-1][:limit]

    async def list_robots(self, *, owner: str | None = None) -> list[RobotPublic]:
        with self._lock:
            mine = [r for key, r in self._robots.items() if r.builtin or key == scoped_robot(owner, r.name)]
        return sorted(mine, key=lambda r: (not r.builtin, r.name))

    async def register_robot(
        self, robot: RobotRegister, timeout: float = 30.0, *, owner: str | None = None
    ) -> RobotPublic:
        with self._lock:
            ready = [w for w in self._workers.values() if w.info is not None]
            existing = self._robots.get(robot.name)
        if existing is not None and existing.builtin:
            raise RobotInvalid(f"name: '{robot.name}' is a built-in hand")
        if not ready:
            raise QueueUnavailable("no worker is running to validate the robot")
        worker = min(ready, key=lambda w: len(w.inflight))
        rid, loop = new_id(), asyncio.get_running_loop()
        payload = pack(robot.model_dump(mode="python", exclude_none=True))
        future: asyncio.Future[dict[str, Any]] = loop.create_future()
        with self._lock:
            self._robot_replies[rid] = (loop, future)
        try:
            worker.send({"op": "robot", "rid": rid}, payload)
            reply = await asyncio.wait_for(future, timeout)
        except TimeoutError as exc:
            raise QueueUnavailable(f"no worker validated the robot within {timeout} s") from exc
        finally:
            with self._lock:
                self._robot_replies.pop(rid, None)
        if "error" in reply:
            raise RobotInvalid(reply["error"])
        public = RobotPublic.model_validate(reply["robot"])
        key = scoped_robot(owner, robot.name)
        with self._lock:
            self._registered[key] = payload
            self._robots[key] = public
        return public

    async def delete_robot(self, name: str, *, owner: str | None = None) -> None:
        key = scoped_robot(owner, name)
        with self._lock:
            robot = self._robots.get(key)
            if robot is None or robot.builtin:
                raise JobNotFound(f"no registered robot {name!r}")
            del self._robots[key]
            self._registered.pop(key, None)

    # ---- pump thread -----------------------------------------------------------------------------------------
    def _wake(self) -> None:
        with contextlib.suppress(OSError):
            self._wake_w.send_bytes(b"")

    def _pump_loop(self) -> None:
        last_sweep = 0.0
        while self._running or any(w.inflight or w.process.is_alive() for w in list(self._workers.values())):
            conns: list[Any] = [w.conn for w in list(self._workers.values())]
            for conn in wait([*conns, self._wake_r], timeout=0.1):
                if conn is self._wake_r:
                    while self._wake_r.poll():
                        self._wake_r.recv_bytes()
                    continue
                self._receive(conn)
            if time.monotonic() - last_sweep > 0.05:
                last_sweep = time.monotonic()
                self._sweep()
            if self._running:
                self._dispatch()
            elif not any(w.process.is_alive() for w in list(self._workers.values())):
                break

    def _receive(self, conn: Any) -> None:
        worker = next((w for w in list(self._workers.values()) if w.conn is conn), None)
        if worker is None:
            return
        try:
            msg = unpack(conn.recv_bytes())
        except (EOFError, OSError):
            worker.process.join(1)
            self._lost(worker, f"worker process exited (code {worker.process.exitcode}) while running the job")
            return
        op = msg["op"]
        result = None
        if op == "done" and msg.get("state") == JobState.SUCCEEDED.value:
            try:
                result = conn.recv_bytes()  # the result's frame follows its header (bytes, stored as they are)
            except (EOFError, OSError):
                worker.process.join(1)
                self._lost(worker, "worker process exited while sending a result")
                return
        with self._lock:
            if op == "hello":
                worker.info = WorkerPublic.model_validate(msg["worker"])
                for raw in msg["robots"]:
                    robot = RobotPublic.model_validate(raw)
                    self._robots.setdefault(robot.name, robot)
            elif op == "heartbeat" and worker.info is not None:
                worker.info.last_heartbeat = float(msg["t"])
            elif op == "progress" and (job := self._jobs.get(msg["id"])) and job.state is JobState.RUNNING:
                job.progress = JobProgress.model_validate(msg["p"])
            elif op == "done":
                worker.inflight.discard(msg["id"])
                worker.jobs_done += 1
                job = self._jobs.get(msg["id"])
                if job is not None and job.state is JobState.RUNNING:
                    job.timings.update(msg.get("timings", {}))
                    if result is not None:
                        self._finish(job, result=result)
                    else:
                        self._finish(job, error=ErrorBody.model_validate(msg["error"]))
            elif op == "robot" and (reply := self._robot_replies.get(msg["rid"])):
                loop, future = reply
                loop.call_soon_threadsafe(settle, future, msg)

    def _lost(self, worker: WorkerHandle, detail: str) -> None:
        with self._lock:
            self._workers.pop(worker.id, None)
            max_deliveries = self.settings.max_deliveries
            for job_id in sorted(worker.inflight, key=lambda i: self._jobs[i].created_at, reverse=True):
                job = self._jobs.get(job_id)
                if job is None or job.state.terminal:
                    continue
                error = worker_lost_error(detail, job.deliveries, max_deliveries)
                if job.cancel:
                    self._finish(job, error=cancelled_error())
                elif not self._running:
                    self._finish(job, error=shutdown_error("queue shut down while the job ran"))
                elif job.deliveries >= max_deliveries:
                    self._finish(job, error=error)
                    self._dead.append(DeadLetter(job_id=job.id, deliveries=job.deliveries, error=error,
                                                 failed_at=time.time()))  # fmt: skip
                    log.warning("job dead-lettered", extra={"job_id": job.id, "request_id": job.request_id,
                                                           "deliveries": job.deliveries})  # fmt: skip
                else:
                    job.state, job.progress, job.error = JobState.QUEUED, JobProgress(), error
                    self._pending.appendleft(job.id)
                    log.warning("job re-queued after worker loss",
                                extra={"job_id": job.id, "request_id": job.request_id})  # fmt: skip
            worker.inflight.clear()
            if self._running and worker.info is not None:
                self._spawn()
            elif self._running:
                log.error("worker %s exited before it was ready (code %s); not respawned",
                          worker.id, worker.process.exitcode)  # fmt: skip
        worker.conn.close()

    def _dispatch(self) -> None:
        sends: list[tuple[WorkerHandle, list[dict[str, Any]], list[bytes]]] = []
        with self._lock:
            idle = [w for w in self._workers.values() if w.info is not None and not w.inflight]
            now = time.time()
            for worker in idle:
                batch: list[dict[str, Any]] = []
                frames: list[bytes] = []
                while self._pending and len(batch) < self.settings.batch_size:
                    job = self._jobs.get(self._pending[0])
                    if job is None or job.state is not JobState.QUEUED:
                        self._pending.popleft()
                        continue
                    if job.deliveries and batch:
                        break  # a job whose worker died runs alone: a poison job takes no batch-mate down
                    self._pending.popleft()
                    job.state, job.worker, job.deliveries = JobState.RUNNING, worker.id, job.deliveries + 1
                    job.started_at = now
                    robot = self._registered.get(scoped_robot(job.owner, job.robot or ""))
                    batch.append({
                        "id": job.id, "deadline": job.deadline, "request_id": job.request_id,
                        "queued_for": now - job.created_at, "robot": robot is not None,
                    })  # fmt: skip
                    frames += [job.payload, robot] if robot is not None else [job.payload]
                    worker.inflight.add(job.id)
                    if job.deliveries > 1:
                        break
                if not batch:
                    break
                sends.append((worker, batch, frames))
        for worker, batch, frames in sends:
            with contextlib.suppress(OSError):  # on failure, the EOF on its pipe re-queues the jobs
                worker.send({"op": "run", "jobs": batch}, *frames)

    def _sweep(self) -> None:
        now = time.time()
        with self._lock:
            for job_id in list(self._pending):
                job = self._jobs.get(job_id)
                if job is not None and job.deadline is not None and job.deadline <= now and not job.state.terminal:
                    self._finish(job, error=deadline_error())
            ttl = self.settings.result_ttl
            while self._finished:
                oldest = next(iter(self._finished))
                job = self._jobs[oldest]
                if len(self._finished) <= self.settings.max_results and (job.finished_at or now) + ttl > now:
                    break
                self._finished.popitem(last=False)
                del self._jobs[oldest]
                self._tombstones[oldest] = (job.created_at, job.batch_id, job.owner)
                if len(self._tombstones) > _TOMBSTONES_PER_RESULT * self.settings.max_results:
                    self._tombstones.popitem(last=False)

    def _finish(self, job: JobRecord, *, result: bytes | None = None, error: ErrorBody | None = None) -> None:
        """Make ``job`` terminal (caller holds the lock) and wake its waiters."""
        if job.state is JobState.QUEUED:
            with contextlib.suppress(ValueError):
                self._pending.remove(job.id)
        job.finished_at = time.time()
        job.result, job.error, job.payload = result, error, b""
        job.state = JobState.SUCCEEDED if error is None else state_for_error(error)
        if job.state is JobState.SUCCEEDED:
            job.progress = JobProgress(stage=Stage.DONE, fraction=1.0)
            self._totals["completed"] += 1
        elif job.state is JobState.FAILED:
            self._totals["failed"] += 1
        self._finished[job.id] = None
        for loop, future in self._waiters.pop(job.id, []):
            loop.call_soon_threadsafe(settle, future, None)
