"""`mani-lab bench offline`: items/s of `mani offline` on the local pool and on 1 and 2 local Ray nodes, side by side.

The same ``--requests`` request files (panda_gripper on a 64-point sphere, seeds 0..n-1) run through the worker
core with ``--pipeline`` (default `StagedPipeline`, ``--stage-seconds`` a stage: a fixed, known amount of work;
``models``: the real pipeline) on each backend, from a fresh output directory:

- ``in-process``: one worker in this process, no pool (the work itself: the reference for the overhead);
- ``local xW``: the local spawn pool with W processes;
- ``ray N node(s)``: a local `ray.cluster_utils.Cluster` of N nodes with ``--cpus-per-node`` CPUs each (bound to
  127.0.0.1; started before the clock runs), one actor per CPU.

``wall s`` runs from the first item submitted to the last result written (worker start-up and model loading
included), ``first result s`` to the first result written; ``items/s after the first`` leaves the start-up out;
``overhead ms/item`` = wall × workers / items − the in-process seconds per item: the worker time each
item costs beyond its own work (start-up, transfer, scheduling, writing), amortised over the run.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from manifoundation.server.offline.synthesis import SynthesisWorker

STAGED = "research.staged_pipeline:StagedPipeline"
MODELS = "manifoundation.server.worker.models_pipeline:ModelsPipeline"


@dataclass
class Row:
    """One backend's figures."""

    backend: str
    workers: int
    items: int
    seconds: float
    first: float  # seconds to the first result written

    @property
    def rate(self) -> float:
        return self.items / self.seconds

    @property
    def steady(self) -> float:
        """Items/s after the first result (start-up left out)."""
        return (self.items - 1) / max(self.seconds - self.first, 1e-9)


def register(subparsers: Any) -> None:
    """Add ``offline`` to the sub-parsers of `mani-lab bench`."""
    p = subparsers.add_parser("offline", help="mani offline items/s: local pool vs 1 and 2 local Ray nodes",
                              description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)  # fmt: skip
    p.add_argument("--requests", type=int, default=200, help="requests per backend (default 200)")
    p.add_argument("--pipeline", choices=("staged", "models"), default="staged")
    p.add_argument("--stage-seconds", type=float, default=0.005, help="staged: seconds a stage (5 stages an item)")
    p.add_argument("--cpus-per-node", type=int, default=1, help="Ray: CPUs (= actors) a node (default 1)")
    p.add_argument("--batch-size", type=int, default=8, help="requests per micro-batch (default 8)")
    p.set_defaults(func=main)


def main(args: argparse.Namespace) -> int:
    """Run every backend on the same requests and print the table (module doc)."""
    os.environ.setdefault("RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER", "0")  # loopback-only clusters (before ray loads)
    from manifoundation.server.offline.synthesis import SynthesisWorker

    options: dict[str, Any] = {"hands": ["panda_gripper"]}
    if args.pipeline == "staged":
        options = {"stage_seconds": args.stage_seconds}
    worker = SynthesisWorker(STAGED if args.pipeline == "staged" else MODELS, options)
    cpus = args.cpus_per_node
    with tempfile.TemporaryDirectory(prefix="mani-bench-offline-") as scratch:
        requests = Path(scratch) / "requests"
        _write_requests(requests, args.requests)
        rows = [_run("in-process", requests, worker, 1, None, args.batch_size)]
        rows.append(_run(f"local x{2 * cpus}", requests, worker, 2 * cpus, None, args.batch_size))
        for nodes in (1, 2):
            with _cluster(nodes, cpus) as address:
                name = f"ray {nodes} node{'s' if nodes > 1 else ''} x{nodes * cpus}"
                rows.append(_run(name, requests, worker, nodes * cpus, address, args.batch_size))
    _print(rows, args)
    return 0


def _run(name: str, requests: Path, worker: SynthesisWorker, workers: int, address: str | None,
         batch_size: int) -> Row:  # fmt: skip
    from manifoundation.server.offline.batch import run_batch

    with tempfile.TemporaryDirectory(prefix="mani-bench-out-") as out:
        t0 = time.perf_counter()
        first: list[float] = []
        watch = threading.Thread(target=_first_result, args=(Path(out), t0, first), daemon=True)
        watch.start()
        summary = run_batch(requests, Path(out), worker, ray_address=address, workers=workers,
                            batch_size=batch_size, progress=False)  # fmt: skip
        seconds = time.perf_counter() - t0
        watch.join()
    if summary.counts.get("succeeded") != summary.found:
        raise RuntimeError(f"{name}: not every request succeeded: {summary.counts}")
    return Row(name, workers, summary.answered, seconds, first[0] if first else seconds)


def _first_result(out: Path, t0: float, first: list[float]) -> None:
    while not any(out.glob("*.msgpack")) and time.perf_counter() - t0 < 600:
        time.sleep(0.005)
    first.append(time.perf_counter() - t0)


@contextmanager
def _cluster(nodes: int, cpus: int) -> Iterator[str]:
    """A local Ray cluster of ``nodes`` nodes with ``cpus`` CPUs each, this process connected; yields its address."""
    import ray
    from ray.cluster_utils import Cluster

    store = 100 * 1024**2
    head = {"num_cpus": cpus, "object_store_memory": store, "node_ip_address": "127.0.0.1", "include_dashboard": False}
    cluster = Cluster(initialize_head=True, head_node_args=head)
    try:
        for _ in range(nodes - 1):
            cluster.add_node(num_cpus=cpus, object_store_memory=store, node_ip_address="127.0.0.1")
        cluster.wait_for_nodes()
        ray.init(address=cluster.address, log_to_driver=False)
        yield str(cluster.address)
    finally:
        ray.shutdown()
        cluster.shutdown()


def _write_requests(directory: Path, count: int) -> None:
    from manifoundation.contract import SynthesisRequest

    directory.mkdir(parents=True)
    normals = np.random.default_rng(0).normal(size=(64, 3))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    for seed in range(count):
        r = SynthesisRequest.model_validate({
            "object": {"points": 0.03 * normals, "normals": normals}, "task": {"kind": "force_closure"},
            "robot": {"name": "panda_gripper"}, "options": {"seed": seed, "max_iterations": 3},
        })  # fmt: skip
        (directory / f"r{seed:05d}.json").write_text(r.model_dump_json(exclude_none=True))


def _print(rows: list[Row], args: argparse.Namespace) -> None:
    work = rows[0].seconds / rows[0].items
    work_name = f"staged, {args.stage_seconds * 1000:g} ms a stage" if args.pipeline == "staged" else "models"
    print(f"{args.requests} requests, pipeline {work_name}, batch {args.batch_size}, {os.cpu_count()} cores; "
          f"work a request (in-process): {work * 1000:.1f} ms")  # fmt: skip
    print("| backend | workers | items | wall s | first result s | items/s | items/s after the first "
          "| overhead ms/item |")  # fmt: skip
    print("|---|--:|--:|--:|--:|--:|--:|--:|")
    for r in rows:
        overhead = (r.seconds * r.workers / r.items - work) * 1000
        print(f"| {r.backend} | {r.workers} | {r.items} | {r.seconds:.2f} | {r.first:.2f} | {r.rate:.1f} "
              f"| {r.steady:.1f} | {overhead:.1f} |")
