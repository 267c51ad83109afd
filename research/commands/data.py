"""`mani-lab data generate`: labelled training data for rigid and articulated objects (see research/data);
`mani-lab data labels`: how dense those labels are (`research.data.label_density`)."""

from __future__ import annotations

import argparse
from typing import Any


def register(subparsers: Any) -> None:
    """Add the ``data`` command (sub-command ``generate``)."""
    p = subparsers.add_parser("data", help="generate training data")
    sub = p.add_subparsers(dest="data_command", required=True)
    g = sub.add_parser("generate", help="generate (or resume) a sharded data set")
    g.add_argument("--out", default="data/v4", help="output directory (shards + manifest.json)")
    g.add_argument("--objects", type=int, default=400, help="number of objects")
    g.add_argument("--seed", type=int, default=0)
    g.add_argument("--workers", type=int, default=2, help="worker processes (Ray actors with --ray)")
    g.add_argument("--ray", metavar="ADDRESS", default=None,
                   help="rigid and articulated shards on Ray Data at ADDRESS (auto, HOST:6379, ray://HOST:10001; "
                        "local: a cluster of its own); docs/offline.md")
    g.add_argument("--objects-per-shard", type=int, default=2)
    g.add_argument(
        "--hands", default=None, help="comma-separated training hands (default: allegro,leap,panda_gripper,kinova3f)"
    )
    g.add_argument("--held-out-hands", default=None, help="comma-separated held-out hands (default: shadow,barrett)")
    g.add_argument("--palms", type=int, default=16, help="palm poses sampled per (object, hand)")
    g.add_argument("--grasps-per-job", type=int, default=6)
    g.add_argument("--max-set", type=int, default=32, help="valid grasps kept per example (its grasp set)")
    g.add_argument("--examples-per-grasp", type=int, default=4, help="examples with random forces per grasp")
    g.add_argument(
        "--targeted-per-grasp", type=int, default=0,
        help="examples of a chosen task per grasp (a lift most often, else a push or a turn; firm forces)",
    )  # fmt: skip
    g.add_argument("--physics", choices=("off", "closure"), default="off",
                   help="closure: only sampled grasps that hold in the simulated six-push test label examples "
                        "(research/data/physics_labels.py); off: every feasible grasp")
    g.add_argument("--closure-mu", type=float, default=None,
                   help="sample grasps aiming for force closure at this friction coefficient (pinching palms, "
                        "closure pre-test; research/data/sampling.py) instead of any feasible grasp")
    g.add_argument("--articulated-fraction", type=float, default=0.2)
    g.add_argument("--test-fraction", type=float, default=0.15)
    g.add_argument(
        "--test-objects-only",
        action="store_true",
        help="label only the test objects (the evaluation set: test_uo and the held-out hands, ~7x faster)",
    )
    g.add_argument(
        "--materials",
        default="rigid,articulated",
        help="comma-separated materials; cloth, rope, plasticine go to OUT/deformable (data.deformable_generate)",
    )
    g.add_argument("--bodies", type=int, default=12, help="deformable bodies per material")
    g.add_argument("--examples-per-body", type=int, default=4, help="simulated manipulations per deformable body")
    g.add_argument(
        "--verify-moving",
        action="store_true",
        help="cloth and rope: label the target's most-moved points too when a rollout verifies them (one more each)",
    )
    g.add_argument(
        "--slides",
        type=float,
        default=0.0,
        help="cloth and rope: this fraction of the examples slides the whole body (labelled by the sets that reach it)",
    )
    g.add_argument("--stiff", action="store_true", help="cloth and rope properties reach a card's and a stick's")
    g.add_argument(
        "--slide-margin",
        type=float,
        default=0.0,
        help="slides: label only the sets that also reach the same heading's slide this long (× size; 0: off)",
    )
    g.add_argument(
        "--stiff-ends",
        type=float,
        default=0.0,
        help="with --stiff: this fraction of bodies draws its stiffness near a handkerchief's or a card's (a rope's "
        "or a stick's) end of the range, either with equal chance",
    )
    g.add_argument(
        "--paired-ends",
        action="store_true",
        help="with --stiff (cloth, rope): bodies come in pairs, one shape at the soft and at the stiff end of the "
        "range, asked the same tasks",
    )
    g.add_argument("--no-progress", action="store_true")
    g.set_defaults(func=_generate)
    lab = sub.add_parser("labels", help="how much of each object its valid grasps cover, and simple rules' hits")
    lab.add_argument("data", nargs="+", help="generated data directories")
    lab.add_argument("--splits", default="train,test_so,test_uo", help="comma-separated splits")
    lab.add_argument("--limit", type=int, default=2000, help="examples read (evenly spaced), at most")
    lab.add_argument("--seed", type=int, default=0)
    lab.set_defaults(func=_labels)


def _generate(args: argparse.Namespace) -> int:
    import json

    from research.data.generate import HELD_OUT_HANDS, TRAIN_HANDS, DataConfig, generate

    materials = [m for m in args.materials.split(",") if m]
    deformable = [m for m in materials if m in ("cloth", "rope", "plasticine")]
    unknown = sorted(set(materials) - {"rigid", "articulated", *deformable})
    if unknown:
        raise SystemExit(f"--materials: unknown {', '.join(unknown)} (rigid, articulated, cloth, rope, plasticine)")
    if not 0.0 <= args.stiff_ends <= 1.0 or (args.stiff_ends and not args.stiff):
        raise SystemExit(f"--stiff-ends: {args.stiff_ends} must lie in [0, 1] and needs --stiff")
    if args.paired_ends and (not args.stiff or args.stiff_ends or "plasticine" in materials):
        raise SystemExit("--paired-ends: needs --stiff, not --stiff-ends, and cloth or rope only (plasticine has no "
                         "ends)")
    if deformable:
        from research.data.deformable_generate import DeformableDataConfig
        from research.data.deformable_generate import generate as generate_deformable

        dcfg = DeformableDataConfig(materials=tuple(deformable), bodies=args.bodies,
                                    examples_per_body=args.examples_per_body, seed=args.seed,
                                    verify_moving=args.verify_moving, slides=args.slides,
                                    stiff=args.stiff, slide_margin=args.slide_margin,
                                    stiff_ends=args.stiff_ends,
                                    paired_ends=args.paired_ends)  # fmt: skip
        made = generate_deformable(dcfg, args.out, workers=args.workers, progress=not args.no_progress)
        print(json.dumps(made["totals"], indent=1))
    if not {"rigid", "articulated"} & set(materials):
        return 0
    cfg = DataConfig(
        objects=args.objects,
        seed=args.seed,
        objects_per_shard=args.objects_per_shard,
        test_fraction=args.test_fraction,
        articulated_fraction=args.articulated_fraction,
        hands=tuple(args.hands.split(",")) if args.hands else TRAIN_HANDS,
        held_out_hands=tuple(args.held_out_hands.split(",")) if args.held_out_hands is not None else HELD_OUT_HANDS,
        grasps_per_job=args.grasps_per_job,
        examples_per_grasp=args.examples_per_grasp,
        targeted_per_grasp=args.targeted_per_grasp,
        palms=args.palms,
        max_set=args.max_set,
        test_objects_only=args.test_objects_only,
        physics=args.physics,
        closure_mu=args.closure_mu,
    )
    from manifoundation.core.robots import list_hands

    unknown_hands = sorted({h for h in (*cfg.hands, *cfg.held_out_hands) if h} - set(list_hands(aliases=True)))
    if unknown_hands:
        raise SystemExit(f"--hands / --held-out-hands: unknown {', '.join(unknown_hands)} "
                         f"(built-in: {', '.join(list_hands(aliases=True))})")  # fmt: skip
    runner = None
    if args.ray:
        from research.offline.shards import ray_runner

        runner = ray_runner(args.ray, args.workers)
    manifest = generate(cfg, args.out, workers=args.workers, progress=not args.no_progress, runner=runner)
    print(json.dumps(manifest["totals"], indent=1))
    if manifest["lost_shards"]:
        print(f"lost shards (their workers died on every try; rerun to generate them): {manifest['lost_shards']}")
        return 1
    return 0


def _labels(args: argparse.Namespace) -> int:
    import numpy as np

    from research.data.dataset import example_sets, load_examples
    from research.data.label_density import label_density

    print("| data | split | examples | valid grasps an example | points in the valid region | in its own grasp's "
          "| hit: random point | hit: most-opposed normal | hit: farthest point |")
    print("|---|---|--:|--:|--:|--:|--:|--:|--:|")
    for d in args.data:
        for split in args.splits.split(","):
            try:
                ex = load_examples(d, (split,))
            except ValueError:
                continue
            pick = np.unique(np.linspace(0, len(ex) - 1, min(args.limit, len(ex))).astype(int))
            rows = []
            for i in pick:
                o = ex.obj_index[i]
                set_heat, _ = example_sets(ex, int(i), slice(None))
                rows.append((ex.points[o], ex.normals[o], ex.motion[i], set_heat, ex.heat[i]))
            r = label_density(rows, args.seed)
            print(f"| {d} | {split} | {r.examples} | {r.set_size:.1f} | {r.coverage:.1%} | {r.own:.1%} | "
                  f"{r.hit_random:.1%} | {r.hit_push:.1%} | {r.hit_far:.1%} |")
    return 0
