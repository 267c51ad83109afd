"""Redis Streams backend: scale-out, as durable as the Redis behind it (AOF: see
manifoundation/server/worker/README.md). The service
enqueues; `mani worker` processes anywhere consume.

One stream with one consumer group; a job's record is a hash, its result a separate msgpack key with a TTL (a
finished job whose result key is gone reports "expired"); see `manifoundation.server.queue.redis_lua` for the key layout
and the atomic scripts, `manifoundation.server.worker.worker` for the consumer side (XREADGROUP, XAUTOCLAIM, heartbeats,
dead letters). Waiting uses a pub/sub channel with polling as a fallback, so a lost message only delays, never hangs.
Every call is bounded in time: connect and command timeouts of ``redis_timeout`` seconds, one retry after a
reconnect, and a deadline of ``OP_ROUNDS × redis_timeout`` on each guarded step, so a hung Redis (SIGSTOP, a
black-holed network) answers `QueueUnavailable` (503) in seconds instead of hanging requests.

Why one module: one `JobQueue` implementation; its methods share the key layout and the Lua scripts' calling
conventions.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import re
import time
from collections.abc import AsyncIterator, Sequence
from typing import Any

import redis.asyncio as aioredis
from redis.asyncio.retry import Retry
from redis.backoff import ExponentialBackoff
from redis.exceptions import ConnectionError as RedisConnectionError
from redis.exceptions import OutOfMemoryError, RedisError, ResponseError
from redis.exceptions import TimeoutError as RedisTimeoutError

from manifoundation.contract import (
    DeadLetter,
    ErrorBody,
    ErrorType,
    FieldError,
    JobKind,
    JobProgress,
    JobPublic,
    JobRequest,
    JobState,
    QueueStats,
    RobotPublic,
    RobotRegister,
    Stage,
    SynthesisRequest,
    WorkerPublic,
)
from manifoundation.contract.codec import pack, unpack
from manifoundation.server.queue.base import (
    JobNotFound,
    JobQueue,
    QueueFull,
    QueueUnavailable,
    RobotDeadlineExceeded,
    RobotInvalid,
)
from manifoundation.server.queue.persistence import check_persistence_async
from manifoundation.server.queue.records import (
    NO_ANSWER,
    REGISTRATION_GRACE_S,
    new_id,
    registration_overrun,
    result_expired_error,
    robot_reply,
    scoped_robot,
    with_answer,
)
from manifoundation.server.queue.redis_lua import CANCEL, GROUP, SUBMIT, Keys
from manifoundation.server.queue.robot_quota import RESERVE_ROBOT, RobotLimits, refusal
from manifoundation.server.spool import (
    SpooledRequest,
    job_kind,
    open_payload,
    read_payload,
    remove_payload,
    request_payload,
    robot_of,
)
from manifoundation.server.worker.settings import QueueSettings

log = logging.getLogger("manifoundation.server.queue.redis")
OP_ROUNDS = 2
"""A guarded step (a few pipelined round trips) may take this many ``redis_timeout``s in all."""


async def ensure_group(client: Any, keys: Keys) -> None:
    """Create the stream and its consumer group if missing (from the start, so no queued job is skipped)."""
    with contextlib.suppress(ResponseError):  # BUSYGROUP: exists already
        await client.xgroup_create(keys.stream, GROUP, id="0", mkstream=True)


def _safe_url(url: str) -> str:
    """The URL without its password (for logs)."""
    head, sep, tail = url.rpartition("@")
    return f"{head.split('://')[0]}://***@{tail}" if sep else url


def _s(value: bytes | None) -> str | None:
    return None if value is None else value.decode()


def _f(value: bytes | None) -> float | None:
    return None if value in (None, b"") else float(value)


def job_from_hash(job_id: str, h: dict[bytes, bytes], result: bytes | None, has_result: bool) -> JobPublic:
    """A `JobPublic` from a job's record hash (and its result bytes, when fetched)."""
    state = JobState(h[b"state"].decode())
    detail = [FieldError.model_validate(d) for d in unpack(h[b"error_detail"])] if h.get(b"error_detail") else None
    error = None
    if b"error" in h:
        error = ErrorBody(error=h[b"error"].decode(), type=h[b"error_type"].decode(), detail=detail)
    progress = JobProgress.model_validate(unpack(h[b"progress"])) if h.get(b"progress") else JobProgress()
    if state is JobState.SUCCEEDED and not has_result:
        state, error = JobState.EXPIRED, result_expired_error()
    if state is JobState.SUCCEEDED:
        progress = JobProgress(stage=Stage.DONE, fraction=1.0)
    job = JobPublic(
        id=job_id, kind=JobKind(h.get(b"kind", b"synthesis").decode()), state=state, progress=progress,
        created_at=float(h[b"created_at"]),
        started_at=_f(h.get(b"started_at")), finished_at=_f(h.get(b"finished_at")), deadline=_f(h.get(b"deadline")),
        deliveries=int(h.get(b"deliveries", b"0")), worker=_s(h.get(b"worker")), batch_id=_s(h.get(b"batch_id")),
        timings=unpack(h[b"timings"]) if h.get(b"timings") else {},
        error=error if state is not JobState.SUCCEEDED else None,
    )  # fmt: skip
    return with_answer(job, result or None)


_SCRIPT_DETAIL = re.compile(r"[.,]?\s*script: [0-9a-f]{40}.*$", re.DOTALL)


def public_reason(exc: BaseException) -> str:
    """What a caller may read of a Redis failure: Redis's own words, without the server's internals (a Lua
    script's SHA and source line); an out-of-memory refusal said plainly."""
    text = str(exc)
    if isinstance(exc, OutOfMemoryError) or text.startswith("OOM"):
        return "Redis is out of memory (its maxmemory is reached): nothing can be written until memory is freed"
    return _SCRIPT_DETAIL.sub("", text).strip() or type(exc).__name__


class RedisQueue(JobQueue):
    """Client side of the Redis Streams backend (the service's queue with ``MANI_REDIS_URL``)."""

    backend = "redis"

    def __init__(self, settings: QueueSettings | None = None, **overrides: Any) -> None:
        base = settings or QueueSettings()
        self.settings = base.model_copy(update=overrides) if overrides else base
        if not self.settings.redis_url:
            raise ValueError("redis_url: required by the Redis backend")
        self.keys = Keys(self.settings.queue_prefix)
        self._client: Any = None
        self._listener: asyncio.Task[None] | None = None
        self._waiters: dict[str, list[asyncio.Future[None]]] = {}
        self._closing = False

    # ---- lifecycle -------------------------------------------------------------------------------------------
    async def start(self) -> None:
        assert self.settings.redis_url is not None
        self._closing = False
        limit = self.settings.redis_timeout
        pool = aioredis.BlockingConnectionPool.from_url(
            self.settings.redis_url, max_connections=64, timeout=limit,
            socket_connect_timeout=limit, socket_timeout=limit, health_check_interval=10,
            retry=Retry(ExponentialBackoff(cap=0.5, base=0.05), 1),
            retry_on_error=[RedisConnectionError, RedisTimeoutError],
        )  # fmt: skip
        self._client = aioredis.Redis(connection_pool=pool)
        with contextlib.suppress(RedisError, OSError):
            async with asyncio.timeout(OP_ROUNDS * limit):
                await ensure_group(self._client, self.keys)
                await check_persistence_async(self._client, _safe_url(self.settings.redis_url))
        self._submit = self._client.register_script(SUBMIT)
        self._cancel = self._client.register_script(CANCEL)
        self._reserve_robot = self._client.register_script(RESERVE_ROBOT)
        self._listener = asyncio.create_task(self._listen(), name="mani-redis-queue-listener")

    async def close(self) -> None:
        self._closing = True
        if self._listener is not None:
            self._listener.cancel()  # redis-py may swallow one cancellation inside a read: the flag ends the loop
            await asyncio.wait({self._listener}, timeout=OP_ROUNDS * self.settings.redis_timeout + 1.0)
            self._listener = None
        if self._client is not None:
            await self._client.aclose()
            self._client = None

    async def ping(self) -> bool:
        try:
            async with asyncio.timeout(self.settings.redis_timeout):
                return bool(await self._client.ping())
        except (RedisError, OSError, AttributeError):  # TimeoutError is an OSError
            return False

    async def _listen(self) -> None:
        """Wake waiters when the workers announce finished jobs; reconnects after Redis goes away."""
        while not self._closing:
            pubsub = self._client.pubsub(ignore_subscribe_messages=True)
            try:
                await pubsub.subscribe(self.keys.done)
                while not self._closing:
                    message = await pubsub.get_message(ignore_subscribe_messages=True, timeout=1.0)
                    if message is None:
                        continue
                    for future in self._waiters.pop(message["data"].decode(), []):
                        if not future.done():
                            future.set_result(None)
            except (RedisError, OSError):
                await asyncio.sleep(0.5)
            finally:
                with contextlib.suppress(RedisError, OSError):
                    await pubsub.aclose()

    @contextlib.asynccontextmanager
    async def _guard(self) -> AsyncIterator[None]:
        if self._client is None:
            raise QueueUnavailable("the Redis queue is not started")
        limit = OP_ROUNDS * self.settings.redis_timeout
        try:
            async with asyncio.timeout(limit):
                yield
        except TimeoutError as exc:
            raise QueueUnavailable(f"Redis did not answer within {limit:g} s") from exc
        except (RedisError, OSError) as exc:
            raise QueueUnavailable(f"Redis unavailable: {public_reason(exc)}") from exc

    # ---- submit / observe ------------------------------------------------------------------------------------
    async def submit(
        self, requests: Sequence[JobRequest | SpooledRequest], *, batch_id: str | None = None,
        deadline: float | None = None, request_id: str | None = None, owner: str | None = None,
    ) -> list[str]:  # fmt: skip
        ids = [new_id() for _ in requests]
        args: list[Any] = [self.keys.prefix, self.settings.max_queue, int(self.settings.record_ttl), time.time()]
        args += [len(requests), int(self.settings.result_ttl * 1000), request_id or "", owner or ""]
        for job_id, request in zip(ids, requests, strict=True):
            kind = job_kind(request)
            args += [
                job_id,
                await _payload(request),
                "" if deadline is None else repr(deadline),
                batch_id or "",
                robot_of(request) or "",
                "" if kind is JobKind.SYNTHESIS else kind.value,
            ]
        async with self._guard():
            answer = int(await self._submit(keys=[self.keys.stream, self.keys.recent], args=args))
        if answer < 0:
            depth = -answer - 1
            raise QueueFull(f"queue holds {depth} jobs (max {self.settings.max_queue})", retry_after=1.0)
        for request in requests:  # accepted: spooled payloads are Redis's now
            if isinstance(request, SpooledRequest):
                remove_payload(request.path)
        return ids

    @property
    def capacity(self) -> int | None:
        return self.settings.max_queue

    async def room(self, count: int = 1) -> bool:
        async with self._guard():
            return int(await self._client.xlen(self.keys.stream)) + count <= self.settings.max_queue

    async def get(self, job_id: str, *, with_result: bool = True, owner: str | None = None) -> JobPublic:
        async with self._guard():
            pipe = self._client.pipeline(transaction=False)
            pipe.hgetall(self.keys.job(job_id))
            pipe.get(self.keys.result(job_id)) if with_result else pipe.exists(self.keys.result(job_id))
            h, result = await pipe.execute()
        if not h or (owner is not None and h.get(b"owner", b"").decode() != owner):
            raise JobNotFound(f"no job {job_id}")
        job = job_from_hash(job_id, h, result if with_result else None, bool(result))
        if job.state is JobState.QUEUED and job.deadline is not None and job.deadline <= time.time():
            expired = ErrorType.DEADLINE_EXCEEDED
            await self._end_queued(job_id, JobState.EXPIRED, "job deadline passed before it started", expired)
            return await self.get(job_id, with_result=with_result)
        return job

    async def _end_queued(self, job_id: str, state: JobState, message: str, kind: ErrorType) -> str:
        keys = [self.keys.stream, self.keys.job(job_id), self.keys.counts, self.keys.done]
        args = [GROUP, time.time(), state.value, message, kind, job_id, int(self.settings.record_ttl * 1000)]
        async with self._guard():
            return (await self._cancel(keys=keys, args=args)).decode()

    async def wait(self, job_id: str, timeout: float) -> JobPublic:
        end = time.monotonic() + timeout
        loop = asyncio.get_running_loop()
        while True:
            future: asyncio.Future[None] = loop.create_future()
            self._waiters.setdefault(job_id, []).append(future)
            try:
                job = await self.get(job_id)
                remaining = end - time.monotonic()
                if job.state.terminal or remaining <= 0:
                    return job
                with contextlib.suppress(TimeoutError):
                    await asyncio.wait_for(future, min(remaining, 1.0))
            finally:
                waiters = self._waiters.get(job_id, [])
                if future in waiters:
                    waiters.remove(future)
                if not waiters:
                    self._waiters.pop(job_id, None)

    async def cancel(self, job_id: str, *, owner: str | None = None) -> JobPublic:
        if owner is not None:
            await self.get(job_id, with_result=False, owner=owner)  # JobNotFound for another owner's job
        if await self._end_queued(job_id, JobState.CANCELLED, "job cancelled", ErrorType.CANCELLED) == "missing":
            raise JobNotFound(f"no job {job_id}")
        return await self.get(job_id, with_result=False)

    async def list_recent(self, limit: int = 50, *, owner: str | None = None) -> list[JobPublic]:
        if limit <= 0:
            return []
        async with self._guard():
            ids = [i.decode() for i in await self._client.zrevrange(self.keys.recent_of(owner), 0, limit - 1)]
            pipe = self._client.pipeline(transaction=False)
            for job_id in ids:
                pipe.hgetall(self.keys.job(job_id))
                pipe.exists(self.keys.result(job_id))
            answers = await pipe.execute()
        jobs = []
        for k, job_id in enumerate(ids):
            h, has = answers[2 * k], answers[2 * k + 1]
            if h:
                jobs.append(job_from_hash(job_id, h, None, bool(has)))
        return jobs

    async def create_batch(
        self, requests: Sequence[SynthesisRequest | SpooledRequest], deadline: float | None = None, *,
        request_id: str | None = None, owner: str | None = None,
    ) -> str:  # fmt: skip
        batch_id = new_id()
        ids = await self.submit(requests, batch_id=batch_id, deadline=deadline, request_id=request_id, owner=owner)
        async with self._guard():
            key, ttl = self.keys.batch(batch_id), int(self.settings.record_ttl)
            pipe = self._client.pipeline().rpush(key, *ids).expire(key, ttl)
            if owner:
                pipe.set(self.keys.batch_owner(batch_id), owner, ex=ttl)
            await pipe.execute()
        return batch_id

    async def batch_job_ids(self, batch_id: str, *, owner: str | None = None) -> list[str]:
        async with self._guard():
            pipe = self._client.pipeline(transaction=False)
            pipe.lrange(self.keys.batch(batch_id), 0, -1).get(self.keys.batch_owner(batch_id))
            ids, holder = await pipe.execute()
        if not ids or (owner is not None and (holder or b"").decode() != owner):
            raise JobNotFound(f"no batch {batch_id}")
        return [i.decode() for i in ids]

    async def stats(self) -> QueueStats:
        async with self._guard():
            pipe = self._client.pipeline(transaction=False)
            pipe.xlen(self.keys.stream)
            pipe.xpending(self.keys.stream, GROUP)
            pipe.hgetall(self.keys.counts)
            pipe.xlen(self.keys.dead)
            try:
                length, pending, counts, dead = await pipe.execute()
            except ResponseError:  # no group yet
                length, pending, counts, dead = 0, {"pending": 0}, {}, 0
            workers = await self.workers()
        running = int(pending["pending"])
        totals = {JobState(k.decode()): int(v) for k, v in counts.items()}
        by_state = dict.fromkeys(JobState, 0) | totals
        by_state[JobState.QUEUED], by_state[JobState.RUNNING] = max(0, length - running), running
        return QueueStats(
            depth=by_state[JobState.QUEUED], running=running, by_state=by_state,
            completed_total=totals.get(JobState.SUCCEEDED, 0), failed_total=totals.get(JobState.FAILED, 0),
            dead_letters=int(dead), workers=len(workers),
        )  # fmt: skip

    async def workers(self) -> list[WorkerPublic]:
        now = time.time()
        async with self._guard():
            await self._client.zremrangebyscore(self.keys.workers, "-inf", now - 10 * self.settings.heartbeat_timeout)
            ids = await self._client.zrangebyscore(self.keys.workers, now - self.settings.heartbeat_timeout, "+inf")
            blobs = await self._client.mget([self.keys.worker(i.decode()) for i in ids]) if ids else []
        return [WorkerPublic.model_validate(unpack(b)) for b in blobs if b]

    async def dead_letters(self, limit: int = 50) -> list[DeadLetter]:
        async with self._guard():
            entries = await self._client.xrevrange(self.keys.dead, count=limit)
        return [DeadLetter.model_validate(unpack(fields[b"d"])) for _, fields in entries]

    async def list_robots(self, *, owner: str | None = None) -> list[RobotPublic]:
        async with self._guard():
            blobs = await self._client.hgetall(self.keys.robots)
        robots = []
        for field, blob in blobs.items():
            robot = RobotPublic.model_validate(unpack(blob))
            if robot.builtin or field.decode() == scoped_robot(owner, robot.name):
                robots.append(robot)
        return sorted(robots, key=lambda r: (not r.builtin, r.name))

    async def register_robot(
        self,
        robot: RobotRegister,
        timeout: float = 30.0,
        *,
        owner: str | None = None,
        limits: RobotLimits | None = None,
    ) -> RobotPublic:
        async with self._guard():
            existing = await self._client.hget(self.keys.robots, robot.name)
        if existing and RobotPublic.model_validate(unpack(existing)).builtin:
            raise RobotInvalid(f"name: '{robot.name}' is a built-in hand")
        if not await self.workers():
            raise QueueUnavailable("no worker is running to validate the robot")
        rid = new_id()
        if limits is not None:
            await self._reserve(robot, rid, owner, limits, timeout + REGISTRATION_GRACE_S)
        try:
            return await self._validated(robot, rid, owner, timeout)
        finally:
            if limits is not None:
                async with self._guard():
                    await self._client.hdel(self.keys.robot_reservations(owner), rid)

    async def _reserve(
        self, robot: RobotRegister, rid: str, owner: str | None, limits: RobotLimits, ttl: float
    ) -> None:
        """Check ``owner``'s limits and reserve the registration's slot and bytes in one script (expires after
        ``ttl`` + 5 s if this process dies before it releases it). Raises `RobotLimitReached`."""
        keys = [self.keys.robots, self.keys.robot_size, self.keys.robot_reservations(owner)]
        args = [
            f"{owner}/" if owner else "", robot.name, robot.stored_bytes, rid, int((ttl + 5) * 1000),
            limits.max_robots, limits.max_bytes,
        ]  # fmt: skip
        async with self._guard():
            code, held = await self._reserve_robot(keys=keys, args=args)
        if code:
            raise refusal(int(code), int(held), robot.stored_bytes, limits)

    async def _validated(self, robot: RobotRegister, rid: str, owner: str | None, timeout: float) -> RobotPublic:
        """Send the registration to a worker and wait for its verdict (stored by the worker when accepted); its
        deadline, ``timeout`` from now, travels with it (the worker stops there) and bounds the wait."""
        payload = pack(robot.model_dump(mode="python", exclude_none=True))
        loop, end = asyncio.get_running_loop(), time.monotonic() + timeout + REGISTRATION_GRACE_S
        async with self._guard():
            fields = {"k": "robot", "id": rid, "p": payload, "d": repr(time.time() + timeout)}
            await self._client.xadd(self.keys.stream, fields | ({"o": owner} if owner else {}))
        while True:
            future: asyncio.Future[None] = loop.create_future()
            self._waiters.setdefault(f"robot:{rid}", []).append(future)
            async with self._guard():  # each read bounded; the wait for the worker's verdict is `timeout`
                reply = await self._client.get(self.keys.robot_reply(rid))
            if reply is not None or time.monotonic() >= end:
                self._waiters.pop(f"robot:{rid}", None)
                break
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(future, min(1.0, end - time.monotonic()))
        if reply is None:
            raise RobotDeadlineExceeded(registration_overrun(timeout, NO_ANSWER))
        return robot_reply(unpack(reply), timeout)

    async def delete_robot(self, name: str, *, owner: str | None = None) -> None:
        key = scoped_robot(owner, name)
        async with self._guard():
            blob = await self._client.hget(self.keys.robots, key)
            if blob is None or RobotPublic.model_validate(unpack(blob)).builtin:
                raise JobNotFound(f"no registered robot {name!r}")
            pipe = self._client.pipeline().hdel(self.keys.robots, key).hdel(self.keys.robot_urdf, key)
            await pipe.hdel(self.keys.robot_size, key).execute()


async def _payload(request: JobRequest | SpooledRequest) -> bytes:
    """A job's payload: packed, or read from the spool it was packed into (in a thread)."""
    if isinstance(request, SpooledRequest):
        return await asyncio.to_thread(read_payload, open_payload(request.path))
    return request_payload(request)
