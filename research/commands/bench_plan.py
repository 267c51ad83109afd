"""`mani-lab bench plan`: planning time and per-step synthesis time of a 10-waypoint task in a cluttered scene, and
the share of steps that keep the grasp.

Each seed makes its own scene and task: a table with ``--obstacles`` boxes (4-12 cm wide, 5-30 cm tall, turned
about z, within ±0.45 m), a cup standing on it, and ``--waypoints`` random poses 8-35 cm above the table (turned
up to ±60° about z and tilted up to 20°) — some fall inside the clutter and are repaired, as an LLM's would be.
Times are wall seconds of this process on one thread (``torch.set_num_threads(1)``).

Example:
    mani-lab bench plan --hand allegro --seeds 0,1,2 --method random_contacts
"""

from __future__ import annotations

import argparse
from typing import Any

EXIT_OK = 0


def register(subparsers: Any) -> None:
    """Add ``plan`` to the ``mani-lab bench`` sub-commands."""
    p = subparsers.add_parser("plan", help="planner link: planning and per-step synthesis time, kept-grasp share",
                              description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)  # fmt: skip
    p.add_argument("--hand", default="allegro", help="hand name (default allegro)")
    p.add_argument("--seeds", default="0,1,2", help="comma-separated seeds, one scene and task each")
    p.add_argument("--waypoints", type=int, default=10, help="waypoints per task (default 10)")
    p.add_argument("--obstacles", type=int, default=12, help="clutter boxes on the table (default 12)")
    p.add_argument("--method", default="random_contacts", choices=("random_contacts", "network"))
    p.add_argument("--translation-step", type=float, default=0.04, help="m (default 0.04)")
    p.add_argument("--rotation-step", type=float, default=0.3, help="rad (default 0.3)")
    p.add_argument("--time-limit", type=float, default=10.0, help="RRT-Connect seconds per task (default 10)")
    p.add_argument("--no-contacts", action="store_true", help="time the trajectory only")
    p.set_defaults(func=run)


def bench_task(hand: Any, seed: int, waypoints: int, obstacles: int, options: Any) -> Any:
    """The seeded task of the module doc as a `PlanInput`."""
    import numpy as np
    from scipy.spatial.transform import Rotation

    from manifoundation.core.planning import Obstacle, PlanInput, Pose
    from manifoundation.core.planning.scenes import cluttered_table, cup_mesh, sampled

    rng = np.random.default_rng(seed)
    start = Pose(np.array([*rng.uniform(-0.3, 0.3, size=2), 0.0]))
    boxes, table = cluttered_table(obstacles, seed, extent=0.45, keep_clear=[start.position])
    poses = []
    for _ in range(waypoints):
        position = np.array([*rng.uniform(-0.4, 0.4, size=2), rng.uniform(0.08, 0.35)])
        axis = rng.uniform(0, 2 * np.pi)
        tilt = Rotation.from_rotvec(np.array([np.cos(axis), np.sin(axis), 0.0]) * rng.uniform(0, np.radians(20.0)))
        turn = Rotation.from_rotvec([0.0, 0.0, rng.uniform(-np.pi / 3, np.pi / 3)])
        poses.append(Pose.from_rotation(position, turn * tilt))
    cup = cup_mesh()
    points, normals = sampled(cup, 1024, seed=seed)
    scene: list[Obstacle] = list(boxes)
    return PlanInput(points=points, normals=normals, hand=hand, start=start, waypoints=poses, obstacles=scene,
                     support=table, mesh_vertices=np.asarray(cup.vertices), mesh_faces=np.asarray(cup.faces),
                     properties={"friction": 0.8}, options=options, hand_key=hand.name)  # fmt: skip


def run(args: argparse.Namespace) -> int:
    import resource
    import time
    from collections import Counter

    import numpy as np
    import torch
    from rich.console import Console
    from rich.table import Table

    from manifoundation.core.planning import PlanningError, PlanOptions, plan_manipulation
    from manifoundation.core.robots import get_hand
    from manifoundation.server.commands.plan import load_predictor

    torch.set_num_threads(1)
    hand = get_hand(args.hand)
    predictor = load_predictor(None) if args.method == "network" and not args.no_contacts else None
    seeds = [int(s) for s in args.seeds.split(",") if s.strip()]
    table = Table(title=f"plan bench: {hand.name}, {args.waypoints} waypoints, {args.obstacles} obstacles, "
                        f"{args.method}, steps {args.translation_step} m / {args.rotation_step} rad")  # fmt: skip
    for col in ("seed", "repaired", "RRT segs", "planning s", "steps", "synthesis s", "kept med s",
                "new med s", "step p90 s", "kept %", "regrasps", "failed"):
        table.add_column(col, justify="right")
    all_steps: list[Any] = []
    plans = []
    for seed in seeds:
        options = PlanOptions(time_limit=args.time_limit, translation_step=args.translation_step,
                              rotation_step=args.rotation_step, seed=seed, method=args.method,
                              contacts=not args.no_contacts)  # fmt: skip
        inp = bench_task(hand, seed, args.waypoints, args.obstacles, options)
        t0 = time.perf_counter()
        try:
            plan = plan_manipulation(inp, predictor)
        except PlanningError as exc:
            table.add_row(str(seed), *["-"] * 10, f"no plan: {exc}"[:40])
            continue
        wall = time.perf_counter() - t0
        plans.append(plan)
        secs = np.array([s.seconds for s in plan.steps]) if plan.steps else np.zeros(1)
        kept = [s.seconds for s in plan.steps if s.grasp == "kept"]
        new = [s.seconds for s in plan.steps if s.grasp != "kept"]
        all_steps += plan.steps
        failed = sum(s.grasp == "failed" for s in plan.steps)
        table.add_row(
            str(seed), str(len(plan.repairs)), f"{sum(not s.straight for s in plan.segments)}/{len(plan.segments)}",
            f"{plan.timings['planning'] + plan.timings['repair']:.2f}", str(len(plan.poses) - 1),
            f"{plan.timings.get('contacts', 0.0):.1f}", f"{np.median(kept):.3f}" if kept else "-",
            f"{np.median(new):.2f}" if new else "-", f"{np.percentile(secs, 90):.3f}",
            f"{100 * plan.kept_share:.0f}" if plan.steps else "-", str(len(plan.regrasps)), str(failed),
        )  # fmt: skip
        cpu = resource.getrusage(resource.RUSAGE_SELF).ru_utime
        print(f"seed {seed}: {wall:.1f} s wall, process CPU so far {cpu:.1f} s", flush=True)
    console = Console(width=160)
    console.print(table)
    rrt = [seg for p in plans for seg in p.segments if not seg.straight]
    if rrt:
        console.print(f"RRT-Connect: {len(rrt)} segments, median {np.median([s.planner_seconds for s in rrt]):.3f} s "
                      f"to connect, median {np.median([s.simplify_seconds for s in rrt]):.3f} s to simplify, "
                      f"{np.median([s.raw_states for s in rrt]):.0f} → "
                      f"{np.median([s.simplified_states for s in rrt]):.0f} states (median)")  # fmt: skip
    dropped = Counter(s.dropped.split(":")[0].split(" ")[0] for s in all_steps if s.dropped)
    if dropped:
        console.print("grasps given up because of: " + ", ".join(f"{why} {n}" for why, n in dropped.most_common()))
    if all_steps:
        later = [s for p in plans for s in p.steps[1:]]
        share = sum(s.grasp == "kept" for s in later) / max(len(later), 1)
        secs = np.array([s.seconds for s in all_steps])
        console.print(f"all seeds: {len(all_steps)} steps, median synthesis {np.median(secs):.3f} s a step, "
                      f"{100 * share:.1f}% of steps after the first keep the grasp, "
                      f"{sum(s.success for s in all_steps)}/{len(all_steps)} verified and collision-free")  # fmt: skip
    return EXIT_OK
