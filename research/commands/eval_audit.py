"""`mani-lab eval audit`: the service's answers on third-party objects, judged by the independent audit.

For each hand, task (``lift``: 5 cm up; ``closure``) and object geometry the caller sends (``mesh``: points, normals
and the mesh; ``points``: points and normals only), the pipeline answers each third-party object (meshes that
installed packages ship, `research.audit.third_party_objects`) and `research.audit` checks every proposal on the exact
mesh and the hand's own kinematics: 5 mm contact tolerance, 1 mm penetration, the caller's normals for the cones,
wrench cosine ≥ 0.99. ``false claims`` counts proposals the service called a success that the audit rejects (the
figure that must be 0); ``best passes`` the share of objects whose best proposal passes the audit.

Example:
    mani-lab eval audit --hand leap,allegro --task lift,closure --geometry mesh,points --objects 18 --proposals 2
"""

from __future__ import annotations

import argparse
import time
from typing import Any

EXIT_OK, EXIT_FAILED, EXIT_USAGE = 0, 1, 2


def add_audit_parser(sub: Any) -> None:
    """The ``eval audit`` sub-command."""
    a = sub.add_parser("audit", help="third-party objects: the service's claims against the independent audit",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)  # fmt: skip
    a.add_argument("--hand", default="leap,allegro", help="hand name(s), comma separated")
    a.add_argument("--task", default="lift,closure", help="lift and/or closure")
    a.add_argument("--geometry", default="mesh,points", help="what the caller sends: mesh and/or points")
    a.add_argument("--objects", type=int, default=18, help="third-party objects (at most 43 here)")
    a.add_argument("--proposals", type=int, default=2, help="proposals per request")
    a.add_argument("--points", type=int, default=2048, help="surface points sent")
    a.add_argument("--method", default="random_contacts", help="request method (random_contacts, network, ...)")
    a.add_argument("--seed", type=int, default=0)
    a.set_defaults(func=run_audit)


def run_audit(args: argparse.Namespace) -> int:
    """Run every cell and print the table; exit 1 when any claimed success fails the audit."""
    import numpy as np
    import torch
    from rich.console import Console
    from rich.progress import Progress
    from rich.table import Table

    from research.audit import third_party_objects
    from research.evaluation.audit import audit_service

    torch.set_num_threads(1)
    hands = [h for h in args.hand.split(",") if h]
    tasks = [t for t in args.task.split(",") if t]
    geometries = [g for g in args.geometry.split(",") if g]
    if any(t not in ("lift", "closure") for t in tasks) or any(g not in ("mesh", "points") for g in geometries):
        print("--task takes lift and/or closure; --geometry mesh and/or points")
        return EXIT_USAGE
    objects = third_party_objects(args.objects)
    console = Console(width=140)
    table = Table(title=f"audit of the service's answers ({len(objects)} third-party objects, "
                        f"{args.proposals} proposals, {args.points} points, method {args.method})")  # fmt: skip
    for col in ("hand", "task", "sent", "objects", "best claimed %", "best passes %", "false claims",
                "median s"):  # fmt: skip
        table.add_column(col, justify="left" if col in ("hand", "task", "sent") else "right")
    false_total = 0
    with Progress(console=console) as bar:
        for hand in hands:
            for task in tasks:
                for geometry in geometries:
                    job = bar.add_task(f"{hand} {task} {geometry}", total=len(objects))
                    claimed = passed = false = 0
                    seconds = []
                    for obj in objects:
                        t0 = time.perf_counter()
                        rows = audit_service(hand, obj, task, num_points=args.points, proposals=args.proposals,
                                             method=args.method, seed=args.seed, send_mesh=geometry == "mesh")
                        seconds.append(time.perf_counter() - t0)
                        claimed += rows[0].claimed
                        passed += rows[0].audited
                        false += sum(r.claimed and not r.audited for r in rows)
                        for r in rows:
                            if r.claimed and not r.audited:
                                console.print(f"false claim: {hand} {task} {geometry} {obj.name}: {r.failures}")
                        bar.advance(job)
                    false_total += false
                    n = len(objects)
                    table.add_row(hand, task, geometry, str(n), f"{100 * claimed / n:.1f}", f"{100 * passed / n:.1f}",
                                  str(false), f"{float(np.median(seconds)):.2f}")  # fmt: skip
    console.print(table)
    return EXIT_FAILED if false_total else EXIT_OK
