"""Bring-your-own-hand figures: third-party hands zipped from their PyPI packages, built as an upload is (archive
checks, palm cut, spheres, pads, point cloud), then force-closure grasps of a small set of boxes and cylinders,
every proposal audited against the package's original files (`research.evaluation.custom_hands`).

Run: ``python -m research.commands.bench_custom_hands [--hands g1_dex3,orca] [--proposals 4]`` (one torch thread).
Columns: build = seconds to read the archive and build the hand (what registration costs a worker); best ok =
objects whose best proposal the service calls a success and the audit passes; proposals = audited / claimed
successes over all proposals (a claim the audit rejects is a false claim); s/obj = seconds per request.
"""

from __future__ import annotations

import argparse
import platform
import time
from typing import Any

SIZES = {"rethink": (0.03, 0.035)}
"""m: object sizes per hand (box edge, cylinder diameter); the Rethink gripper opens to about 4 cm."""
DEFAULT_SIZES = (0.04, 0.05)


def register(subparsers: Any) -> None:
    """Add the ``custom-hands`` benchmark to ``mani-lab bench``."""
    p = subparsers.add_parser("custom-hands", help="third-party hands: build time, spheres, audited grasps",
                              description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)  # fmt: skip
    _arguments(p)
    p.set_defaults(func=run)


def _arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--hands", default="", help="comma-separated (default: every installed one, and leap_hand)")
    p.add_argument("--proposals", type=int, default=4, help="proposals per request (default 4)")
    p.add_argument("--seed", type=int, default=0)


def _objects(name: str) -> list[tuple[str, Any]]:
    import trimesh

    out = []
    for s in SIZES.get(name, DEFAULT_SIZES):
        out.append((f"box {s * 100:.1f} cm", trimesh.creation.box(extents=[s, s, s])))
        out.append((f"cyl d{s * 100:.1f} cm", trimesh.creation.cylinder(radius=s / 2, height=0.08, sections=48)))
    return out


def run(args: argparse.Namespace) -> int:
    """Print one row per hand (see module doc)."""
    import numpy as np
    import torch

    from manifoundation.core.robots import get_hand
    from manifoundation.core.robots.thirdparty import third_party_hands
    from manifoundation.core.robots.user_hand import HandSource, build_user_hand, pad_areas
    from research.audit.hands import load_hand
    from research.evaluation.custom_hands import audit_hand, grasp_and_audit

    torch.set_num_threads(1)
    packaged = third_party_hands()
    names = [n for n in args.hands.split(",") if n] or [*[n for n, h in packaged.items() if h.available], "leap_hand"]
    print(
        f"# {platform.processor() or platform.machine()}, torch threads 1, proposals {args.proposals}, seed {args.seed}"
    )
    head = f"{'hand':<10} {'fmt':<5} {'DoF':>3} {'tips':>4} {'spheres':>7} {'pad cm2':>7} {'zip MB':>6} {'build s':>7}"
    head += f" {'objects':>7} {'best ok':>7} {'proposals':>9} {'false':>5} {'s/obj':>6}"
    print(head)
    print("-" * len(head))
    for name in names:
        if name == "leap_hand":
            t0 = time.perf_counter()
            get_hand.cache_clear()
            hand, fmt, size = get_hand(name), "mjcf", 0.0  # shipped: no archive
            build_s = time.perf_counter() - t0
            pads = float(np.mean(pad_areas(hand))) * 1e4
            checker = load_hand(name)
        else:
            package = packaged[name]
            archive = package.archive()
            built = build_user_hand(HandSource(name=name, archive=archive, palm=package.palm))
            hand, fmt, size, build_s = built.hand, built.format, len(archive) / 1e6, built.seconds
            pads = float(np.mean(built.pad_areas)) * 1e4
            checker = audit_hand(package, built.fingertips)
        best = claimed = audited = 0
        t0 = time.perf_counter()
        objects = _objects(name)
        for _, mesh in objects:
            r = grasp_and_audit(hand, checker, mesh, proposals=args.proposals, seed=args.seed)
            best += r.best_audited
            claimed += r.claimed
            audited += r.audited
        per = (time.perf_counter() - t0) / len(objects)
        row = f"{name:<10} {fmt:<5} {hand.dof:>3} {hand.num_fingertips:>4} {len(hand.sphere_radii):>7} {pads:>7.1f}"
        row += f" {size:>6.2f} {build_s:>7.2f} {len(objects):>7} {best:>4}/{len(objects):<2} {audited:>4}/{claimed:<4}"
        row += f" {claimed - audited:>5} {per:>6.1f}"
        print(row, flush=True)
    return 0


def main() -> None:
    """``python -m research.commands.bench_custom_hands``."""
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    _arguments(parser)
    raise SystemExit(run(parser.parse_args()))


if __name__ == "__main__":
    main()
