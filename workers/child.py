"""The embedded backend's worker process: loads the pipeline (and model) once, then runs the micro-batches its
parent sends over a duplex pipe, streaming progress and outcomes back.

Messages are msgpack maps (`clients.codec`). Parent → child: ``run`` (jobs), ``cancel`` (id), ``robot`` (validate
a registration), ``stop`` (finish the current batch, then exit). Child → parent: ``hello`` (worker info and
built-in robots), ``heartbeat``, ``progress``, ``done`` (outcome and timings), ``robot`` (validation answer).
"""

from __future__ import annotations

import logging
import os
import signal
import socket
import threading
import time
from multiprocessing.connection import Connection
from typing import Any

from clients.codec import pack, unpack
from clients.schemas import ErrorBody, JobProgress, RobotRegister, Stage, SynthesisRequest, WorkerPublic
from workers.logs import job_context, setup_logging
from workers.pipeline import JobInput, Pipeline, error_from_exception, load_pipeline
from workers.runner import run_batch
from workers.settings import QueueSettings

log = logging.getLogger("workers.child")


class _Link:
    """The child's end of the pipe: thread-safe sends, and an inbox drained between stages."""

    def __init__(self, conn: Connection) -> None:
        self.conn = conn
        self.lock = threading.Lock()
        self.cancelled: set[str] = set()
        self.deferred: list[dict[str, Any]] = []
        self.stopping = False

    def send(self, message: dict[str, Any]) -> None:
        data = pack(message)
        with self.lock:
            self.conn.send_bytes(data)

    def drain(self) -> None:
        """Take in what the parent sent while a batch runs (cancels, stop; anything else waits)."""
        while self.conn.poll(0):
            self._take(unpack(self.conn.recv_bytes()))

    def _take(self, msg: dict[str, Any]) -> None:
        if msg["op"] == "cancel":
            self.cancelled.add(msg["id"])
        elif msg["op"] == "stop":
            self.stopping = True
        else:
            self.deferred.append(msg)

    def next(self, timeout: float) -> dict[str, Any] | None:
        if self.deferred:
            return self.deferred.pop(0)
        if not self.conn.poll(timeout):
            return None
        return unpack(self.conn.recv_bytes())


def child_main(worker_id: str, settings_json: str, conn: Connection) -> None:
    """Body of a spawned worker process (``python -m workers.child WORKER_ID FD``, settings in the environment
    variable ``MANI_WORKER_SETTINGS`` as JSON; FD is its end of a socketpair)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the parent decides when we stop
    settings = QueueSettings.model_validate_json(settings_json)
    setup_logging(settings.log_level, worker_id)
    link = _Link(conn)
    signal.signal(signal.SIGTERM, lambda *_: setattr(link, "stopping", True))
    started = time.time()
    pipeline = load_pipeline(settings.pipeline, settings.pipeline_options, settings.weights_dir)
    info = WorkerPublic(
        id=worker_id,
        host=socket.gethostname(),
        pid=os.getpid(),
        started_at=started,
        last_heartbeat=time.time(),
        model_loaded=pipeline.model_loaded,
        model_version=pipeline.model_version,
    )
    robots = [r.model_dump(mode="python", exclude_none=True) for r in pipeline.robots()]
    link.send({"op": "hello", "worker": info.model_dump(mode="python", exclude_none=True), "robots": robots})
    log.info("worker ready", extra={"model_loaded": pipeline.model_loaded})
    beat = threading.Thread(target=_heartbeat, args=(link, settings.heartbeat_interval), daemon=True)
    beat.start()
    try:
        while not link.stopping:
            msg = link.next(0.5)
            if msg is None:
                continue
            if msg["op"] == "run":
                _run(pipeline, link, msg["jobs"])
            elif msg["op"] == "robot":
                _robot(pipeline, link, msg)
            else:
                link._take(msg)
    except (EOFError, OSError):
        pass  # the parent went away
    log.info("worker stopped")


def _heartbeat(link: _Link, interval: float) -> None:
    while True:
        time.sleep(interval)
        try:
            link.send({"op": "heartbeat", "t": time.time()})
        except (OSError, ValueError):
            return


def _run(pipeline: Pipeline, link: _Link, raw_jobs: list[dict[str, Any]]) -> None:
    jobs: list[JobInput] = []
    for raw in raw_jobs:
        try:
            jobs.append(
                JobInput(
                    id=raw["id"],
                    request=SynthesisRequest.model_validate(unpack(raw["request"])),
                    deadline=raw.get("deadline"),
                    robot=RobotRegister.model_validate(raw["robot"]) if raw.get("robot") else None,
                    request_id=raw.get("request_id"),
                )
            )
        except Exception as exc:  # a queue payload is input too: fail that job, not the worker
            error = error_from_exception(exc).model_dump(mode="python", exclude_none=True)
            link.send({"op": "done", "id": raw["id"], "error": error, "timings": {}})
            with job_context(raw["id"], raw.get("request_id")):
                log.warning("job rejected", extra={"error": error["error"]})
            continue
        with job_context(jobs[-1].id, jobs[-1].request_id):
            log.info("job started")
    last: dict[str, float] = {}

    def progress(job_id: str, stage: Stage, fraction: float, iteration: int | None, maximum: int | None) -> None:
        now = time.monotonic()
        if stage is Stage.REFINEMENT and now - last.get(job_id, 0.0) < 0.05 and iteration != maximum:
            return  # throttle per-iteration updates
        last[job_id] = now
        p = JobProgress(stage=stage, fraction=min(max(fraction, 0.0), 1.0), iteration=iteration, max_iterations=maximum)
        link.send({"op": "progress", "id": job_id, "p": p.model_dump(mode="python", exclude_none=True)})

    def should_cancel(job_id: str) -> bool:
        link.drain()
        return job_id in link.cancelled

    t0 = time.perf_counter()
    outcomes = run_batch(pipeline, jobs, progress, should_cancel)
    elapsed = time.perf_counter() - t0
    for job in jobs:
        outcome = outcomes[job.id]
        body = outcome.model_dump(mode="python", exclude_none=True)
        key = "error" if isinstance(outcome, ErrorBody) else "result"
        timings = {**getattr(outcome, "timings", {}), "run": elapsed}
        link.send({"op": "done", "id": job.id, key: body, "timings": timings})
        with job_context(job.id, job.request_id):
            log.info("job finished", extra={"outcome": outcome.type if isinstance(outcome, ErrorBody) else "ok"})
        link.cancelled.discard(job.id)


def _robot(pipeline: Pipeline, link: _Link, msg: dict[str, Any]) -> None:
    try:
        robot = pipeline.validate_robot(RobotRegister.model_validate(msg["robot"]))
        link.send({"op": "robot", "rid": msg["rid"], "robot": robot.model_dump(mode="python", exclude_none=True)})
    except Exception as exc:
        link.send({"op": "robot", "rid": msg["rid"], "error": str(exc) or exc.__class__.__name__})


if __name__ == "__main__":
    import sys

    child_main(sys.argv[1], os.environ["MANI_WORKER_SETTINGS"], Connection(int(sys.argv[2])))
