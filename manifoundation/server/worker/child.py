"""The embedded backend's worker process: a thin shell around `manifoundation.server.worker.core.WorkerCore` that speaks
to its parent (`mani serve`) over a duplex pipe.

Messages are msgpack maps (`manifoundation.contract.codec`); payloads travel as their own frames after the map that
announces them, so a request or a result is never encoded inside another message. Parent → child: ``run`` (job metadata,
then per job its request frame and, when it names a registered robot, the robot's frame), ``cancel`` (id), ``robot``
(then the registration's frame: validate it), ``stop`` (finish the current batch, then exit). Child → parent: ``hello``
(worker info and built-in robots), ``heartbeat``, ``progress``, ``done`` (state, error, timings; then the result's frame
when it succeeded), ``robot`` (validation answer). A ``robot`` message carries its ``deadline``: still loading then,
the child answers and exits (`manifoundation.server.worker.overrun`), and the parent spawns another.
"""

from __future__ import annotations

import logging
import os
import signal
import threading
import time
from multiprocessing.connection import Connection
from typing import Any

from manifoundation.contract import JobKind, JobProgress
from manifoundation.contract.codec import pack, unpack
from manifoundation.server.worker.core import RawJob, WorkerCore
from manifoundation.server.worker.logs import setup_logging
from manifoundation.server.worker.pipeline import load_pipeline
from manifoundation.server.worker.settings import QueueSettings

log = logging.getLogger("manifoundation.server.worker.child")


class _Link:
    """The child's end of the pipe: thread-safe sends, and an inbox drained between stages."""

    def __init__(self, conn: Connection) -> None:
        self.conn = conn
        self.lock = threading.Lock()
        self.cancelled: set[str] = set()
        self.deferred: list[dict[str, Any]] = []
        self.stopping = False

    def send(self, message: dict[str, Any], *frames: bytes) -> None:
        data = pack(message)
        with self.lock:
            self.conn.send_bytes(data)
            for frame in frames:
                self.conn.send_bytes(frame)

    def receive(self) -> dict[str, Any]:
        """One message, with the frames it announces read into ``frames``."""
        msg: dict[str, Any] = unpack(self.conn.recv_bytes())
        count = sum(1 + bool(j.get("robot")) for j in msg["jobs"]) if msg["op"] == "run" else int(msg["op"] == "robot")
        msg["frames"] = [self.conn.recv_bytes() for _ in range(count)]
        return msg

    def drain(self) -> None:
        """Take in what the parent sent while a batch runs (cancels, stop; anything else waits)."""
        while self.conn.poll(0):
            self.take(self.receive())

    def take(self, msg: dict[str, Any]) -> None:
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
        return self.receive()


def child_main(worker_id: str, settings_json: str, conn: Connection) -> None:
    """Body of a spawned worker process (``python -m manifoundation.server.worker.child WORKER_ID FD``, settings in the
    environment
    variable ``MANI_WORKER_SETTINGS`` as JSON; FD is its end of a socketpair)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the parent decides when we stop
    settings = QueueSettings.model_validate_json(settings_json)
    setup_logging(settings.log_level, worker_id)
    link = _Link(conn)
    signal.signal(signal.SIGTERM, lambda *_: setattr(link, "stopping", True))
    core = WorkerCore(load_pipeline(settings.pipeline, settings.pipeline_options, settings.weights_dir))
    info = core.info(worker_id)
    robots = [r.model_dump(mode="python", exclude_none=True) for r in core.robots()]
    link.send({"op": "hello", "worker": info.model_dump(mode="python", exclude_none=True), "robots": robots})
    log.info("worker ready", extra={"model_loaded": info.model_loaded})
    threading.Thread(target=_heartbeat, args=(link, settings.heartbeat_interval), daemon=True).start()
    try:
        while not link.stopping:
            msg = link.next(0.5)
            if msg is None:
                continue
            if msg["op"] == "run":
                _run(core, link, msg)
            elif msg["op"] == "robot":
                _robot(core, link, msg)
            else:
                link.take(msg)
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


def _run(core: WorkerCore, link: _Link, msg: dict[str, Any]) -> None:
    frames = iter(msg["frames"])
    raw_jobs = [
        RawJob(
            id=j["id"], request=next(frames), deadline=j.get("deadline"),
            robot=next(frames) if j.get("robot") else None, request_id=j.get("request_id"),
            queued_for=float(j.get("queued_for", 0.0)), kind=JobKind(j.get("kind", JobKind.SYNTHESIS.value)),
        )
        for j in msg["jobs"]
    ]  # fmt: skip

    def progress(job_id: str, p: JobProgress) -> None:
        link.send({"op": "progress", "id": job_id, "p": p.model_dump(mode="python", exclude_none=True)})

    def should_cancel(job_id: str) -> bool:
        link.drain()
        return job_id in link.cancelled

    for done in core.run(raw_jobs, progress, should_cancel):
        error = done.error.model_dump(mode="python", exclude_none=True) if done.error else None
        header = {"op": "done", "id": done.id, "state": done.state.value, "error": error, "timings": done.timings}
        link.send(header, *([done.result] if done.result is not None else []))
        link.cancelled.discard(done.id)


def _robot(core: WorkerCore, link: _Link, msg: dict[str, Any]) -> None:
    """Validate a registration and answer it; one still loading at its ``deadline`` is answered and this process
    ends there (the parent replaces it)."""

    def answer(reply: dict[str, Any]) -> None:
        link.send({"op": "robot", "rid": msg["rid"], **reply})

    answer(core.validate_robot(msg["frames"][0], msg.get("deadline"), answer))


if __name__ == "__main__":
    import sys

    child_main(sys.argv[1], os.environ["MANI_WORKER_SETTINGS"], Connection(int(sys.argv[2])))
