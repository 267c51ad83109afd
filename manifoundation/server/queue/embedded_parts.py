"""Handles of the embedded backend: a job's in-memory record, a worker process and its pipe."""

from __future__ import annotations

import asyncio
import contextlib
import subprocess
import threading
import time
from multiprocessing.connection import Connection
from typing import Any

from manifoundation.contract import ErrorBody, ErrorType, JobKind, JobProgress, JobPublic, JobState, WorkerPublic
from manifoundation.contract.codec import pack
from manifoundation.server.queue.records import STILL_LOADING


class JobRecord:
    """A job as the embedded queue keeps it: its payload in memory, or in the queue's spool (``spooled``: the
    file; `manifoundation.server.spool`); dropped once terminal."""

    __slots__ = (
        "batch_id", "cancel", "created_at", "deadline", "deliveries", "error", "finished_at", "id", "kind", "owner",
        "payload", "progress", "request_id", "result", "robot", "spooled", "started_at", "state", "timings", "worker",
    )  # fmt: skip

    def __init__(
        self, job_id: str, payload: bytes, robot: str | None, deadline: float | None, batch: str | None,
        request_id: str | None = None, owner: str | None = None, kind: JobKind = JobKind.SYNTHESIS,
    ) -> None:  # fmt: skip
        self.id, self.payload, self.robot, self.deadline, self.batch_id = job_id, payload, robot, deadline, batch
        self.kind = kind
        self.spooled: str | None = None
        self.request_id = request_id  # X-Request-ID of the submitting HTTP request (internal: logs, operators)
        self.owner = owner  # the tenant (internal: never in JobPublic)
        self.created_at = time.time()
        self.state = JobState.QUEUED
        self.progress = JobProgress()
        self.started_at: float | None = None
        self.finished_at: float | None = None
        self.deliveries = 0
        self.worker: str | None = None
        self.timings: dict[str, float] = {}
        self.result: bytes | None = None  # msgpack of the SynthesisResult (PlanResult), as the worker encoded it
        self.error: ErrorBody | None = None
        self.cancel = False

    def public(self) -> JobPublic:
        """The job without its result (the caller decodes ``result`` outside the queue's lock)."""
        return JobPublic(
            id=self.id,
            kind=self.kind,
            state=self.state,
            progress=self.progress.model_copy(),
            created_at=self.created_at,
            started_at=self.started_at,
            finished_at=self.finished_at,
            deadline=self.deadline,
            deliveries=self.deliveries,
            worker=self.worker,
            batch_id=self.batch_id,
            timings=dict(self.timings),
            error=self.error,
        )


class ChildProcess:
    """The few `multiprocessing.Process` methods we use, over a `subprocess.Popen`."""

    def __init__(self, popen: subprocess.Popen[bytes]) -> None:
        self.popen = popen
        self.pid = popen.pid

    @property
    def exitcode(self) -> int | None:
        return self.popen.poll()

    def is_alive(self) -> bool:
        return self.popen.poll() is None

    def join(self, timeout: float | None = None) -> None:
        with contextlib.suppress(subprocess.TimeoutExpired):
            self.popen.wait(timeout)

    def terminate(self) -> None:
        with contextlib.suppress(ProcessLookupError):
            self.popen.terminate()

    def kill(self) -> None:
        with contextlib.suppress(ProcessLookupError):
            self.popen.kill()


class WorkerHandle:
    """One worker process, its end of the socketpair, and the jobs it runs."""

    def __init__(self, worker_id: str, process: ChildProcess, conn: Connection) -> None:
        self.id, self.process, self.conn = worker_id, process, conn
        self.lock = threading.Lock()
        self.info: WorkerPublic | None = None
        self.inflight: set[str] = set()
        self.registering: dict[str, float] = {}  # registrations sent to it, not yet answered: rid -> deadline (epoch)
        self.leaving = False  # it answered a registration at its deadline and is ending itself
        self.jobs_done = 0
        self.last_seen = time.monotonic()  # any message (hello, heartbeat, progress, outcome) read from it

    @property
    def ready(self) -> bool:
        """Said hello and is not ending itself."""
        return self.info is not None and not self.leaving

    @property
    def idle(self) -> bool:
        """Ready, and neither running jobs nor loading a robot (a job is never queued behind a registration)."""
        return self.ready and not self.inflight and not self.registering

    def answered(self, msg: dict[str, Any]) -> None:
        """Its answer to a registration arrived (one stopped at its deadline: it is ending itself)."""
        self.registering.pop(msg["rid"], None)
        self.leaving = self.leaving or msg.get("type") == ErrorType.DEADLINE_EXCEEDED.value

    def unanswered(self, detail: str) -> dict[str, dict[str, Any]]:
        """The answers of the registrations it took with it (it died): past their deadline, it was stopped there
        (`manifoundation.server.worker.overrun`); before, it died of something else (``detail``)."""
        now, registering, self.registering = time.time(), self.registering, {}
        late = {"error": STILL_LOADING, "type": ErrorType.DEADLINE_EXCEEDED.value}
        died = {"error": f"the worker loading the robot died ({detail}); try again"}
        died["type"] = ErrorType.UNAVAILABLE.value
        return {rid: late if now >= deadline else died for rid, deadline in registering.items()}

    def send(self, message: dict[str, Any], *frames: bytes) -> None:
        """``message``, then the payload frames it announces (see `manifoundation.server.worker.child`)."""
        data = pack(message)
        with self.lock:
            self.conn.send_bytes(data)
            for frame in frames:
                self.conn.send_bytes(frame)


def settle(future: asyncio.Future[Any], value: Any) -> None:
    if not future.done():
        future.set_result(value)
