"""`mani-lab bench faults`: what holds under faults and hostile load, measured (bounded in count and time, loopback
only).

Ten scenarios, each on its own private processes (a `redis-server` on a free port with AOF in a temporary
directory, `mani worker` / `mani serve` children), all killed at the end:

- soak: N jobs through Redis with 2 workers (batch 4) while workers are killed (kill -9) and Redis is killed and
  restarted: jobs lost (404), duplicated (two successful outcomes accepted by Redis, each readable by a caller),
  ran twice (two successful runs, one outcome kept), stuck (not terminal at the end), failed, and the longest
  redelivery delay (kill → the job's next start).
- poison: a crashing job in every micro-batch of 4: how many jobs were dead-lettered, and whether all were poison.
- large bodies: C concurrent valid bodies of S MB against `mani serve`: /healthz latency meanwhile, API RSS.
- full queue: C concurrent posts (small and large bodies) against a full queue: 429 latency, timed by raw
  sockets to the status line (`research.bench.probes`); large bodies both pushed at once and sent with
  ``Expect: 100-continue`` (as curl does), which a refusal answers before any of the body is sent.
- slow headers: connections sending their request head a byte at a time: how many the server closed, how soon.
- gRPC batches (issue 62, item 3): concurrent `SubmitBatch` of large messages: /healthz latency, API RSS peak,
  after and once the queue drained.
- include bomb (item 1): an MJCF include bomb registered twice beside a normal registration and a synthesis with a
  20 s deadline, on the real loader.
- MCP bodies (item 2): large `upload_object` posts to ``/mcp`` at once, and one over ``MANI_MCP_MAX_BODY_BYTES``.
- embedded SIGSTOP (item 6): the embedded worker running a job stopped: seconds until the job is delivered again.
- MCP streams (item 7): `GET /mcp` streams from one key: how many were answered, how many outlive
  ``MANI_MCP_STREAM_MAX_S``.

Why one module: the scenarios of one benchmark share their process and Redis helpers and one report table.
"""

from __future__ import annotations

import argparse
import asyncio
import contextlib
import json
import os
import random
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path
from typing import Any

from research.bench.rss import rss_mb
from research.bench.service import _free_port, request_body
from research.hostile_archives import include_bomb as bomb_archive

STAGED = "research.staged_pipeline:StagedPipeline"
SCENARIOS = ("soak", "poison", "large_bodies", "full_queue", "slow_headers", "grpc_batches", "include_bomb",
             "mcp_bodies", "embedded_sigstop", "mcp_streams")
EXAMPLE = """examples (the README's figures):
  mani-lab bench faults --jobs 120 --kills 4 --restarts 2 --poison-batches 4 --bodies 100 --body-mb 8
  mani-lab bench faults --only large_bodies,full_queue --bodies 100 --body-mb 50
  mani-lab bench faults --only slow_headers --slow 300 --slow-interval 15 --slow-seconds 50
  mani-lab bench faults --only full_queue --rounds 10 --checkouts ../base,.   # two versions side by side
  mani-lab bench faults --only grpc_batches,include_bomb,mcp_bodies,embedded_sigstop,mcp_streams   # issue 62"""


def register(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add ``faults`` to the ``mani-lab bench`` sub-commands."""
    parser = subparsers.add_parser(
        "faults",
        help="soak with kills and Redis restarts, poison jobs, large bodies, full queue",
        description=(__doc__ or "").splitlines()[0],
        epilog=EXAMPLE,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--jobs", type=int, default=120, help="soak: jobs (120)")
    parser.add_argument("--kills", type=int, default=4, help="soak: workers killed with kill -9 (4)")
    parser.add_argument("--restarts", type=int, default=2, help="soak: Redis kill -9 + restarts (2)")
    parser.add_argument("--poison-batches", type=int, default=4, help="poison: batches of 4 with one crasher (4)")
    parser.add_argument("--bodies", type=int, default=100, help="large bodies / full-queue posts at once (100)")
    parser.add_argument("--body-mb", type=float, default=8.0, help="size of each large body, MB (8; at most 55)")
    parser.add_argument("--slow", type=int, default=100, help="slow headers: connections (100)")
    parser.add_argument("--slow-interval", type=float, default=2.0, help="slow headers: s between bytes (2)")
    parser.add_argument("--slow-seconds", type=float, default=30.0, help="slow headers: s watched (30)")
    parser.add_argument("--rounds", type=int, default=1, help="full queue: bursts of each kind (1); medians reported")
    parser.add_argument("--checkouts", metavar="DIRS",
                        help="full queue: one service per checkout (comma-separated), side by side, bursts alternating")
    parser.add_argument("--fsync", choices=("always", "everysec"), default="always",
                        help="soak: the private Redis's appendfsync (always: no acknowledged write lost on kill -9)")
    parser.add_argument("--grpc-calls", type=int, default=3, help="gRPC: concurrent SubmitBatch calls (3)")
    parser.add_argument("--grpc-requests", type=int, default=6, help="gRPC: requests per batch (6)")
    parser.add_argument("--grpc-points", type=int, default=200_000, help="gRPC: points per request (200000)")
    parser.add_argument("--grpc-stream", action="store_true", help="gRPC: the batches in pieces (SubmitBatchStream)")
    parser.add_argument("--bomb-depth", type=int, default=4, help="include bomb: levels of 60 includes (4)")
    parser.add_argument("--mcp-posts", type=int, default=4, help="MCP: large upload_object posts at once (4)")
    parser.add_argument("--mcp-points", type=int, default=50_000, help="MCP: points per upload (50000: 6.6 MB)")
    parser.add_argument("--mcp-indent", type=int, default=None, help="MCP: pretty-print uploads with this indent")
    parser.add_argument("--streams", type=int, default=40, help="MCP streams: GET /mcp streams opened (40)")
    parser.add_argument("--stream-max-s", type=float, default=3.0, help="MCP streams: MANI_MCP_STREAM_MAX_S (3)")
    parser.add_argument("--only", default=",".join(SCENARIOS), help=f"scenarios to run ({','.join(SCENARIOS)})")
    parser.add_argument("--budget", type=float, default=240.0, help="seconds per scenario at most (240)")
    parser.add_argument("--json", type=Path, help="also write the figures to this JSON file")
    parser.set_defaults(func=run)


class RedisProcess:
    """A private redis-server with AOF on a free port (``fsync``: its appendfsync; docker-compose keeps Redis's
    default, everysec)."""

    def __init__(self, directory: str, fsync: str = "always") -> None:
        binary = shutil.which("redis-server")
        if binary is None:
            raise SystemExit("mani-lab bench faults: redis-server is not installed")
        self.port = _free_port()
        self.url = f"redis://127.0.0.1:{self.port}/0"
        self.cmd = [binary, "--port", str(self.port), "--bind", "127.0.0.1", "--dir", directory, "--save", "",
                    "--appendonly", "yes", "--appendfsync", fsync]  # fmt: skip
        self.proc: subprocess.Popen[bytes] | None = None

    def start(self) -> None:
        import redis

        self.proc = subprocess.Popen(self.cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        end = time.monotonic() + 20
        while True:
            with contextlib.suppress(redis.RedisError):
                if redis.Redis.from_url(self.url, socket_connect_timeout=0.5).ping():
                    return
            if time.monotonic() > end:
                raise RuntimeError("redis-server did not start")
            time.sleep(0.05)

    def kill(self) -> None:
        if self.proc is not None and self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait(10)


def _stop(proc: subprocess.Popen[bytes], grace: float = 30) -> None:
    if proc.poll() is None:
        proc.terminate()
        try:
            proc.wait(grace)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


def _workers(url: str, prefix: str, log: Path, options: dict[str, Any], **env: str) -> subprocess.Popen[bytes]:
    environ = dict(os.environ, MANI_REDIS_URL=url, MANI_QUEUE_PREFIX=prefix, MANI_PIPELINE=STAGED,
                   MANI_PIPELINE_OPTIONS=json.dumps(options), MANI_LOG_LEVEL="INFO", MANI_BATCH_SIZE="4",
                   MANI_HEARTBEAT_INTERVAL="0.5", **env)  # fmt: skip
    cmd = [sys.executable, "-m", "manifoundation.cli.main", "worker", "--concurrency", "2"]
    return subprocess.Popen(cmd, env=environ, stdout=subprocess.DEVNULL, stderr=log.open("wb"))


def _small(seed: int) -> Any:
    from manifoundation.contract import SynthesisRequest

    body = request_body(64, "test_gripper", "direct_grasp", seed)
    body["options"]["max_iterations"] = 2
    return SynthesisRequest.model_validate(body)


async def _all_states(queue: Any, ids: list[str]) -> dict[str, Any]:
    from manifoundation.server.queue import JobNotFound

    out: dict[str, Any] = {}
    for job_id in ids:
        try:
            out[job_id] = await queue.get(job_id, with_result=False)
        except JobNotFound:
            out[job_id] = None
    return out


async def soak(args: argparse.Namespace, directory: str) -> dict[str, Any]:
    """N jobs, random kill -9 of busy workers and kill -9 + restart of Redis; see the module doc."""
    from manifoundation.server.queue import QueueUnavailable, create_queue

    server = RedisProcess(directory, args.fsync)
    server.start()
    log = Path(directory) / "soak-workers.log"
    options = {"stage_seconds": 0.02, "iterations": 2}
    workers = _workers(server.url, "soak:", log, options, MANI_MAX_DELIVERIES="5", MANI_VISIBILITY_TIMEOUT="30")
    queue = create_queue(server.url, queue_prefix="soak:", max_queue=args.jobs + 10)
    await queue.start()
    rng = random.Random(0)
    kills: list[tuple[float, str]] = []
    try:
        while len(await queue.workers()) < 2:
            await asyncio.sleep(0.1)
        ids = await queue.submit([_small(i) for i in range(args.jobs)])
        t0, end = time.monotonic(), time.monotonic() + args.budget
        events = ["kill"] * args.kills + ["restart"] * args.restarts
        rng.shuffle(events)
        pending, states = set(ids), {}
        while time.monotonic() < end and pending:
            await asyncio.sleep(rng.uniform(0.5, 1.5))
            with contextlib.suppress(QueueUnavailable):
                if events and events[0] == "restart":
                    events.pop(0)
                    server.kill()
                    await asyncio.sleep(2.0)
                    server.start()
                elif events:
                    busy = [w for w in await queue.workers() if w.current_job]
                    if busy:
                        victim = rng.choice(busy)
                        with contextlib.suppress(ProcessLookupError):
                            os.kill(victim.pid, signal.SIGKILL)
                            kills.append((time.time(), victim.current_job or ""))
                            events.pop(0)
                states = await _all_states(queue, sorted(pending))
                pending = {i for i, j in states.items() if j is not None and not j.state.terminal}
        elapsed = time.monotonic() - t0
        final = await _all_states(queue, ids)
    finally:
        await queue.close()
        _stop(workers)
        server.kill()
    finished: Counter[str] = Counter()  # runs that ended in success
    written: Counter[str] = Counter()  # successful outcomes Redis accepted (a caller could have read each)
    for line in log.read_text().splitlines():
        if line.startswith("{"):
            entry = json.loads(line)
            if entry.get("state") == "succeeded":
                if entry.get("msg") == "job finished":
                    finished[entry["job_id"]] += 1
                elif entry.get("msg") == "outcome written":
                    written[entry["job_id"]] += 1
    delays = [final[j].started_at - t for t, j in kills if final.get(j) and (final[j].started_at or 0) > t]
    return {
        "jobs": args.jobs, "kills": len(kills), "restarts": args.restarts, "seconds": round(elapsed, 1),
        "lost": sum(j is None for j in final.values()),
        "stuck": sum(j is not None and not j.state.terminal for j in final.values()),
        "failed": sum(j is not None and j.state.value == "failed" for j in final.values()),
        "fsync": args.fsync, "duplicated": sum(n > 1 for n in written.values()),
        "ran_twice": sum(n > 1 for n in finished.values()),
        "max_redelivery_s": round(max(delays), 2) if delays else None,
    }  # fmt: skip


async def poison(args: argparse.Namespace, directory: str) -> dict[str, Any]:
    """A crashing job (seed 666) first in every batch of 4, queued before the workers start."""
    from manifoundation.server.queue import create_queue

    server = RedisProcess(directory)
    server.start()
    queue = create_queue(server.url, queue_prefix="poison:")
    await queue.start()
    seeds = [666 if i % 4 == 0 else i for i in range(4 * args.poison_batches)]
    ids = await queue.submit([_small(s) for s in seeds])
    t0 = time.monotonic()
    workers = _workers(server.url, "poison:", Path(directory) / "poison-workers.log", {"crash_seed": 666})
    try:
        jobs = await asyncio.gather(*(queue.wait(i, args.budget) for i in ids))
        dead = {d.job_id for d in await queue.dead_letters(limit=1000)}
    finally:
        await queue.close()
        _stop(workers)
        server.kill()
    poisoned = {i for i, s in zip(ids, seeds, strict=True) if s == 666}
    return {
        "jobs": len(ids), "poison": len(poisoned), "dead_lettered": len(dead), "only_poison": dead == poisoned,
        "innocent_succeeded": sum(j.state.value == "succeeded" for j in jobs if j.id not in poisoned),
        "seconds": round(time.monotonic() - t0, 1),
    }  # fmt: skip


def _serve(
    max_queue: int, stage_seconds: float, checkout: str | None = None, grpc_port: int = 0, **env: str
) -> tuple[subprocess.Popen[bytes], str]:
    """`mani serve` on the staged pipeline; ``checkout``: run that directory's code (PYTHONPATH and working
    directory: ``python -m`` puts the latter first on sys.path); ``grpc_port``: gRPC on it (0: HTTP only)."""
    import httpx

    port = _free_port()
    environ = dict(os.environ, MANI_PIPELINE=STAGED, MANI_PIPELINE_OPTIONS=json.dumps({"stage_seconds": stage_seconds}),
                   MANI_MAX_QUEUE=str(max_queue), MANI_RATE_LIMIT_PER_S="0", MANI_LOG_LEVEL="WARNING",
                   MANI_CONCURRENCY="1", MANI_BODY_TIMEOUT="120")  # fmt: skip
    environ.update(env)
    environ.pop("MANI_REDIS_URL", None)
    if checkout:
        environ["PYTHONPATH"] = checkout
    cmd = [sys.executable, "-m", "manifoundation.cli.main", "serve", "--port", str(port)]
    cmd += ["--grpc-port", str(grpc_port)] if grpc_port else ["--no-grpc"]
    proc = subprocess.Popen(cmd, env=environ, cwd=checkout, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    base = f"http://127.0.0.1:{port}"
    end = time.monotonic() + 120
    while time.monotonic() < end:
        with contextlib.suppress(httpx.HTTPError):
            if httpx.get(f"{base}/readyz", timeout=2).status_code == 200:
                return proc, base
        time.sleep(0.2)
    _stop(proc)
    raise RuntimeError("mani serve did not become ready")


# bytes per point of each body layout: rounded points + normals; full-precision points, normals and a per-point
# motion task; the same pretty-printed (indent 1), as some clients send it. The smallest that reaches the size.
_LAYOUTS = ((60.0, False, None), (203.0, True, None), (263.0, True, 1))


def _large_body(mb: float) -> bytes:
    """A valid request of about ``mb`` MB (at most 200 000 points: ≈ 12 MB compact, 41 MB full precision with a
    point-motion task, 53 MB of that pretty-printed)."""
    import numpy as np

    per_point, full, indent = next((layout for layout in _LAYOUTS if mb * 1e6 / layout[0] <= 200_000), _LAYOUTS[-1])
    n = min(200_000, max(64, int(mb * 1e6 / per_point)))
    rng = np.random.default_rng(0)
    p = rng.normal(size=(n, 3))
    p /= np.linalg.norm(p, axis=1, keepdims=True)
    body = request_body(64, "test_gripper", "direct_grasp")
    if full:
        body["object"] = {"points": (0.04 * p).tolist(), "normals": p.tolist()}
        body["task"] = {"kind": "point_motion", "motion": (0.01 * rng.normal(size=(n, 3))).tolist()}
    else:
        body["object"] = {"points": (0.04 * p).round(6).tolist(), "normals": p.round(6).tolist()}
    return json.dumps(body, indent=indent).encode()


def _pct(values: list[float], q: float) -> float | None:
    from manifoundation.server.api.dashboard import percentile

    found = percentile(values, q)
    return None if found is None else round(found * 1000, 1)


async def _posts(base: str, bodies: list[bytes], timeout: float) -> list[tuple[int, float]]:
    import httpx

    async with httpx.AsyncClient(base_url=base, timeout=timeout, limits=httpx.Limits(max_connections=1000)) as http:

        async def one(data: bytes) -> tuple[int, float]:
            t0 = time.perf_counter()
            try:
                answer = await http.post("/v1/jobs", content=data, headers={"Content-Type": "application/json"})
                return answer.status_code, time.perf_counter() - t0
            except httpx.HTTPError:
                return 0, time.perf_counter() - t0

        return await asyncio.gather(*(one(b) for b in bodies))


async def large_bodies(args: argparse.Namespace) -> dict[str, Any]:
    """``--bodies`` concurrent bodies of ``--body-mb`` MB; /healthz polled every 20 ms meanwhile by a process of
    its own (this one is busy uploading), API RSS sampled every 20 ms."""
    import httpx

    from research.bench.probes import health_probe

    data = _large_body(args.body_mb)
    proc, base = _serve(max_queue=10 * args.bodies, stage_seconds=0.0)
    try:
        with health_probe(f"{base}/healthz") as health:
            posting = asyncio.ensure_future(_posts(base, [data] * args.bodies, args.budget))
            peak = 0.0
            while not posting.done():
                peak = max(peak, rss_mb(proc.pid).get("VmRSS", 0.0))
                await asyncio.sleep(0.02)
            answers = posting.result()
        after = rss_mb(proc.pid)
        async with httpx.AsyncClient(base_url=base, timeout=60) as http:
            queued = (await http.get("/dashboard/data")).json()["stats"]["depth"]
            end = time.monotonic() + args.budget
            while (await http.get("/dashboard/data")).json()["stats"]["depth"] and time.monotonic() < end:
                await asyncio.sleep(0.5)
            await asyncio.sleep(1.0)
            drained = rss_mb(proc.pid)
    finally:
        _stop(proc)
    return {
        "bodies": args.bodies, "body_mb": round(len(data) / 1e6, 1), "answers": dict(Counter(s for s, _ in answers)),
        "healthz_p50_ms": _pct(health, 0.5), "healthz_p99_ms": _pct(health, 0.99),
        "healthz_max_ms": _pct(health, 1.0), "api_rss_peak_mb": round(max(peak, after.get("VmHWM", 0.0)), 0),
        "api_rss_after_mb": round(after.get("VmRSS", 0.0), 0), "queued_after": queued,
        "api_rss_drained_mb": round(drained.get("VmRSS", 0.0), 0),
        "seconds": round(max((t for _, t in answers), default=0.0), 1),
    }  # fmt: skip


def _grpc_batch(requests: int, points: int) -> bytes:
    """A serialized `BatchCreate` of ``requests`` requests of ``points`` points, points and normals as float64
    (200 000 points: 9.6 MB a request)."""
    import numpy as np

    from manifoundation.contract import BatchCreate
    from manifoundation.contract.protos.convert import to_proto
    from manifoundation.contract.protos.v1 import manifoundation_pb2 as pb

    body = request_body(64, "test_gripper", "direct_grasp")
    p = np.random.default_rng(0).normal(size=(points, 3))
    p /= np.linalg.norm(p, axis=1, keepdims=True)
    body["object"] = {"points": 0.04 * p, "normals": p}
    body["options"]["max_iterations"] = 2
    batch = BatchCreate.model_validate({"requests": [body] * requests})
    return bytes(to_proto(batch, pb.BatchCreate).SerializeToString())


async def grpc_batches(args: argparse.Namespace) -> dict[str, Any]:
    """``--grpc-calls`` concurrent `SubmitBatch` of ``--grpc-requests`` requests of ``--grpc-points`` points
    (issue 62, item 3: 3 × 6 × 200 000 points, 57.6 MB a call), or with ``--grpc-stream`` the same batches sent
    in 1 MiB pieces (`SubmitBatchStream`); /healthz polled every 20 ms by a process of its own, API RSS sampled
    every 20 ms, and read again once the queue drained."""
    import grpc
    import httpx

    from manifoundation.contract.protos.v1 import manifoundation_pb2 as pb
    from manifoundation.sdk._grpc_core import message_pieces
    from research.bench.probes import health_probe

    data = _grpc_batch(args.grpc_requests, args.grpc_points)
    pieces = message_pieces(data) if args.grpc_stream else []  # made once, sent by every call
    port = _free_port()
    proc, base = _serve(max_queue=10 * args.grpc_calls * args.grpc_requests, stage_seconds=0.0, grpc_port=port)
    options = [("grpc.max_send_message_length", -1), ("grpc.max_receive_message_length", -1)]
    method = "/manifoundation.v1.ManiFoundation/SubmitBatch" + ("Stream" if args.grpc_stream else "")
    try:
        before = rss_mb(proc.pid).get("VmRSS", 0.0)
        async with grpc.aio.insecure_channel(f"127.0.0.1:{port}", options=options) as channel:
            if args.grpc_stream:
                call: Any = channel.stream_unary(method, request_serializer=pb.MessagePiece.SerializeToString,
                                                 response_deserializer=None)  # fmt: skip
            else:
                call = channel.unary_unary(method, request_serializer=None, response_deserializer=None)

            async def one() -> tuple[str, float]:
                t0 = time.perf_counter()
                try:
                    await call(iter(pieces) if args.grpc_stream else data, timeout=args.budget)
                    return "OK", time.perf_counter() - t0
                except grpc.aio.AioRpcError as exc:
                    return exc.code().name, time.perf_counter() - t0

            with health_probe(f"{base}/healthz") as health:
                calls = [asyncio.ensure_future(one()) for _ in range(args.grpc_calls)]
                posting = asyncio.gather(*calls)
                peak = 0.0
                while not posting.done():
                    peak = max(peak, rss_mb(proc.pid).get("VmRSS", 0.0))
                    await asyncio.sleep(0.02)
                answers = posting.result()
        after = rss_mb(proc.pid)
        async with httpx.AsyncClient(base_url=base, timeout=60) as http:
            end = time.monotonic() + args.budget
            while time.monotonic() < end:
                stats = (await http.get("/dashboard/data")).json()["stats"]
                if not stats["depth"] and not stats["running"]:
                    break
                await asyncio.sleep(0.5)
            await asyncio.sleep(3.0)  # the queue trims the heap at most every 2 s
            drained = rss_mb(proc.pid)
    finally:
        _stop(proc)
    return {
        "calls": args.grpc_calls, "requests": args.grpc_requests, "points": args.grpc_points,
        "rpc": method.rsplit("/", 1)[1],
        "call_mb": round(len(data) / 1e6, 1), "answers": dict(Counter(s for s, _ in answers)),
        "healthz_p50_ms": _pct(health, 0.5), "healthz_p99_ms": _pct(health, 0.99),
        "healthz_max_ms": _pct(health, 1.0), "api_rss_before_mb": round(before, 0),
        "api_rss_peak_mb": round(max(peak, after.get("VmHWM", 0.0)), 0),
        "api_rss_after_mb": round(after.get("VmRSS", 0.0), 0),
        "api_rss_drained_mb": round(drained.get("VmRSS", 0.0), 0),
        "seconds": round(max((t for _, t in answers), default=0.0), 1),
    }  # fmt: skip


async def include_bomb(args: argparse.Namespace) -> dict[str, Any]:
    """Issue 62, item 1: an include bomb of ``--bomb-depth`` levels registered twice at once beside a normal
    registration (the same archive without includes), on the real loader (`ModelsPipeline`, one worker, hand
    barrett): each bomb's status and seconds, the worker's peak RSS meanwhile, the normal one's status and
    seconds, and those of a synthesis (20 s deadline, `/v1/synthesize`) sent beside them."""
    import base64

    import httpx

    from research.bench.rss import worker_pids

    archive = base64.b64encode(bomb_archive(args.bomb_depth)).decode()
    plain = base64.b64encode(bomb_archive(0)).decode()
    proc, base = _serve(max_queue=20, stage_seconds=0.0, MANI_ROBOT_REGISTER_TIMEOUT="120",
                        MANI_PIPELINE="manifoundation.server.worker.models_pipeline:ModelsPipeline",
                        MANI_PIPELINE_OPTIONS=json.dumps({"hands": ["barrett"]}))  # fmt: skip
    try:
        workers = worker_pids(proc.pid)
        async with httpx.AsyncClient(base_url=base, timeout=args.budget) as http:

            async def register(name: str) -> tuple[int, str, float]:
                t0 = time.perf_counter()
                answer = await http.post("/v1/robots", json={"name": name, "archive": archive})
                return answer.status_code, str(answer.json().get("error", ""))[:80], time.perf_counter() - t0

            async def normal() -> tuple[int, float]:
                t0 = time.perf_counter()
                answer = await http.post("/v1/robots", json={"name": "plain", "archive": plain, "fingertips": ["tip"]})
                return answer.status_code, time.perf_counter() - t0

            async def job() -> tuple[int, float]:  # a synthesis with a 20 s deadline, sent just after the bombs
                body = request_body(256, "barrett", "direct_grasp")
                body["options"].update(timeout=20, max_iterations=20)
                await asyncio.sleep(0.05)
                t0 = time.perf_counter()
                answer = await http.post("/v1/synthesize", json=body)
                return answer.status_code, time.perf_counter() - t0

            before = sum(rss_mb(pid).get("VmRSS", 0.0) for pid in workers)
            work = asyncio.ensure_future(asyncio.gather(register("bomb1"), register("bomb2"), normal(), job()))
            peak = 0.0
            while not work.done():
                peak = max(peak, sum(rss_mb(pid).get("VmRSS", 0.0) for pid in workers))
                await asyncio.sleep(0.02)
            first, second, (normal_status, normal_s), (job_status, job_s) = work.result()
    finally:
        _stop(proc)
    return {
        "depth": args.bomb_depth, "archive_bytes": len(base64.b64decode(archive)),
        "statuses": [first[0], second[0]], "error": first[1], "seconds": [round(first[2], 2), round(second[2], 2)],
        "worker_rss_before_mb": round(before, 0), "worker_rss_peak_mb": round(peak, 0),
        "normal": normal_status, "normal_s": round(normal_s, 2), "job_deadline_20s": job_status,
        "job_s": round(job_s, 2),
    }  # fmt: skip


async def mcp_bodies(args: argparse.Namespace) -> dict[str, Any]:
    """Issue 62, item 2: ``--mcp-posts`` `upload_object` calls of ``--mcp-points`` points posted to ``/mcp`` at once
    (JSON, decoded in the service's body processes) and one over ``MANI_MCP_MAX_BODY_BYTES`` (refused before it is
    read): /healthz latency meanwhile, API RSS peak and after; ``stored_mb``, the arrays of the objects the
    service kept (at most ``MANI_MAX_OBJECTS`` per key: the other uploads are refused by the tool, ``tool_errors``)."""
    import httpx
    import numpy as np

    from manifoundation.server.api.settings import Settings
    from research.bench.probes import health_probe

    p = np.random.default_rng(0).normal(size=(args.mcp_points, 3))
    p /= np.linalg.norm(p, axis=1, keepdims=True)
    call = {"jsonrpc": "2.0", "id": 1, "method": "tools/call",
            "params": {"name": "upload_object", "arguments": {"points": (0.04 * p).tolist(), "normals": p.tolist()}}}
    data = json.dumps(call, indent=args.mcp_indent).encode()
    huge = data + b" " * max(0, Settings().mcp_max_body_bytes + 1 - len(data))  # over the limit, whitespace-padded
    headers = {"Content-Type": "application/json", "Accept": "application/json, text/event-stream"}
    proc, base = _serve(max_queue=10, stage_seconds=0.0)
    try:
        async with httpx.AsyncClient(base_url=base, timeout=args.budget, headers=headers) as http:
            await http.post("/mcp", json={"jsonrpc": "2.0", "id": 0, "method": "tools/list"})  # the SDK loaded
            before = rss_mb(proc.pid).get("VmRSS", 0.0)

            kept: list[int] = []
            tool_errors: list[str] = []

            async def post(body: bytes) -> int:
                try:
                    answer = await http.post("/mcp", content=body)
                except httpx.HTTPError:
                    return 0
                result = answer.json().get("result", {}) if answer.status_code == 200 else {}
                if result.get("isError"):
                    tool_errors.append(result["content"][0]["text"])
                elif "structuredContent" in result:
                    kept.append(int(result["structuredContent"]["bytes"]))
                return answer.status_code

            with health_probe(f"{base}/healthz") as health:
                t0 = time.perf_counter()
                posting = asyncio.gather(*[asyncio.ensure_future(post(data)) for _ in range(args.mcp_posts)])
                peak = 0.0
                while not posting.done():
                    peak = max(peak, rss_mb(proc.pid).get("VmRSS", 0.0))
                    await asyncio.sleep(0.02)
                seconds = time.perf_counter() - t0
                statuses = posting.result()
            refused = await post(huge)
        await asyncio.sleep(1.0)
        after = rss_mb(proc.pid)
    finally:
        _stop(proc)
    return {
        "posts": args.mcp_posts, "post_mb": round(len(data) / 1e6, 1), "answers": dict(Counter(statuses)),
        "stored": len(kept), "stored_mb": round(sum(kept) / 1e6, 1), "tool_errors": len(tool_errors),
        "huge_mb": round(len(huge) / 1e6, 1), "huge_answer": refused,
        "healthz_p50_ms": _pct(health, 0.5), "healthz_p99_ms": _pct(health, 0.99), "healthz_max_ms": _pct(health, 1.0),
        "api_rss_before_mb": round(before, 0), "api_rss_peak_mb": round(max(peak, after.get("VmHWM", 0.0)), 0),
        "api_rss_after_mb": round(after.get("VmRSS", 0.0), 0), "seconds": round(seconds, 1),
    }  # fmt: skip


async def embedded_sigstop(args: argparse.Namespace) -> dict[str, Any]:
    """Issue 62, item 6: the embedded worker running a job is stopped (SIGSTOP): seconds until its job is
    delivered again (to a replacement; heartbeat every 0.5 s, timeout 1.5 s), the job's end, and the stopped
    process's fate (killed by the queue, or left, then killed here)."""
    import httpx

    from research.bench.rss import worker_pids

    proc, base = _serve(max_queue=10, stage_seconds=0.1, MANI_HEARTBEAT_INTERVAL="0.5")
    stopped = None
    try:
        async with httpx.AsyncClient(base_url=base, timeout=30) as http:
            body = request_body(256, "test_gripper", "direct_grasp")
            body["options"].update(max_iterations=10, timeout=60)
            job_id = (await http.post("/v1/jobs", json=body)).json()["id"]
            end = time.monotonic() + args.budget
            while (await http.get(f"/v1/jobs/{job_id}")).json()["state"] != "running" and time.monotonic() < end:
                await asyncio.sleep(0.05)
            stopped = worker_pids(proc.pid)[0]
            os.kill(stopped, signal.SIGSTOP)
            t0 = time.monotonic()
            redelivered = None
            job: dict[str, Any] = {}
            while time.monotonic() - t0 < min(args.budget, 60):
                job = (await http.get(f"/v1/jobs/{job_id}")).json()
                if redelivered is None and job.get("deliveries", 1) >= 2:
                    redelivered = time.monotonic() - t0
                if job["state"] in ("succeeded", "failed", "cancelled", "expired"):
                    break
                await asyncio.sleep(0.05)
            ended = time.monotonic() - t0
            killed = _gone(stopped)
    finally:
        if stopped is not None:
            with contextlib.suppress(ProcessLookupError, FileNotFoundError):
                os.kill(stopped, signal.SIGKILL)
        _stop(proc)
    return {
        "redelivered_after_s": None if redelivered is None else round(redelivered, 1), "state": job.get("state"),
        "deliveries": job.get("deliveries"), "ended_after_s": round(ended, 1), "stopped_worker_killed": killed,
    }  # fmt: skip


def _gone(pid: int) -> bool:
    """Whether process ``pid`` has exited (gone, or a zombie until its parent reaps it)."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] == "Z"
    except (OSError, IndexError):
        return True


async def mcp_streams(args: argparse.Namespace) -> dict[str, Any]:
    """Issue 62, item 7: ``--streams`` `GET /mcp` event streams from one key (``MANI_MCP_MAX_STREAMS`` 8): how many
    were answered 200 and 429, the most open at once, and how many are still open ``--stream-max-s`` + 2 s later."""
    import httpx

    key = "bench-faults-key-1"
    proc, base = _serve(max_queue=10, stage_seconds=0.0, MANI_API_KEYS=key,
                        MANI_MCP_STREAM_MAX_S=str(args.stream_max_s))  # fmt: skip
    headers = {"Accept": "text/event-stream", "Authorization": f"Bearer {key}"}
    codes: list[int] = []
    open_streams = peak = 0
    try:
        limits = httpx.Limits(max_connections=None)
        async with httpx.AsyncClient(base_url=base, timeout=args.budget, limits=limits) as http:

            async def hold() -> None:
                nonlocal open_streams, peak
                try:
                    async with http.stream("GET", "/mcp", headers=headers) as answer:
                        codes.append(answer.status_code)
                        open_streams += answer.status_code == 200
                        peak = max(peak, open_streams)
                        try:
                            async for _ in answer.aiter_bytes():
                                pass
                        finally:
                            open_streams -= answer.status_code == 200
                except httpx.HTTPError:
                    codes.append(0)

            tasks = [asyncio.ensure_future(hold()) for _ in range(args.streams)]
            await asyncio.sleep(1.0)
            open_at_1s = open_streams
            await asyncio.sleep(args.stream_max_s + 1.0)
            still_open = open_streams
            for task in tasks:
                task.cancel()
            await asyncio.gather(*tasks, return_exceptions=True)
    finally:
        _stop(proc)
    return {
        "streams": args.streams, "answers": dict(Counter(codes)), "open_peak": peak, "open_after_1s": open_at_1s,
        "stream_max_s": args.stream_max_s, f"open_after_{args.stream_max_s + 2:g}s": still_open,
    }  # fmt: skip


async def full_queue(args: argparse.Namespace) -> dict[str, Any]:
    """The queue full (10 slow jobs), then ``--bodies`` posts at once of a small body, of a large one pushed at
    once, and of a large one sent with ``Expect: 100-continue``: 429 latency to the status line, the median over
    ``--rounds`` bursts of each burst's p50 and p99; with ``--checkouts``, one service per checkout, side by side,
    their bursts alternating."""
    import statistics

    import httpx

    from research.bench.probes import raw_posts

    checkouts = args.checkouts.split(",") if args.checkouts else [None]
    small = json.dumps(request_body(256, "test_gripper", "direct_grasp")).encode()
    large = _large_body(args.body_mb)
    servers = []
    json_type = {"Content-Type": "application/json"}
    try:
        for checkout in checkouts:
            servers.append(_serve(max_queue=10, stage_seconds=30.0, checkout=checkout))
            with httpx.Client(base_url=servers[-1][1], timeout=30, headers=json_type) as http:
                while http.post("/v1/jobs", content=small).status_code == 202:
                    pass
        figures: dict[str, dict[str, Any]] = {}
        kinds = (("small", small, False), ("large", large, False), ("large_expect", large, True))
        for name, data, expect in kinds:
            bursts: dict[str, list[tuple[int, float | None, float | None]]] = {str(c): [] for c in checkouts}
            for _ in range(args.rounds):
                for checkout, (_, base) in zip(checkouts, servers, strict=True):
                    host, port = base.split("//")[1].rsplit(":", 1)
                    answers = await raw_posts(host, int(port), "/v1/jobs", data, args.bodies, args.budget,
                                              expect=expect)  # fmt: skip
                    refused = [t for s, t in answers if s == 429]
                    bursts[str(checkout)].append((len(refused), _pct(refused, 0.5), _pct(refused, 0.99)))
            for checkout, runs in bursts.items():
                out = figures.setdefault(checkout, {"max_queue": 10, "posts": args.bodies, "rounds": args.rounds,
                                                    "large_mb": round(len(large) / 1e6, 1)})  # fmt: skip
                out[f"{name}_429"] = min(n for n, _, _ in runs)
                for q, values in (("p50", [r[1] for r in runs]), ("p99", [r[2] for r in runs])):
                    known = [v for v in values if v is not None]
                    out[f"{name}_{q}_ms"] = round(statistics.median(known), 1) if known else None
    finally:
        for proc, _ in servers:
            _stop(proc)
    return figures["None"] if checkouts == [None] else figures


async def slow_headers(args: argparse.Namespace) -> dict[str, Any]:
    """``--slow`` connections sending their head a byte every ``--slow-interval`` s for ``--slow-seconds``: how
    many were closed and when; /healthz on a fresh connection meanwhile."""
    import httpx

    from research.bench.probes import slow_headers as probe

    proc, base = _serve(max_queue=10, stage_seconds=0.0)
    host, port = base.split("//")[1].rsplit(":", 1)
    try:
        watching = asyncio.ensure_future(probe(host, int(port), args.slow, args.slow_interval, args.slow_seconds))
        health: list[float] = []
        async with httpx.AsyncClient(base_url=base, timeout=10) as http:
            while not watching.done():
                t0 = time.perf_counter()
                if (await http.get("/healthz")).status_code == 200:
                    health.append(time.perf_counter() - t0)
                await asyncio.sleep(0.25)
        closed, after = watching.result()
    finally:
        _stop(proc)
    return {
        "connections": args.slow, "byte_every_s": args.slow_interval, "watched_s": args.slow_seconds,
        "closed": closed, "closed_after_max_s": round(max(after), 1) if after else None,
        "healthz_ok": len(health), "healthz_p99_ms": _pct(health, 0.99),
    }  # fmt: skip


def run(args: argparse.Namespace) -> int:
    """Run the scenarios (``--only``) and print a table of what held."""
    figures: dict[str, Any] = {}
    chosen = [name for name in SCENARIOS if name in args.only.split(",")]
    with tempfile.TemporaryDirectory(prefix="mani-bench-faults-") as directory:
        scenarios = {
            "soak": lambda: soak(args, tempfile.mkdtemp(dir=directory)),
            "poison": lambda: poison(args, tempfile.mkdtemp(dir=directory)),
            "large_bodies": lambda: large_bodies(args),
            "full_queue": lambda: full_queue(args),
            "slow_headers": lambda: slow_headers(args),
            "grpc_batches": lambda: grpc_batches(args),
            "include_bomb": lambda: include_bomb(args),
            "mcp_bodies": lambda: mcp_bodies(args),
            "embedded_sigstop": lambda: embedded_sigstop(args),
            "mcp_streams": lambda: mcp_streams(args),
        }
        for name in chosen:
            figures[name] = asyncio.run(scenarios[name]())
            print(f"{name}: {figures[name]}", flush=True)
    print()
    print("| scenario | figures |")
    print("|---|---|")
    for name, values in figures.items():
        print(f"| {name} | " + ", ".join(f"{k} {v}" for k, v in values.items()) + " |")
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(json.dumps(figures, indent=2))
    return 0
