"""The embedded backend's state and its pump thread: the jobs in memory, the worker processes on their pipes,
dispatch, outcomes, worker loss and retention.

`manifoundation.server.queue.embedded.EmbeddedQueue` is the queue's API on top of this (the asyncio side). The pump
thread is the only reader of the workers' pipes (the `manifoundation.server.worker.child` protocol: a map, then the
payload frames it announces); everything shared between it and the event loop is guarded by ``_lock``, held only
for bookkeeping (no decoding, no validation, no I/O that can block: a spooled payload's file is opened under it,
read after it).

Why one module: one lock's state; dispatch, outcomes, worker loss and retention each change the same job records,
pending list and workers' in-flight sets under it, and its invariants (a job is pending, in one worker's in-flight
set, or terminal) are read in one place.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import multiprocessing as mp
import socket
import threading
import time
from collections import OrderedDict, deque
from multiprocessing.connection import Connection, wait
from typing import Any

from manifoundation.contract import (
    DeadLetter,
    ErrorBody,
    JobKind,
    JobProgress,
    JobState,
    RobotPublic,
    Stage,
    WorkerPublic,
)
from manifoundation.contract.codec import unpack
from manifoundation.server.queue.embedded_parts import ChildProcess, JobRecord, WorkerHandle, settle
from manifoundation.server.queue.embedded_payloads import FreedPayloads, read_spooled, unreadable_error
from manifoundation.server.queue.records import (
    cancelled_error,
    deadline_error,
    new_id,
    scoped_robot,
    shutdown_error,
    state_for_error,
    worker_lost_error,
)
from manifoundation.server.spool import open_payload, remove_payload
from manifoundation.server.worker.settings import QueueSettings
from manifoundation.server.worker.supervisor import spawn, stop_all

log = logging.getLogger("manifoundation.server.queue.embedded")
_TOMBSTONES_PER_RESULT = 10
_STOP_GRACE_S = 10.0
"""Seconds a stopping worker has to finish its batch before it is killed."""


class EmbeddedPump:
    """The in-memory jobs and the worker processes, driven by one pump thread (see module doc)."""

    def __init__(self, settings: QueueSettings | None = None, **overrides: Any) -> None:
        base = settings or QueueSettings()
        self.settings = base.model_copy(update=overrides) if overrides else base
        self._lock = threading.Lock()
        self._jobs: dict[str, JobRecord] = {}
        self._pending: deque[str] = deque()
        self._finished: OrderedDict[str, None] = OrderedDict()
        self._result_bytes = 0  # of the finished jobs' results held in `_jobs`
        self._freed = FreedPayloads()
        self._tombstones: OrderedDict[str, tuple[float, str | None, str | None]] = OrderedDict()
        self._batches: OrderedDict[str, tuple[str | None, list[str]]] = OrderedDict()
        self._waiters: dict[str, list[tuple[asyncio.AbstractEventLoop, asyncio.Future[None]]]] = {}
        self._workers: dict[str, WorkerHandle] = {}
        self._robots: dict[str, RobotPublic] = {}  # by `scoped_robot(owner, name)`; built-ins by name
        self._registered: dict[str, bytes] = {}  # owner-scoped name -> msgpack of its RobotRegister
        self._robot_replies: dict[str, tuple[asyncio.AbstractEventLoop, asyncio.Future[dict[str, Any]]]] = {}
        self._robot_reservations: dict[str, tuple[str | None, str, int]] = {}  # rid -> (owner, name, bytes)
        self._dead: deque[DeadLetter] = deque(maxlen=1000)
        self._totals = {"completed": 0, "failed": 0}
        self._wake_r, self._wake_w = mp.Pipe(duplex=False)
        self._pump: threading.Thread | None = None
        self._running = False
        self.spool: str | None = None  # the payload spool's directory while running

    def _live(self, worker: WorkerHandle) -> bool:
        """Ready and heard from within ``heartbeat_timeout`` (a silent worker is not live, as on Redis)."""
        return worker.ready and time.monotonic() - worker.last_seen <= self.settings.heartbeat_timeout

    def _join(self, workers: list[WorkerHandle]) -> None:
        """Wait for workers told to stop (they finish their batch), killing those that outlive the grace."""
        stop_all([w.process.popen for w in workers], _STOP_GRACE_S, signal_first=False)

    def _spawn(self) -> WorkerHandle:
        worker_id = new_id()[:12]
        parent, child = socket.socketpair()
        settings = self.settings.model_dump_json()
        process = spawn(
            "manifoundation.server.worker.child", [worker_id, str(child.fileno())], settings, pass_fds=(child.fileno(),)
        )
        child.close()
        worker = WorkerHandle(worker_id, ChildProcess(process), Connection(parent.detach()))
        self._workers[worker_id] = worker
        return worker

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
                    self._replace_silent()
            idle = not self._pending and not any(w.inflight for w in list(self._workers.values()))
            self._freed.maybe_trim(idle)
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
        worker.last_seen = time.monotonic()
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
            elif op == "robot":
                worker.answered(msg)
                if reply := self._robot_replies.get(msg["rid"]):
                    reply[0].call_soon_threadsafe(settle, reply[1], msg)

    def _replace_silent(self) -> None:
        """Kill every ready worker not heard from for ``heartbeat_timeout`` (stopped, hung in native code, swapped
        out) and treat it as lost: its jobs are re-delivered and a replacement spawned, as a Redis worker's jobs are
        once its heartbeat key expires. Its heartbeat thread writes every ``heartbeat_interval`` while it works."""
        limit, now = self.settings.heartbeat_timeout, time.monotonic()
        for worker in [w for w in list(self._workers.values()) if w.info is not None and now - w.last_seen > limit]:
            silent = now - worker.last_seen
            log.warning("worker %s silent for %.1f s (no heartbeat): killed, its jobs re-delivered", worker.id, silent)
            worker.process.kill()
            worker.process.join(1)
            self._lost(worker, f"worker sent no heartbeat for {silent:.1f} s (hung or stopped) and was replaced")

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
            for rid, answer in worker.unanswered(detail).items():
                if reply := self._robot_replies.get(rid):
                    reply[0].call_soon_threadsafe(settle, reply[1], answer)
            if self._running and worker.info is not None:
                self._spawn()
            elif self._running:
                log.error("worker %s exited before it was ready (code %s); not respawned",
                          worker.id, worker.process.exitcode)  # fmt: skip
        worker.conn.close()

    def _dispatch(self) -> None:
        sends: list[tuple[WorkerHandle, list[dict[str, Any]], list[bytes | int]]] = []
        with self._lock:
            idle = [w for w in self._workers.values() if w.idle]
            now = time.time()
            for worker in idle:
                batch: list[dict[str, Any]] = []
                frames: list[bytes | int] = []
                while self._pending and len(batch) < self.settings.batch_size:
                    job = self._jobs.get(self._pending[0])
                    if job is None or job.state is not JobState.QUEUED:
                        self._pending.popleft()
                        continue
                    alone = job.deliveries or job.kind is JobKind.PLAN
                    if alone and batch:
                        break  # a job whose worker died runs alone: a poison job takes no batch-mate down; a plan
                        # runs alone: it takes seconds to minutes
                    try:  # a spooled payload is read outside the lock, from a descriptor opened under it
                        payload: bytes | int = open_payload(job.spooled) if job.spooled else job.payload
                    except OSError as exc:
                        self._finish(job, error=unreadable_error(exc))
                        continue
                    self._pending.popleft()
                    job.state, job.worker, job.deliveries = JobState.RUNNING, worker.id, job.deliveries + 1
                    job.started_at = now
                    robot = self._registered.get(scoped_robot(job.owner, job.robot or ""))
                    batch.append({
                        "id": job.id, "deadline": job.deadline, "request_id": job.request_id,
                        "queued_for": now - job.created_at, "robot": robot is not None, "kind": job.kind.value,
                    })  # fmt: skip
                    frames += [payload, robot] if robot is not None else [payload]
                    worker.inflight.add(job.id)
                    if job.deliveries > 1 or job.kind is JobKind.PLAN:
                        break
                if not batch:
                    break
                sends.append((worker, batch, frames))
        for worker, batch, frames in sends:  # spooled payloads read here, outside the lock
            try:
                data = read_spooled(frames)
            except OSError as exc:
                self._unreadable(worker, batch, exc)
                continue
            with contextlib.suppress(OSError):  # on failure, the EOF on its pipe re-queues the jobs
                worker.send({"op": "run", "jobs": batch}, *data)
            read = sum(len(d) for d, f in zip(data, frames, strict=True) if isinstance(f, int))
            with self._lock:
                self._freed.add(read)  # the spooled payloads read for it, let go once sent

    def _unreadable(self, worker: WorkerHandle, batch: list[dict[str, Any]], exc: OSError) -> None:
        """A batch whose spooled payloads could not be read (the disk failed): its jobs fail, nothing is sent."""
        log.error("spooled payloads could not be read", extra={"error": str(exc)})
        error = unreadable_error(exc)
        with self._lock:
            for entry in batch:
                worker.inflight.discard(entry["id"])
                job = self._jobs.get(entry["id"])
                if job is not None and not job.state.terminal:
                    self._finish(job, error=error)

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
                fits = len(self._finished) <= self.settings.max_results
                fits = fits and self._result_bytes <= self.settings.max_result_bytes
                if fits and (job.finished_at or now) + ttl > now:
                    break
                self._finished.popitem(last=False)
                self._result_bytes -= len(job.result or b"")
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
        self._result_bytes += len(result or b"") - len(job.result or b"")
        self._freed.add(len(job.payload))
        if job.spooled is not None:
            remove_payload(job.spooled)  # a dispatch reading it holds its descriptor
        job.result, job.error, job.payload, job.spooled = result, error, b"", None
        job.state = JobState.SUCCEEDED if error is None else state_for_error(error)
        if job.state is JobState.SUCCEEDED:
            job.progress = JobProgress(stage=Stage.DONE, fraction=1.0)
            self._totals["completed"] += 1
        elif job.state is JobState.FAILED:
            self._totals["failed"] += 1
        self._finished[job.id] = None
        for loop, future in self._waiters.pop(job.id, []):
            loop.call_soon_threadsafe(settle, future, None)
