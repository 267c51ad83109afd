"""Embedded backend: an in-process queue feeding N spawned worker processes (the default; NOT durable).

Jobs, results and dead letters live in this process's memory: they are lost when it exits. Results are kept
``result_ttl`` seconds, at most ``max_results`` finished jobs and ``max_result_bytes`` of their results (oldest
evicted first: memory stays bounded whatever the results' size); an evicted job still answers state "expired"
(a bounded list of tombstones), never "unknown". One pump thread talks to the workers over one duplex pipe each
(`manifoundation.server.worker.child`): it dispatches up to ``batch_size`` queued jobs to an idle worker, takes progress
and outcomes back, and notices a dead worker (EOF): its jobs go back to the queue until they have been delivered
``max_deliveries`` times, then to the dead letters with the error; a replacement is spawned. A job given back
that way runs alone (a micro-batch of one), so a job that kills its worker fails no batch-mate.

Payloads over `manifoundation.server.spool.SPOOL_BYTES` wait in a spool directory of the queue's own (removed when
it closes), not in memory; a body process may pack a large batch straight into it (`spool`).

This module is the queue's asyncio API; the state and the pump thread are `manifoundation.server.queue.embedded_pump`.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import threading
import time
from collections.abc import Sequence

from manifoundation.contract import (
    DeadLetter,
    JobPublic,
    JobRequest,
    JobState,
    QueueStats,
    SynthesisRequest,
    WorkerPublic,
)
from manifoundation.server.queue.base import (
    JobNotFound,
    JobQueue,
    QueueFull,
    QueueUnavailable,
)
from manifoundation.server.queue.embedded_parts import JobRecord, WorkerHandle
from manifoundation.server.queue.embedded_payloads import discard_spooled, packed
from manifoundation.server.queue.embedded_robots import EmbeddedRobots
from manifoundation.server.queue.records import (
    cancelled_error,
    new_id,
    result_expired_error,
    shutdown_error,
    with_answer,
)
from manifoundation.server.spool import SpooledRequest, job_kind, new_spool, remove_spool, robot_of

log = logging.getLogger("manifoundation.server.queue.embedded")


class EmbeddedQueue(EmbeddedRobots, JobQueue):
    """In-process queue + ``concurrency`` spawned worker processes (see module doc)."""

    backend = "embedded"

    # ---- lifecycle -------------------------------------------------------------------------------------------
    async def start(self) -> None:
        if self._running:
            return
        self._running = True
        self.spool = new_spool()
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
        if self.spool is not None:
            remove_spool(self.spool)
            self.spool = None

    async def ping(self) -> bool:
        return self._running

    # ---- submit / observe ------------------------------------------------------------------------------------
    async def submit(
        self, requests: Sequence[JobRequest | SpooledRequest], *, batch_id: str | None = None,
        deadline: float | None = None, request_id: str | None = None, owner: str | None = None,
    ) -> list[str]:  # fmt: skip
        if not self._running:
            raise QueueUnavailable("the embedded queue is not running")
        try:
            payloads = await packed(requests, self.spool)
        except OSError as exc:  # the spool's disk (full, gone): nothing was kept
            raise QueueUnavailable(f"the queue's spool could not take the payload: {exc}") from exc
        try:
            with self._lock:
                if len(self._pending) + len(requests) > self.settings.max_queue:
                    raise QueueFull(f"queue holds {len(self._pending)} jobs (max {self.settings.max_queue})", 1.0)
                ids = []
                for request, payload in zip(requests, payloads, strict=True):
                    data = payload if isinstance(payload, bytes) else b""
                    job = JobRecord(new_id(), data, robot_of(request), deadline, batch_id, request_id, owner,
                                    job_kind(request))  # fmt: skip
                    job.spooled = payload.path if isinstance(payload, SpooledRequest) else None
                    self._jobs[job.id] = job
                    self._pending.append(job.id)
                    ids.append(job.id)
        except BaseException:  # refused: the payloads this call spooled go
            discard_spooled(payloads, requests)
            raise
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
            return with_answer(public, raw)  # the one validation of a result on the service side, outside the lock
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
        self, requests: Sequence[SynthesisRequest | SpooledRequest], deadline: float | None = None, *,
        request_id: str | None = None, owner: str | None = None,
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
                workers=sum(1 for w in self._workers.values() if self._live(w)),
            )

    async def workers(self) -> list[WorkerPublic]:
        with self._lock:
            out = []
            for w in self._workers.values():
                if self._live(w) and w.info is not None:
                    current = next(iter(w.inflight), None)
                    out.append(w.info.model_copy(update={"current_job": current, "jobs_done": w.jobs_done}))
            return out

    async def dead_letters(self, limit: int = 50) -> list[DeadLetter]:
        with self._lock:
            return list(self._dead)[::-1][:limit]
