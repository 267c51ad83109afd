"""`mani-lab bench network`: latency, throughput and memory of the network's inference, per configuration.

Untrained (random, seeded) weights: the cost does not depend on the values. Each measurement calls
``ContactPredictor.predict`` on a batch of synthetic objects (N points on a sphere, a 1024-point hand that is
cached after the warm-up, as in the service), so normalisation, resampling and the map back are included.
"""

from __future__ import annotations

import argparse
import os
import platform
import time
from pathlib import Path
from typing import Any


def register(subparsers: Any) -> None:
    """Add the ``network`` benchmark to ``mani-lab bench``."""
    p = subparsers.add_parser(
        "network",
        help="latency/throughput/memory of the contact network (both configurations)",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog="example: mani-lab bench network --configs cpu --batches 1,8 --iters 10",
    )
    p.add_argument("--configs", default="cpu,paper", help="comma-separated configuration names")
    p.add_argument("--points", type=int, default=2048, help="points per object (N)")
    p.add_argument("--batches", default="1,8,32", help="comma-separated batch sizes")
    p.add_argument("--samples", type=int, default=1, help="latent samples K per object")
    p.add_argument("--iters", type=int, default=20, help="timed calls per batch size")
    p.add_argument("--warmup", type=int, default=3, help="untimed calls first")
    p.add_argument("--threads", type=int, default=2, help="torch intra-op threads")
    p.add_argument(
        "--deformable",
        action="store_true",
        help="objects carry cloth properties, so a network's deformable head runs (rigid objects skip it)",
    )
    p.set_defaults(func=run)


def _reset_peak_rss() -> bool:
    try:
        Path("/proc/self/clear_refs").write_text("5")
        return True
    except OSError:
        return False


def _peak_rss_mb() -> float:
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) / 1024.0
    except OSError:
        pass
    import resource

    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def _inputs(n: int, batch: int, deformable: bool = False) -> list[Any]:
    import numpy as np

    from manifoundation.core.deformable.materials import DEFAULTS
    from manifoundation.core.network import NetworkInput

    rng = np.random.default_rng(0)
    hand = rng.standard_normal((1024, 3))
    hand_n = hand / np.linalg.norm(hand, axis=1, keepdims=True)
    out = []
    for _ in range(batch):
        d = rng.standard_normal((n, 3))
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        out.append(
            NetworkInput(
                points=d * 0.1,
                normals=d,
                motion=np.tile([0.02, 0.0, 0.0], (n, 1)),
                mask=np.ones(n, dtype=bool),
                properties=dict(DEFAULTS["cloth"]) if deformable else {"friction": 0.5},  # what a cloth request gets
                hand_points=hand_n * 0.05,
                hand_normals=hand_n,
                hand_key="bench-hand",
            )
        )
    return out


def run(args: argparse.Namespace) -> int:
    """Run the benchmark and print one table row per (configuration, batch size)."""
    import numpy as np
    import torch

    from manifoundation.core.network import ContactPredictor, count_parameters

    torch.set_num_threads(args.threads)
    batches = [int(b) for b in args.batches.split(",")]
    exact_peak = _reset_peak_rss()
    print(
        f"machine: {platform.machine()}, {os.cpu_count()} CPUs, torch {torch.__version__}, "
        f"{torch.get_num_threads()} threads; N={args.points}, K={args.samples}, {args.iters} timed calls, "
        f"{'cloth' if args.deformable else 'rigid'} objects; "
        f"load average at start {os.getloadavg()[0]:.1f}"
    )
    print(f"peak memory: process peak RSS {'during each row' if exact_peak else 'so far (cumulative)'}")
    header = (
        f"{'config':<8} {'params':>10} {'batch':>5} {'p50 ms':>9} {'p90 ms':>9} {'samples/s':>10} "
        f"{'CPU ms/obj':>10} {'peak MB':>8}"
    )
    print(header)
    print("-" * len(header))
    for name in args.configs.split(","):
        predictor = ContactPredictor.untrained(name.strip(), seed=0)
        params = count_parameters(predictor.model)
        for batch in batches:
            inputs = _inputs(args.points, batch, args.deformable)
            for _ in range(args.warmup):
                predictor.predict(inputs, num_samples=args.samples, seed=0)
            _reset_peak_rss()
            times = []
            cpu0 = time.process_time()
            for i in range(args.iters):
                t0 = time.perf_counter()
                predictor.predict(inputs, num_samples=args.samples, seed=i)
                times.append(time.perf_counter() - t0)
            cpu_ms = (time.process_time() - cpu0) * 1e3 / (args.iters * batch)
            p50, p90 = np.percentile(times, 50), np.percentile(times, 90)
            print(
                f"{name:<8} {params:>10,} {batch:>5} {p50 * 1e3:>9.1f} {p90 * 1e3:>9.1f} "
                f"{batch / p50:>10.1f} {cpu_ms:>10.1f} {_peak_rss_mb():>8.0f}"
            )
    print("samples/s = objects per second at the median latency (batch / p50); K latent samples each.")
    print("CPU ms/obj = process CPU time per object (all threads): a figure that other load disturbs less.")
    return 0
