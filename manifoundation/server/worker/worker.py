"""A Redis Streams worker process: load the pipeline (model) once, then consume micro-batches.

Loop: XAUTOCLAIM entries idle longer than ``visibility_timeout`` (their worker died), one at a time (a re-delivered job
runs alone, so a job that kills its worker takes no batch-mate down), else XREADGROUP COUNT = ``batch_size`` (waiting up
to ``max_wait_ms`` to fill a batch); for each job the BEGIN script counts the delivery (beyond ``max_deliveries`` →
dead-letter stream, the job failed with its last error), drops expired or cancelled jobs, marks it running; the batch
runs through the worker core (`manifoundation.server.worker.core`); the FINISH script writes the result (msgpack, TTL)
and acks in one atomic step, only while this worker still owns the entry. A heartbeat thread publishes the worker's
state and XCLAIMs its own in-flight entries so a long job is not stolen. SIGTERM: finish the current batch, then exit.
Redis going away: retry with back-off, recreate the group, go on; an outcome that could not be written while Redis was
down is retried until it is (`_end_durably`), so no job stays "running". Redis at its maxmemory (noeviction) refuses
writes: an outcome is retried every second or so and, after `OOM_RESULT_RETRY_S`, written as a failure without its
result (``Unavailable``, said plainly); entries taken whose BEGIN was refused are begun again by this worker after a
short back-off. Neither waits for the visibility timeout.

Run as ``python -m manifoundation.server.worker.worker`` (settings as JSON in ``MANI_WORKER_SETTINGS``, else
``MANI_*``); `mani worker` supervises several of these.

Why one module: one consumer's loop: claiming, delivery, heartbeats and durable outcomes share its in-flight
bookkeeping and lock.
"""

from __future__ import annotations

import contextlib
import logging
import math
import os
import signal
import socket
import threading
import time
from typing import Any

import redis
from redis.exceptions import ConnectionError as RedisConnectionError
from redis.exceptions import OutOfMemoryError, RedisError, ResponseError
from redis.exceptions import TimeoutError as RedisTimeoutError

from manifoundation.contract import (
    DeadLetter,
    ErrorBody,
    ErrorType,
    JobKind,
    JobProgress,
    Stage,
    WorkerPublic,
)
from manifoundation.contract.codec import pack
from manifoundation.server.queue.records import cancelled_error, deadline_error, new_id, scoped_robot
from manifoundation.server.queue.redis import public_reason
from manifoundation.server.queue.redis_lua import BEGIN, FINISH, GROUP, TOUCH, Keys
from manifoundation.server.worker.core import PROGRESS_INTERVAL_S, RawJob, WorkerCore, runs_of
from manifoundation.server.worker.logs import job_context, setup_logging
from manifoundation.server.worker.pipeline import load_pipeline
from manifoundation.server.worker.settings import QueueSettings
from manifoundation.server.worker.supervisor import announce_ready

log = logging.getLogger("manifoundation.server.worker.worker")
PROGRESS_S = PROGRESS_INTERVAL_S
"""Seconds between a job's cancel-flag reads (as between its progress writes: short jobs stay at ~4 round trips)."""
END_RETRY_S = 30.0
"""How long a stopping worker keeps retrying to write an outcome while Redis is unreachable."""
OOM_RESULT_RETRY_S = 10.0
"""How long an outcome refused by a Redis at its maxmemory is retried with its result; after that the job is
failed without it (a much smaller write), so its caller learns why instead of waiting."""
REFUSED_BACKOFF_MAX_S = 1.0
"""The longest pause between retries of a write Redis refused for lack of memory (memory may free at any time)."""


def out_of_memory(exc: BaseException) -> bool:
    """Whether Redis refused a write because its maxmemory is reached (noeviction)."""
    text = str(exc)
    return isinstance(exc, OutOfMemoryError) or text.startswith("OOM") or "maxmemory" in text


class RedisWorker:
    """One consumer of the job stream (see module doc)."""

    def __init__(self, settings: QueueSettings, worker_id: str | None = None) -> None:
        if not settings.redis_url:
            raise ValueError("redis_url: a Redis worker needs MANI_REDIS_URL / --redis")
        self.settings = settings
        self.id = worker_id or f"{socket.gethostname()}-{os.getpid()}-{new_id()[:6]}"
        self.keys = Keys(settings.queue_prefix)
        limit = settings.redis_timeout
        blocking = 1.0 + settings.max_wait_ms / 1000  # XREADGROUP BLOCK waits that long beyond the round trip
        self.r: Any = redis.Redis.from_url(
            settings.redis_url, socket_connect_timeout=limit, socket_timeout=limit + blocking
        )
        self.stopping = False
        self.inflight: dict[str, str] = {}  # entry id -> job id
        self.lock = threading.Lock()
        self.jobs_done = 0
        self.cancel_checked: dict[str, float] = {}
        self.builtin_robots: set[str] = set()
        self.core: WorkerCore | None = None
        self.info: WorkerPublic | None = None
        self._begin, self._finish = self.r.register_script(BEGIN), self.r.register_script(FINISH)
        self._last_claim = 0.0
        self._last_orphans = 0.0
        self._last_tidy = time.monotonic()
        self._healthy_since = -math.inf  # since this worker's last Redis error: other workers had time to beat
        self._retake: list[tuple[bytes, dict[bytes, bytes]]] = []  # taken, not begun (a write refused): begin again

    # ---- lifecycle -------------------------------------------------------------------------------------------
    def run(self) -> None:
        """Serve until `stop()` (SIGTERM)."""
        s = self.settings
        self.core = WorkerCore(load_pipeline(s.pipeline, s.pipeline_options, s.weights_dir))
        self.info = self.core.info(self.id)
        if not self._connect_when_up():
            return
        beat = threading.Thread(target=self._heartbeat_loop, name="mani-heartbeat", daemon=True)
        beat.start()
        log.info("worker ready", extra={"model_loaded": self.info.model_loaded})
        announce_ready()
        backoff = 0.1
        while not self.stopping:
            try:
                entries = self._take()
                if entries:
                    self._handle(entries)
                backoff = 0.1
            except RedisError as exc:
                refused = out_of_memory(exc)
                log.warning("redis error, retrying in %.1f s: %s", backoff, public_reason(exc) if refused else exc)
                self._healthy_since = time.monotonic()
                time.sleep(backoff)
                backoff = min(backoff * 2, REFUSED_BACKOFF_MAX_S if refused else 5.0)
                self._connect(quiet=True)
        self._leave()
        log.info("worker stopped")

    def stop(self, *_: object) -> None:
        self.stopping = True

    @property
    def _core(self) -> WorkerCore:
        if self.core is None:
            raise RuntimeError("the worker has not loaded its pipeline yet (call run())")
        return self.core

    def _connect(self, quiet: bool = False) -> None:
        """Create the group (if Redis lost it) and publish the built-in robots."""
        try:
            with_group = True
            try:
                self.r.xgroup_create(self.keys.stream, GROUP, id="0", mkstream=True)
            except ResponseError:
                with_group = False
            robots = {r.name: pack(r.model_dump(mode="python", exclude_none=True)) for r in self._core.robots()}
            self.builtin_robots = set(robots)
            if robots:
                self.r.hset(self.keys.robots, mapping=robots)
            if with_group:
                log.info("created consumer group")
            self._beat()
        except RedisError:
            if not quiet:
                raise

    def _connect_when_up(self) -> bool:
        """`_connect`, retried with back-off while Redis is unreachable (a worker started during a Redis restart
        waits instead of exiting); False when told to stop first."""
        backoff = 0.1
        while not self.stopping:
            try:
                self._connect()
                return True
            except RedisError as exc:
                log.warning("redis unreachable at start, retrying in %.1f s: %s", backoff, exc)
                self._healthy_since = time.monotonic()
                time.sleep(backoff)
                backoff = min(backoff * 2, 5.0)
        return False

    def _leave(self) -> None:
        try:
            self.r.zrem(self.keys.workers, self.id)
            self.r.delete(self.keys.worker(self.id))
            pending = self.r.xpending_range(self.keys.stream, GROUP, "-", "+", 1, consumername=self.id)
            if not pending:
                self.r.xgroup_delconsumer(self.keys.stream, GROUP, self.id)
        except RedisError:
            pass

    # ---- heartbeats ------------------------------------------------------------------------------------------
    def _heartbeat_loop(self) -> None:
        limit = self.settings.redis_timeout
        client = redis.Redis.from_url(self.settings.redis_url or "", socket_connect_timeout=limit, socket_timeout=limit)
        touch = client.register_script(TOUCH)
        while not self.stopping:
            time.sleep(self.settings.heartbeat_interval)
            try:
                self._beat(client)
            except RedisError as exc:  # e.g. refused at maxmemory: the entries are touched all the same
                log.debug("heartbeat failed: %s", exc)
            try:  # XCLAIM is allowed at maxmemory: a worker waiting for memory keeps its jobs
                with self.lock:
                    entries = list(self.inflight)
                if entries:
                    touch(keys=[self.keys.stream], args=[GROUP, self.id, *entries], client=client)
            except RedisError as exc:
                log.debug("touch failed: %s", exc)

    def _beat(self, client: Any = None) -> None:
        assert self.info is not None
        now = time.time()
        with self.lock:
            current = next((job for job in self.inflight.values() if job), None)
        info = self.info.model_copy(update={"last_heartbeat": now, "current_job": current, "jobs_done": self.jobs_done})
        ttl = int(self.settings.heartbeat_timeout * 1000)
        pipe = (client or self.r).pipeline(transaction=False)
        pipe.set(self.keys.worker(self.id), pack(info.model_dump(mode="python", exclude_none=True)), px=ttl)
        pipe.zadd(self.keys.workers, {self.id: now})
        pipe.execute()

    # ---- consuming -------------------------------------------------------------------------------------------
    def _tidy(self) -> None:
        """Forget consumers of workers that died long ago and own nothing (their names are never reused)."""
        idle_ms = 1000 * max(60.0, 10 * self.settings.visibility_timeout)
        for consumer in self.r.xinfo_consumers(self.keys.stream, GROUP):
            name = consumer["name"].decode() if isinstance(consumer["name"], bytes) else consumer["name"]
            if name != self.id and int(consumer["pending"]) == 0 and int(consumer["idle"]) > idle_ms:
                self.r.xgroup_delconsumer(self.keys.stream, GROUP, name)

    def _orphan(self) -> list[tuple[bytes, dict[bytes, bytes]]]:
        """One entry of a consumer whose heartbeat key has expired (its worker died): claimed within seconds of
        the death instead of after the visibility timeout. Only once Redis has been up, and this worker talking
        to it, for a heartbeat timeout (after a Redis restart or a hang every live worker's key is gone until its
        next beat; a worker that has just started has no such doubt), and only an entry idle that long too (a
        live worker's heartbeat keeps resetting its entries' idle time)."""
        timeout = self.settings.heartbeat_timeout
        settle = timeout + self.settings.heartbeat_interval
        if time.monotonic() - self._healthy_since < settle or self._redis_uptime() < settle:
            return []
        for consumer in self.r.xinfo_consumers(self.keys.stream, GROUP):
            name = consumer["name"].decode() if isinstance(consumer["name"], bytes) else consumer["name"]
            if name == self.id or int(consumer["pending"]) == 0 or self.r.exists(self.keys.worker(name)):
                continue
            for pending in self.r.xpending_range(self.keys.stream, GROUP, "-", "+", 1, consumername=name):
                claimed = self.r.xclaim(self.keys.stream, GROUP, self.id, int(timeout * 1000), [pending["message_id"]])
                entries = [(e, f) for e, f in claimed if f]
                if entries:
                    log.info("re-delivering an entry of dead worker %s (no heartbeat)", name)
                    return entries
        return []

    def _redis_uptime(self) -> float:
        """Seconds since the Redis server started (INFO server)."""
        return float(self.r.info("server").get("uptime_in_seconds", 0))

    def _take(self) -> list[tuple[bytes, dict[bytes, bytes]]]:
        if self._retake:  # still this worker's in the stream's pending list (the heartbeat kept them)
            entries, self._retake = self._retake, []
            with self.lock:
                for entry, _ in entries:
                    self.inflight.pop(entry.decode(), None)
            return entries
        size = self.settings.batch_size
        now = time.monotonic()
        if now - self._last_tidy > 30.0:
            self._last_tidy = now
            with contextlib.suppress(ResponseError):
                self._tidy()
        if now - self._last_orphans > self.settings.heartbeat_interval:
            self._last_orphans = now
            with contextlib.suppress(ResponseError):
                orphan = self._orphan()
                if orphan:
                    self._last_orphans = 0.0  # look for the next one at once
                    return orphan
        if now - self._last_claim > min(1.0, self.settings.visibility_timeout / 4):
            self._last_claim = now
            idle = int(self.settings.visibility_timeout * 1000)
            try:  # one at a time: a re-delivered job runs alone, so a poison job fails no batch-mate
                claimed = self.r.xautoclaim(self.keys.stream, GROUP, self.id, idle, "0-0", count=1)
            except ResponseError:  # NOGROUP after a Redis restart
                self._connect()
                return []
            entries = [(e, f) for e, f in claimed[1] if f]
            if entries:
                self._last_claim = 0.0  # look for the next one at once
                log.info("re-delivering an entry of a stopped worker")
                return entries
        try:
            got = self.r.xreadgroup(GROUP, self.id, {self.keys.stream: ">"}, count=size, block=1000)
        except ResponseError:
            self._connect()
            return []
        entries = list(got[0][1]) if got else []
        if entries and len(entries) < size and self.settings.max_wait_ms > 0:
            more = self.r.xreadgroup(
                GROUP, self.id, {self.keys.stream: ">"}, count=size - len(entries),
                block=max(1, int(self.settings.max_wait_ms)),
            )  # fmt: skip
            entries += list(more[0][1]) if more else []
        return entries

    def _handle(self, entries: list[tuple[bytes, dict[bytes, bytes]]]) -> None:
        """Run the jobs taken, then the registrations (a job never waits for a robot's loading, up to its
        registration deadline)."""
        robots = [(entry, fields) for entry, fields in entries if fields.get(b"k") == b"robot"]
        try:
            self._handle_jobs([(entry, fields) for entry, fields in entries if fields.get(b"k") != b"robot"])
        finally:
            for entry, fields in robots:
                self._robot(entry.decode(), fields)

    def _handle_jobs(self, entries: list[tuple[bytes, dict[bytes, bytes]]]) -> None:
        raw_jobs: list[RawJob] = []
        entry_of: dict[str, str] = {}
        refused: RedisError | None = None
        for index, (entry_raw, fields) in enumerate(entries):
            entry = entry_raw.decode()
            try:
                job_id = fields[b"id"].decode()
                request_id = fields[b"r"].decode() if fields.get(b"r") else None  # entries of older services lack it
                with job_context(job_id, request_id):
                    raw = self._start_job(entry, job_id, fields, request_id)
            except RedisError as exc:
                # Taken but not begun: without this the entries would wait for the visibility timeout. They stay
                # this worker's (the heartbeat touches them) and are begun again after the run loop's back-off.
                refused, self._retake = exc, list(entries[index:])
                with self.lock:
                    self.inflight.update({e.decode(): "" for e, _ in self._retake})
                break
            if raw is not None:
                raw_jobs.append(raw)
                entry_of[job_id] = entry
        if not raw_jobs:
            if refused is not None:
                raise refused
            return
        request_of = {j.id: j.request_id for j in raw_jobs}
        with self.lock:
            self.inflight.update({entry_of[j.id]: j.id for j in raw_jobs})
        try:
            for run in runs_of(raw_jobs):  # a plan alone: its batch-mates' outcomes are not held back for it
                for done in self._core.run(run, self._progress, self._should_cancel):
                    with job_context(done.id, request_of[done.id]):
                        self._end_durably(entry_of[done.id], done.id, done.state.value, result=done.result or b"",
                                          error=done.error, timings=done.timings)  # fmt: skip
                        self.jobs_done += 1
                    with self.lock:
                        self.inflight.pop(entry_of[done.id], None)
                    self.cancel_checked.pop(done.id, None)
        finally:  # whatever was not finished is given back: no heartbeat keeps it from re-delivery any more
            with self.lock:
                for raw in raw_jobs:
                    self.inflight.pop(entry_of[raw.id], None)
        if refused is not None:
            raise refused

    def _end_durably(self, entry: str, job_id: str, state: str, **outcome: Any) -> None:
        """`_end`, retried with back-off while Redis is unreachable (a restart, a failover): the outcome is
        written once Redis is back, and until then the heartbeat keeps the entry with this worker. Gives up
        (the entry is then re-delivered) only when stopping and Redis stays away for `END_RETRY_S` seconds, or
        when the job's stream is gone (Redis came back without its data)."""
        backoff, give_up = 0.1, float("inf")
        refused_since: float | None = None
        while True:
            try:
                self._end(entry, job_id, state, **outcome)
                return
            except ResponseError as exc:
                if not out_of_memory(exc):  # NOGROUP: Redis restarted without persistence, the job is gone
                    log.error("outcome discarded: the job's stream entry is gone (%s)", exc)
                    return
                now = time.monotonic()
                refused_since = now if refused_since is None else refused_since
                if self.stopping and give_up == float("inf"):
                    give_up = now + END_RETRY_S
                if now > give_up:
                    log.error("outcome not written, %s; the job will be re-delivered", public_reason(exc))
                    raise
                if outcome.get("result") and now - refused_since > OOM_RESULT_RETRY_S:
                    state, outcome = "failed", {"error": _unstorable(exc), "timings": outcome.get("timings")}
                    log.error("result not stored, %s: the job fails without it", public_reason(exc))
                    continue
                log.warning("outcome refused, %s; retrying in %.1f s", public_reason(exc), backoff)
                time.sleep(backoff)
                backoff = min(backoff * 2, REFUSED_BACKOFF_MAX_S)
            except (RedisConnectionError, RedisTimeoutError) as exc:
                if self.stopping and give_up == float("inf"):
                    give_up = time.monotonic() + END_RETRY_S
                if time.monotonic() > give_up:
                    log.error("outcome not written, Redis unreachable; the job will be re-delivered: %s", exc)
                    raise
                log.warning("outcome not written yet (%s); retrying in %.1f s", exc, backoff)
                time.sleep(backoff)
                backoff = min(backoff * 2, 2.0)

    def _start_job(self, entry: str, job_id: str, fields: dict[bytes, bytes], request_id: str | None) -> RawJob | None:
        """BEGIN the delivery; the job as the core takes it when it is to run, else end it here (dead, expired,
        cancelled or already terminal)."""
        s = self.settings
        now = time.time()
        verdict, deliveries, *rest = self._begin(keys=[self.keys.job(job_id)], args=[self.id, now, s.max_deliveries])
        verdict = verdict.decode()
        queued_for = now - float(rest[0]) if rest else 0.0
        if rest:
            self.cancel_checked[job_id] = time.monotonic()  # BEGIN just checked the cancel flag
        if verdict == "run":
            deadline = float(rest[1]) if len(rest) > 1 and rest[1] else None
            log.info("job delivered", extra={"delivery": int(deliveries)})
            robot = self._registered_robot(job_id, fields)
            kind = JobKind(fields[b"t"].decode()) if fields.get(b"t") else JobKind.SYNTHESIS
            return RawJob(job_id, fields[b"p"], deadline, robot, request_id, queued_for, kind)
        if verdict == "dead":
            h = self.r.hmget(self.keys.job(job_id), ["error", "error_type"])
            message = h[0].decode() if h[0] else "failed on every delivery"
            error = ErrorBody(error=message, type=h[1].decode() if h[1] else ErrorType.WORKER_LOST.value)
            letter = DeadLetter(job_id=job_id, deliveries=int(deliveries), error=error, failed_at=time.time())
            self.r.xadd(self.keys.dead, {"d": pack(letter.model_dump(mode="python"))}, maxlen=10_000)
            self._end(entry, job_id, "failed", error=error)
            log.warning("job dead-lettered", extra={"deliveries": int(deliveries)})
        elif verdict == "expired":
            self._end(entry, job_id, "expired", error=deadline_error())
        elif verdict == "cancelled":
            self._end(entry, job_id, "cancelled", error=cancelled_error())
        else:
            self._end(entry, job_id, "", owner=False)  # already terminal: just ack
        return None

    def _registered_robot(self, job_id: str, fields: dict[bytes, bytes]) -> bytes | None:
        """The registration (msgpack bytes, as stored) of the user robot the job names; None for a built-in."""
        name = fields.get(b"h") or self.r.hget(self.keys.job(job_id), "robot")  # entries of older services lack h
        if not name or name.decode() in self.builtin_robots:
            return None
        owner = fields[b"o"].decode() if fields.get(b"o") else None
        raw: bytes | None = self.r.hget(self.keys.robot_urdf, scoped_robot(owner, name.decode()))
        return raw

    def _end(
        self, entry: str, job_id: str, state: str, *, result: bytes = b"", error: ErrorBody | None = None,
        timings: dict[str, float] | None = None, owner: bool = True,
    ) -> None:  # fmt: skip
        s = self.settings
        progress = JobProgress(stage=Stage.DONE, fraction=1.0) if state == "succeeded" else None
        keys = [self.keys.stream, self.keys.job(job_id), self.keys.result(job_id), self.keys.counts, self.keys.done]
        args: list[Any] = [
            GROUP, self.id, entry, state, time.time(), result, error.error if error else "",
            error.type if error else "", pack(timings or {}),
            pack(progress.model_dump(mode="python")) if progress else "",
            int(s.result_ttl * 1000), int(max(s.record_ttl, s.result_ttl) * 1000), job_id, "1" if owner else "0",
            pack([d.model_dump(mode="python") for d in error.detail]) if error and error.detail else "",
        ]  # fmt: skip
        if not self._finish(keys=keys, args=args):
            log.warning("result discarded: the job was re-delivered to another worker")
        elif state:
            log.info("outcome written", extra={"state": state})

    def _progress(self, job_id: str, progress: JobProgress) -> None:
        """A job's (throttled) progress, written to its record; best effort."""
        try:
            self.r.hset(self.keys.job(job_id), "progress", pack(progress.model_dump(mode="python", exclude_none=True)))
        except RedisError as exc:  # progress is best effort; the outcome is what must not be lost
            log.warning("progress not written: %s", exc)

    def _should_cancel(self, job_id: str) -> bool:
        """The job's cancel flag, read at most every `PROGRESS_S` (BEGIN read it when the job started)."""
        now = time.monotonic()
        if now - self.cancel_checked.get(job_id, 0.0) < PROGRESS_S:
            return False
        self.cancel_checked[job_id] = now
        try:
            return bool(self.r.hget(self.keys.job(job_id), "cancel") == b"1")
        except RedisError:
            return False

    def _robot(self, entry: str, fields: dict[bytes, bytes]) -> None:
        """Validate a registration and answer it; one still loading at its deadline (``d``) is answered and this
        process ends there (`manifoundation.server.worker.overrun`; `mani worker` starts another). The heartbeat
        keeps the entry this worker's while it loads."""
        deadline = float(fields[b"d"]) if fields.get(b"d") else None  # entries of older services lack d
        with self.lock:
            self.inflight[entry] = ""
        try:
            answer = self._core.validate_robot(fields[b"p"], deadline, lambda a: self._answer(entry, fields, a))
            self._answer(entry, fields, answer)
        finally:
            with self.lock:
                self.inflight.pop(entry, None)

    def _answer(self, entry: str, fields: dict[bytes, bytes], answer: dict[str, Any]) -> None:
        """Store an accepted robot for every worker, and the answer for the service, in one step."""
        pipe = self.r.pipeline()
        if "robot" in answer:
            key = scoped_robot(fields[b"o"].decode() if fields.get(b"o") else None, answer["robot"]["name"])
            pipe.hset(self.keys.robots, key, pack(answer["robot"]))
            pipe.hset(self.keys.robot_urdf, key, fields[b"p"])
            pipe.hset(self.keys.robot_size, key, answer["robot"].get("stored_bytes") or 0)
        rid = fields[b"id"].decode()
        pipe.set(self.keys.robot_reply(rid), pack(answer), ex=300)
        pipe.xack(self.keys.stream, GROUP, entry)
        pipe.xdel(self.keys.stream, entry)
        pipe.publish(self.keys.done, f"robot:{rid}")
        pipe.execute()


def _unstorable(exc: BaseException) -> ErrorBody:
    """The error of a job whose result Redis refused to store."""
    return ErrorBody(
        error=f"the job ran but its result could not be stored: {public_reason(exc)}; submit it again later",
        type=ErrorType.UNAVAILABLE.value,
    )


def main() -> None:
    """Entry point of one worker process (``python -m manifoundation.server.worker.worker``)."""
    raw = os.environ.get("MANI_WORKER_SETTINGS")
    settings = QueueSettings.model_validate_json(raw) if raw else QueueSettings()
    worker = RedisWorker(settings, os.environ.get("MANI_WORKER_ID"))
    setup_logging(settings.log_level, worker.id)
    signal.signal(signal.SIGTERM, worker.stop)
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the supervisor forwards SIGTERM
    worker.run()


if __name__ == "__main__":
    main()
