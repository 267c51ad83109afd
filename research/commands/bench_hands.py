"""`mani-lab bench hands`: forward kinematics + all fingertip Jacobians per hand (batch 1 and 64), sphere centres +
Jacobians, and the KD-tree signed distance per 100 query points.

Median and minimum of ``--iters`` timed calls after 3 warm-up calls (the minimum is the least disturbed call on a
shared machine), float64 (what the refinement uses) unless ``--float32``, one torch thread unless ``--threads``.
"""

from __future__ import annotations

import argparse
import os
import platform
import time
from typing import Any


def register(subparsers: Any) -> None:
    """Add the ``hands`` benchmark to ``mani-lab bench``."""
    p = subparsers.add_parser(
        "hands",
        help="FK + fingertip/sphere Jacobians per hand; signed-distance query time",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog="example: mani-lab bench hands --iters 50 --batches 1,64",
    )
    p.add_argument("--hands", default="", help="comma-separated hand names (default: all built-ins)")
    p.add_argument("--batches", default="1,64", help="comma-separated batch sizes")
    p.add_argument("--iters", type=int, default=30, help="timed calls per measurement")
    p.add_argument("--sdf-points", default="2048,8192", help="comma-separated object cloud sizes for the SDF")
    p.add_argument("--threads", type=int, default=1, help="torch intra-op threads (workers run 1 each)")
    p.add_argument("--float32", action="store_true", help="time float32 instead of float64")
    p.set_defaults(func=run)


def _median_ms(fn: Any, iters: int) -> float:
    return _times_ms(fn, iters)[0]


def _times_ms(fn: Any, iters: int) -> tuple[float, float]:
    """(median, min) wall milliseconds of ``iters`` calls after 3 warm-up calls (min: least disturbed call)."""
    for _ in range(3):
        fn()
    times = []
    for _ in range(iters):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    times.sort()
    return 1e3 * times[len(times) // 2], 1e3 * times[0]


def run(args: argparse.Namespace) -> int:
    """Print one row per (hand, batch) and the SDF timing."""
    import numpy as np
    import torch

    from manifoundation.core.geometry import ObjectGeometry
    from manifoundation.core.robots import get_hand, list_hands

    torch.set_num_threads(args.threads)
    dtype = torch.float32 if args.float32 else torch.float64
    names = [n for n in args.hands.split(",") if n] or list_hands()
    batches = [int(b) for b in args.batches.split(",") if b]
    kind = str(dtype).removeprefix("torch.")
    cpu = platform.processor() or platform.machine()
    print(
        f"machine: {cpu}, {os.cpu_count()} cores, torch {torch.__version__}, threads {torch.get_num_threads()}, {kind}"
    )
    header = (
        f"{'hand':<14} {'dof':>4} {'tips':>4} {'spheres':>7} {'batch':>5} {'tips+J ms p50/min':>18} "
        f"{'spheres+J ms p50/min':>21}"
    )
    print(header)
    print("-" * len(header))
    for name in names:
        hand = get_hand(name)
        for B in batches:
            g = np.random.default_rng(0)
            pos = torch.as_tensor(g.normal(scale=0.1, size=(B, 3)), dtype=dtype)
            quat = torch.as_tensor(g.normal(size=(B, 4)), dtype=dtype)
            quat = quat / quat.norm(dim=-1, keepdim=True)
            q = torch.as_tensor(g.uniform(hand.lower, hand.upper, size=(B, hand.dof)), dtype=dtype)
            tip50, tipmin = _times_ms(lambda: hand.fingertip_jacobians(pos, quat, q), args.iters)  # noqa: B023
            sph50, sphmin = _times_ms(lambda: hand.spheres(pos, quat, q), args.iters)  # noqa: B023
            t_tip, t_sph = f"{tip50:.3f}/{tipmin:.3f}", f"{sph50:.3f}/{sphmin:.3f}"
            print(f"{name:<14} {hand.dof:>4} {hand.num_fingertips:>4} {len(hand.sphere_radii):>7} {B:>5} "
                  f"{t_tip:>18} {t_sph:>21}")  # fmt: skip
    g = np.random.default_rng(0)
    for n in (int(v) for v in args.sdf_points.split(",") if v):
        d = g.normal(size=(n, 3))
        d /= np.linalg.norm(d, axis=1, keepdims=True)
        geom = ObjectGeometry.from_points(0.05 * d, d)
        x = g.normal(scale=0.06, size=(100, 3))
        t_sdf = _median_ms(lambda: geom.signed_distance(x), args.iters)  # noqa: B023
        t_mesh = _median_ms(lambda: geom.mesh.nearest.signed_distance(x), max(3, args.iters // 10))  # noqa: B023
        print(f"signed distance, {n}-point cloud, 100 queries: KD-tree {t_sdf:.3f} ms; "
              f"trimesh on its convex hull ({len(geom.mesh.faces)} faces) {t_mesh:.3f} ms")  # fmt: skip
    return 0
