"""`mani plan FILE`: plan a manipulation locally from a YAML/JSON plan file and print a summary.

The file names the object, the hand, the start pose, the waypoints, the scene and the options (format:
`manifoundation.core.planning.spec`; the wire schema's field names). The object's path is planned with OMPL RRT-Connect
against the scene (waypoints in collision are repaired or reported), densified, and the contact model answers
every step, keeping the grasp while it works. Exit status 0 when every step is verified and collision-free,
1 when not (or no path was found), 2 for a bad plan file.

Examples:
    mani plan plan.yaml --method random_contacts --html plan.html
    mani plan plan.json --no-contacts --json trajectory.json
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

EXIT_OK, EXIT_FAILED, EXIT_USAGE = 0, 1, 2


def register(subparsers: Any) -> None:
    """Add ``plan`` to ``mani``."""
    p = subparsers.add_parser("plan", help="plan a manipulation through waypoints locally (trajectory + contacts)",
                              description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)  # fmt: skip
    p.add_argument("file", type=Path, help="plan file (.yaml, .yml or .json)")
    p.add_argument("--method", choices=("network", "random_contacts"), help="contacts of a new grasp (file's)")
    p.add_argument("--seed", type=int, help="seed of planner and synthesis (file's, default 0)")
    p.add_argument("--time-limit", type=float, help="RRT-Connect seconds over all segments (file's, default 5)")
    p.add_argument("--proposals", type=int, help="hand proposals per new grasp (file's, default 4)")
    p.add_argument("--no-contacts", action="store_true", help="plan the trajectory only")
    p.add_argument("--weights", type=Path, default=None, help="checkpoint directory for method network "
                   "(default: the shipped manifoundation/core/weights)")  # fmt: skip
    p.add_argument("--json", type=Path, default=None, help="write the plan (poses, repairs, steps) as JSON")
    p.add_argument("--html", type=Path, default=None, help="write an offline 3D view that plays the plan")
    p.set_defaults(func=run)


def load_predictor(path: Path | None) -> Any | None:
    """The network from ``path`` (or the shipped weights): the directory or its first loadable sub-directory."""
    import manifoundation.core
    from manifoundation.core.network.inference import ContactPredictor

    root = path or Path(manifoundation.core.__file__).parent / "weights"
    if not root.is_dir():
        return None
    for candidate in [root, *sorted(p for p in root.iterdir() if p.is_dir())]:
        try:
            return ContactPredictor.from_checkpoint(candidate)
        except (FileNotFoundError, ValueError, KeyError, OSError):
            continue
    return None


def run(args: argparse.Namespace) -> int:
    """Load the plan file, plan, print the summary; write JSON / HTML when asked."""
    import json
    from dataclasses import replace

    import torch

    from manifoundation.core.pipeline import ModelUnavailable
    from manifoundation.core.planning import InvalidPlan, PlanningError, plan_manipulation, scene_of
    from manifoundation.core.planning.export import plan_to_dict, summary_lines
    from manifoundation.core.planning.spec import load_plan_file
    from manifoundation.core.robots import get_hand

    torch.set_num_threads(1)
    if not args.file.is_file():
        print(f"{args.file}: no such file")
        return EXIT_USAGE
    try:
        inp = load_plan_file(args.file, get_hand)
    except InvalidPlan as exc:
        print(f"{args.file}: {exc}")
        return EXIT_USAGE
    overrides = {"method": args.method, "seed": args.seed, "time_limit": args.time_limit,
                 "num_proposals": args.proposals}  # fmt: skip
    options = replace(inp.options, **{k: v for k, v in overrides.items() if v is not None})
    if args.no_contacts:
        options = replace(options, contacts=False)
    inp = replace(inp, options=options)
    predictor = load_predictor(args.weights) if options.contacts and options.method == "network" else None
    print(f"{inp.hand.name}: {len(inp.points)} object points, {len(inp.waypoints)} waypoints, "
          f"{len(inp.obstacles)} obstacles, method {options.method}, seed {options.seed}")  # fmt: skip
    try:
        plan = plan_manipulation(inp, predictor)
    except InvalidPlan as exc:
        print(f"invalid plan: {exc}")
        return EXIT_USAGE
    except (PlanningError, ModelUnavailable) as exc:
        print(f"no plan: {exc}")
        return EXIT_FAILED
    for line in summary_lines(plan):
        print(line)
    for s in plan.steps:
        if not s.success:
            why = s.proposal.quality.failures if s.proposal is not None else ["no answer"]
            print(f"  step {s.index}: {s.grasp}, verification {why or 'passed'}, hand meets {s.hand_collisions}")
    if args.json:
        args.json.write_text(json.dumps(plan_to_dict(plan), indent=1))
        print(f"plan written to {args.json}")
    if args.html:
        from manifoundation.core.planning.view import plan_figure

        plan_figure(plan, scene_of(inp), inp.hand).write_html(str(args.html), include_plotlyjs=True)
        print(f"view written to {args.html}")
    return EXIT_OK if plan.success else EXIT_FAILED

