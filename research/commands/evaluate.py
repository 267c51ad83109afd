"""`mani-lab eval`: evaluations of the science (paper Tables I and II).

``mani-lab eval refine`` reproduces the refinement protocol of docs/evaluation.md (see `research.evaluation.refinement`
for the exact procedure: ground-truth poses from the data generator's verified grasp sampling (``--ground-truth
sampled``, default; force-closure grasps for ``closure``) or from our own verified force-closure refinements
(``--ground-truth refined``, the original protocol), targets those grasps can produce, starts retreated + rotated ≤
60° + shifted ≤ 5 cm, fingers at rest) on the procedural test objects of `manifoundation.core.objects` (sizes 5-25 cm,
kinds cycled, seeded), against the direct-grasp baseline.

Examples:
    mani-lab eval refine --hand leap --mode task --objects 20 --grasps 2 --seed 0
    mani-lab eval refine --hand allegro,leap,shadow,barrett --mode task,closure --objects 20 --grasps 2 --json out.json
"""

from __future__ import annotations

import argparse
from typing import Any

from research.commands.eval_audit import add_audit_parser
from research.commands.eval_deformable import add_deformable
from research.commands.eval_dexgraspbench import add_dexgraspbench_parser
from research.commands.eval_labels import add_labels_parser
from research.commands.eval_network import add_network_parser
from research.commands.eval_physics import add_physics_parser

EXIT_OK, EXIT_FAILED, EXIT_USAGE = 0, 1, 2


def register(subparsers: Any) -> None:
    """Add ``eval`` with its ``refine`` (Table II), ``network`` (Table I), ``labels`` (the network's top point on
    re-sampled labels), ``audit``, ``deformable`` (Table I, deformable columns) and ``physics`` (the simulated grasp
    test) and ``dexgraspbench`` (the same answers in DexGraspBench's own evaluation) sub-commands to ``mani``."""
    p = subparsers.add_parser(
        "eval", help="evaluate refinement / network", description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sub = p.add_subparsers(
        dest="eval_command", metavar="{refine,network,labels,audit,deformable,physics,dexgraspbench}"
    )
    add_refine(sub)
    add_network_parser(sub)
    add_labels_parser(sub)
    add_audit_parser(sub)
    add_deformable(sub)
    add_physics_parser(sub)
    add_dexgraspbench_parser(sub)
    p.set_defaults(func=lambda args: (p.print_help(), EXIT_USAGE)[1])


def add_refine(sub: Any) -> None:
    """The ``eval refine`` sub-command."""
    r = sub.add_parser("refine", help="refinement success rate and time vs the direct-grasp baseline (Table II)")
    r.add_argument("--hand", default="leap", help="hand name(s), comma separated (default leap)")
    r.add_argument("--mode", default="task", help="task, closure, or both comma separated (default task)")
    r.add_argument("--objects", type=int, default=20, help="number of test objects (default 20)")
    r.add_argument("--grasps", type=int, default=2, help="grasps per object (default 2)")
    r.add_argument("--seed", type=int, default=0, help="seed of objects, targets and starts (default 0)")
    r.add_argument("--retreat", type=float, default=0.30, help="start distance behind the feasible pose (m, paper 0.3)")
    r.add_argument("--max-iterations", type=int, default=100, help="refinement iteration cap (default 100)")
    r.add_argument("--mu", type=float, default=0.5, help="friction coefficient (default 0.5)")
    r.add_argument("--ground-truth", choices=("sampled", "refined"), default="sampled",
                   help="source of the known-feasible poses: the data generator's grasp sampling (default) or "
                        "our own refinement from a random approach (the original, circular protocol)")
    r.add_argument("--ground-truth-cache", default=None,
                   help="pickle file keeping the sampled ground truths between runs (read if present, then "
                        "updated); delete it after changing the sampler")
    r.add_argument("--json", default=None, help="also write every trial to this JSON file")
    r.set_defaults(func=run_refine)


def run_refine(args: argparse.Namespace) -> int:
    """Run the protocol for every (hand, mode) and print the table."""
    import json
    import os
    import pickle
    from dataclasses import asdict

    import torch
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn
    from rich.table import Table

    from manifoundation.core.objects import object_set
    from manifoundation.core.refine.refine import RefineConfig
    from manifoundation.core.robots import UnknownHand, get_hand
    from research.evaluation.refinement import evaluate

    torch.set_num_threads(1)  # one core per grasp, as the timing goal says
    hands = [h.strip() for h in args.hand.split(",") if h.strip()]
    modes = [m.strip() for m in args.mode.split(",") if m.strip()]
    if any(m not in ("task", "closure") for m in modes) or args.objects < 1 or args.grasps < 1:
        print("mode must be task and/or closure; --objects and --grasps must be ≥ 1")
        return EXIT_USAGE
    try:
        hand_objs = [get_hand(h) for h in hands]
    except UnknownHand as exc:
        print(exc)
        return EXIT_USAGE
    objects = object_set(args.objects, seed=args.seed)
    config = RefineConfig(max_iterations=args.max_iterations)
    console = Console(width=160)
    reports = []
    store: dict[Any, Any] = {}
    if args.ground_truth_cache and os.path.exists(args.ground_truth_cache):
        with open(args.ground_truth_cache, "rb") as src:
            store = pickle.load(src)

    def save_store() -> None:
        tmp = f"{args.ground_truth_cache}.tmp"
        with open(tmp, "wb") as dst:
            pickle.dump(store, dst)
        os.replace(tmp, args.ground_truth_cache)

    with Progress(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                  console=console) as bar:
        for hand in hand_objs:
            cache: dict[Any, Any] = {}  # sampled ground truths shared by the modes of this hand
            for mode in modes:
                job = bar.add_task(f"{hand.name} {mode}", total=args.objects * args.grasps)

                def advance(_trial: Any, job: Any = job, label: str = f"{hand.name} {mode}") -> None:
                    bar.advance(job)
                    done = int(bar.tasks[job].completed)
                    if done % args.grasps:
                        return
                    if not console.is_terminal:  # a log file gets no live bar: one line per object instead
                        console.print(f"{label}: {done}/{args.objects * args.grasps} grasps, "
                                      f"{bar.tasks[job].elapsed or 0.0:.0f} s")
                    if args.ground_truth_cache and done > args.grasps:
                        save_store()  # the previous object's ground truths: an interrupted run resumes from here

                reports.append(evaluate(
                    hand, objects, mode, args.grasps, args.seed, mu=args.mu, retreat=args.retreat, config=config,
                    on_trial=advance, ground_truth=args.ground_truth, cache=cache, store=store,
                ))
                if args.ground_truth_cache:
                    save_store()
    table = Table(title=f"refinement: {args.objects} objects x {args.grasps} grasps, seed {args.seed}, "
                        f"retreat {args.retreat} m, mu {args.mu}, ground truth {args.ground_truth}")
    for col in ("hand", "mode", "n", "skipped", "success %", "median s", "p90 s", "median it",
                "baseline %", "baseline median s"):
        table.add_column(col, justify="right")
    for rep in reports:
        s = rep.summary()
        if not s.get("n"):
            table.add_row(rep.hand, rep.mode, "0", str(s["skipped"]), *["-"] * 6)
            continue
        table.add_row(rep.hand, rep.mode, str(s["n"]), str(s["skipped"]), f"{s['success']:.1f}",
                      f"{s['median_s']:.3f}", f"{s['p90_s']:.3f}", f"{s['median_iterations']:.0f}",
                      f"{s['baseline_success']:.1f}", f"{s['baseline_median_s']:.3f}")
    console.print(table)
    if args.json:
        with open(args.json, "w") as fh:
            json.dump([{"hand": r.hand, "mode": r.mode, "ground_truth": r.ground_truth, "summary": r.summary(),
                        "trials": [asdict(t) for t in r.trials]} for r in reports], fh, indent=1, default=float)
    return EXIT_OK
