"""`mani-lab bench refine`: one SCP step with Clarabel's native API vs the same step rebuilt in CVXPY, in one run.

Times are CPU seconds of this process (one thread), robust to other load on the machine. Both solve identical
local models (linearisations of a hand facing procedural objects from random directions,
with random finger joints); the objectives must agree and the times are compared (median, ratio). With
``--refinements N`` it also times N full refinements (force closure, from the evaluation's approach start) with
the adaptive trust region and with the paper's fixed one.

Example:
    mani-lab bench refine --hand allegro --steps 40 --refinements 10
"""

from __future__ import annotations

import argparse
from typing import Any

EXIT_OK = 0


def register(subparsers: Any) -> None:
    """Add ``refine`` to the ``mani-lab bench`` sub-commands."""
    p = subparsers.add_parser("refine", help="SCP step: native Clarabel vs rebuilt CVXPY (ratio)",
                              description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--hand", default="allegro", help="hand name (default allegro)")
    p.add_argument("--steps", type=int, default=40, help="linearisations to time (default 40)")
    p.add_argument("--refinements", type=int, default=0, help="also time this many full refinements")
    p.add_argument("--seed", type=int, default=0)
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    import time

    import numpy as np
    import torch
    from rich.console import Console
    from rich.table import Table
    from tqdm import tqdm

    from manifoundation.core.objects import object_set
    from manifoundation.core.refine.field import PointCloudField
    from manifoundation.core.refine.refine import RefineConfig, refine
    from manifoundation.core.refine.state import HandPose, linearise
    from manifoundation.core.refine.step import StepParams, solve_step, solve_step_cvxpy
    from manifoundation.core.refine.wrench import characteristic_length, closure_task, rigid_task
    from manifoundation.core.robots import get_hand
    from research.evaluation.refinement import approach_start

    torch.set_num_threads(1)
    hand = get_hand(args.hand)
    rng = np.random.default_rng(args.seed)
    objects = object_set(max(4, args.steps // 5), seed=args.seed)
    n = 6 + hand.dof
    base = np.concatenate([np.full(3, 0.01), np.full(3, 0.1), np.full(n - 6, 0.15)])
    native, rebuilt, gaps = [], [], []
    for i in tqdm(range(args.steps), desc="steps"):
        obj = objects[i % len(objects)]
        cloud = PointCloudField(obj.points, obj.normals)
        length = characteristic_length(obj.points, np.zeros(3))
        task = closure_task(np.zeros(3), length) if i % 2 else rigid_task(rng.normal(size=6), np.zeros(3), length)
        start = approach_start(hand, cloud, np.zeros(3), rng)
        q = np.clip(start.q + rng.normal(scale=0.2, size=hand.dof), hand.lower, hand.upper)
        lin = linearise(hand, HandPose(start.palm_pos, start.palm_quat, q), cloud, task, 0.5, 1.0)
        params = StepParams(base, 0.25)
        t0 = time.process_time()
        a = solve_step(lin, params)
        t1 = time.process_time()
        b = solve_step_cvxpy(lin, params)
        t2 = time.process_time()
        native.append(t1 - t0)
        rebuilt.append(t2 - t1)
        gaps.append(abs(a.objective - b.objective) / max(1.0, abs(b.objective)))
    table = Table(title=f"SCP step, {hand.name}, {args.steps} local models (one core)")
    for col in ("solver", "median ms", "p90 ms"):
        table.add_column(col, justify="right")
    for name, t in (("clarabel native", native), ("cvxpy rebuilt", rebuilt)):
        table.add_row(name, f"{1e3 * np.median(t):.2f}", f"{1e3 * np.percentile(t, 90):.2f}")
    console = Console(width=120)
    console.print(table)
    console.print(f"ratio (median cvxpy / median native): {np.median(rebuilt) / np.median(native):.1f}x; "
                  f"max relative objective gap {max(gaps):.1e}")
    if args.refinements:
        # the same starts for the adaptive trust region (default) and the paper's fixed s_q, s_f
        starts = []
        for i in range(args.refinements):
            obj = objects[i % len(objects)]
            cloud = PointCloudField(obj.points, obj.normals)
            task = closure_task(np.zeros(3), characteristic_length(obj.points, np.zeros(3)))
            starts.append((cloud, task, approach_start(hand, cloud, np.zeros(3), rng)))
        rows = Table(title=f"{args.refinements} force-closure refinements from approach starts")
        for col in ("trust region", "converged %", "median s", "p90 s", "median it", "ms / it"):
            rows.add_column(col, justify="right")
        for label, cfg in (("adaptive", RefineConfig()), ("fixed", RefineConfig(adaptive=False))):
            times, its, conv = [], [], []
            for cloud, task, start in tqdm(starts, desc=f"refinements ({label})"):
                t0 = time.process_time()
                res = refine(hand, cloud, task, start, 0.5, cfg)
                times.append(time.process_time() - t0)
                its.append(res.iterations)
                conv.append(res.converged)
            rows.add_row(label, f"{100 * np.mean(conv):.0f}", f"{np.median(times):.3f}",
                         f"{np.percentile(times, 90):.3f}", f"{np.median(its):.0f}",
                         f"{1e3 * np.sum(times) / max(1, np.sum(its)):.1f}")
        console.print(rows)
    return EXIT_OK
