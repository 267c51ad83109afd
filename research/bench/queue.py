"""`mani-lab bench queue`: queue overhead, pipeline throughput with 1 and 2 workers, network batching gain.

- Overhead: one job at a time through each backend with a zero-work pipeline (`StagedPipeline`,
  ``stage_seconds=0``), one worker; "round trip" = submit → result visible to the client, "overhead" = round trip
  minus the worker's own run time. Embedded, and Redis on ``--redis`` (loopback) with a `mani worker`.
- Throughput: ``--pipeline-jobs`` requests submitted at once to the embedded backend with 1 and 2 worker
  processes running ``--pipeline`` (default: the models pipeline, Panda gripper, 256-point sphere, two given
  contacts, force closure: initialisation → SOCP refinement (≤ 50 iterations) → verification); jobs/s.
- Batching gain: the network stage (``ContactPredictor``, random weights: timing only) on B objects as one
  batch vs one by one, one thread (as a worker process on a 2-core machine runs it).
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import subprocess
import sys
import time
import uuid
from typing import Any

import numpy as np

STAGED = "research.staged_pipeline:StagedPipeline"
MODELS = "manifoundation.server.worker.models_pipeline:ModelsPipeline"


def register(subparsers: Any) -> None:
    """Add ``queue`` to the sub-parsers of `mani-lab bench`."""
    parser = subparsers.add_parser(
        "queue",
        help="queue overhead, pipeline throughput, batching gain",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--redis", default="redis://127.0.0.1:6379/0", help="Redis URL ('' to skip)")
    parser.add_argument("--jobs", type=int, default=300, help="sequential jobs per backend for the overhead")
    parser.add_argument("--pipeline", default=MODELS, help="pipeline for the throughput figure")
    parser.add_argument("--pipeline-jobs", type=int, default=16, help="jobs for the throughput figure")
    parser.add_argument("--batch", type=int, default=8, help="objects per network batch")
    parser.add_argument("--skip", nargs="*", default=[], choices=["overhead", "throughput", "batching"])
    parser.add_argument("--json", metavar="PATH", help="also write the figures as JSON")
    parser.set_defaults(func=main)


def main(args: argparse.Namespace) -> int:
    figures: dict[str, Any] = {"machine": f"{os.cpu_count()} cores", "python": sys.version.split()[0]}
    if "overhead" not in args.skip:
        figures["overhead"] = {"embedded": asyncio.run(_overhead(None, args.jobs))}
        if args.redis:
            figures["overhead"]["redis"] = asyncio.run(_overhead(args.redis, args.jobs))
    if "throughput" not in args.skip:
        figures["throughput"] = {n: asyncio.run(_throughput(args.pipeline, n, args.pipeline_jobs)) for n in (1, 2)}
    if "batching" not in args.skip:
        figures["batching"] = _batching(args.batch)
    _print(figures)
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(figures, fh, indent=2)
    return 0


def _request(seed: int = 0, hand: str = "test_gripper") -> Any:
    """A 256-point sphere (r = 4 cm), force closure, two given contacts (refined by the SOCP loop)."""
    from manifoundation.contract import SynthesisRequest

    rng = np.random.default_rng(seed)
    points = rng.normal(size=(256, 3))
    normals = points / np.linalg.norm(points, axis=1, keepdims=True)
    axis = normals[0]
    return SynthesisRequest.model_validate(
        {"object": {"points": 0.04 * normals, "normals": normals}, "task": {"kind": "force_closure"},
         "robot": {"name": hand}, "contacts": {"points": 0.04 * np.stack([axis, -axis])},
         "options": {"seed": seed, "method": "contacts", "max_iterations": 50}}
    )  # fmt: skip


async def _overhead(redis_url: str | None, jobs: int) -> dict[str, float]:
    from manifoundation.server.queue import create_queue

    prefix = f"mani-bench:{uuid.uuid4().hex[:8]}:"
    options: dict[str, Any] = {"pipeline": STAGED, "pipeline_options": {"iterations": 0}, "log_level": "WARNING"}
    worker = None
    if redis_url:
        env = dict(os.environ, MANI_REDIS_URL=redis_url, MANI_QUEUE_PREFIX=prefix, MANI_PIPELINE=STAGED,
                   MANI_PIPELINE_OPTIONS='{"iterations": 0}', MANI_LOG_LEVEL="WARNING")  # fmt: skip
        worker = subprocess.Popen([sys.executable, "-m", "manifoundation.server.worker.worker"], env=env)
        queue = create_queue(redis_url, queue_prefix=prefix, **options)
    else:
        queue = create_queue(None, redis_url=None, concurrency=1, **options)
    await queue.start()
    try:
        while not await queue.workers():
            await asyncio.sleep(0.05)
        request = _request()
        trips, overheads = [], []
        for i in range(jobs + 20):
            t0 = time.perf_counter()
            [job_id] = await queue.submit([request])
            job = await queue.wait(job_id, 30)
            trip = time.perf_counter() - t0
            run = job.timings.get("run", 0.0)
            if i >= 20:  # warm-up
                trips.append(trip)
                overheads.append(trip - run)
        return {
            "round_trip_p50_ms": 1e3 * float(np.percentile(trips, 50)),
            "round_trip_p99_ms": 1e3 * float(np.percentile(trips, 99)),
            "overhead_p50_ms": 1e3 * float(np.percentile(overheads, 50)),
            "overhead_p99_ms": 1e3 * float(np.percentile(overheads, 99)),
            "jobs": jobs,
        }
    finally:
        await queue.close()
        if worker is not None:
            worker.terminate()
            worker.wait(30)
            import redis

            client = redis.Redis.from_url(redis_url or "")
            keys = list(client.scan_iter(match=prefix + "*", count=1000))
            if keys:
                client.delete(*keys)


async def _throughput(pipeline: str, workers: int, jobs: int) -> dict[str, Any]:
    from manifoundation.contract import JobState
    from manifoundation.server.queue import create_queue

    hand = "test_gripper" if pipeline == STAGED else "panda_gripper"
    options = {} if pipeline == STAGED else {"hands": [hand]}
    queue = create_queue(None, redis_url=None, concurrency=workers, pipeline=pipeline, pipeline_options=options,
                         log_level="WARNING", start_timeout=300, batch_size=1)  # fmt: skip
    await queue.start()
    try:
        if len(await queue.workers()) < workers:
            return {"error": f"{pipeline}: workers did not start"}
        warm = await queue.submit([_request(99, hand=hand)])
        await queue.wait(warm[0], 300)
        t0 = time.perf_counter()
        ids = await queue.submit([_request(i, hand=hand) for i in range(jobs)])
        done = await asyncio.gather(*(queue.wait(i, 600) for i in ids))
        elapsed = time.perf_counter() - t0
        ok = sum(j.state is JobState.SUCCEEDED for j in done)
        errors = sorted({j.error.error[:120] for j in done if j.error})
        return {"jobs": jobs, "succeeded": ok, "seconds": elapsed, "jobs_per_s": jobs / elapsed, "errors": errors}
    finally:
        await queue.close()


def _batching(size: int, repeats: int = 3) -> dict[str, Any]:
    try:
        import importlib

        import torch

        inference = importlib.import_module("manifoundation.core.network.inference")
        ContactPredictor, NetworkInput = inference.ContactPredictor, inference.NetworkInput
    except ImportError as exc:
        return {"error": f"network unavailable: {exc}"}
    torch.set_num_threads(1)
    predictor = ContactPredictor.untrained()
    rng = np.random.default_rng(0)
    hand = rng.normal(size=(1024, 3))
    hand_normals = hand / np.linalg.norm(hand, axis=1, keepdims=True)

    def obj(i: int) -> Any:
        p = rng.normal(size=(2048, 3))
        n = p / np.linalg.norm(p, axis=1, keepdims=True)
        return NetworkInput(points=0.05 * n, normals=n, motion=np.zeros_like(n), mask=np.ones(len(n), bool),
                            properties={"friction": 0.5}, hand_points=0.05 * hand, hand_normals=hand_normals,
                            hand_key="bench")  # fmt: skip

    batch = [obj(i) for i in range(size)]
    predictor.predict(batch[:2])  # warm-up (and the hand encoding is cached)
    batched = single = float("inf")
    for _ in range(repeats):
        t0 = time.perf_counter()
        predictor.predict(batch)
        batched = min(batched, time.perf_counter() - t0)
        t0 = time.perf_counter()
        for item in batch:
            predictor.predict([item])
        single = min(single, time.perf_counter() - t0)
    return {
        "batch": size,
        "batched_s": batched,
        "one_by_one_s": single,
        "gain": single / batched,
        "threads": 1,
        "config": "cpu",
        "points": 2048,
        "samples": 4,
    }


def _print(figures: dict[str, Any]) -> None:
    print(f"machine: {figures['machine']}, Python {figures['python']}")
    for backend, f in figures.get("overhead", {}).items():
        trip = f"round trip p50 {f['round_trip_p50_ms']:.2f} ms  p99 {f['round_trip_p99_ms']:.2f} ms"
        over = f"queue overhead p50 {f['overhead_p50_ms']:.2f} ms  p99 {f['overhead_p99_ms']:.2f} ms"
        print(f"overhead  {backend:9s} {trip} | {over}  ({f['jobs']} jobs)")
    for n, f in figures.get("throughput", {}).items():
        if "error" in f:
            print(f"throughput {n} worker(s): {f['error']}")
        else:
            print(f"throughput {n} worker(s): {f['jobs_per_s']:.2f} jobs/s ({f['succeeded']}/{f['jobs']} ok in "
                  f"{f['seconds']:.1f} s) {'; '.join(f['errors'])}")  # fmt: skip
    b = figures.get("batching")
    if b and "error" not in b:
        print(f"batching  network B={b['batch']}: batched {b['batched_s']:.3f} s vs one by one "
              f"{b['one_by_one_s']:.3f} s -> gain x{b['gain']:.2f} (1 thread)")  # fmt: skip
    elif b:
        print(f"batching: {b['error']}")
