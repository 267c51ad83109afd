"""`mani-lab eval labels`: the network's top point against valid regions re-sampled independently of each case.

Each unmasked rigid case of ``--data``'s split is judged on the data's own valid region and on ``--resamples``
regions from new samplings of its object (`research.evaluation.label_agreement`): the table gives each source's
coverage (a random point's hit), the network's top-point hit, the same for their union, and how far the label
sources agree with one another. The ``eval`` parser is owned by `research.commands.evaluate`.
"""

from __future__ import annotations

import argparse
from typing import Any


def add_labels_parser(eval_subparsers: Any) -> None:
    """Add ``labels`` under ``mani-lab eval``."""
    p = eval_subparsers.add_parser("labels", help="top point against independently re-sampled valid regions")
    p.add_argument("--data", default="data/d6-test", help="generated data directory (its test split)")
    p.add_argument("--split", default="test_uo")
    p.add_argument("--hand", default="allegro", help="the hand whose grasps label the cases and are re-sampled")
    p.add_argument("--weights", default="manifoundation/core/weights/cpu1k",
                   help="checkpoint directories, comma-separated (DIR@S: at prior scale S)")  # fmt: skip
    p.add_argument("--cases", type=int, default=10_000, help="at most this many cases (unmasked ones are kept)")
    p.add_argument("--resamples", type=int, default=3, help="independent samplings of each object's grasps")
    p.add_argument("--resample-seed", type=int, default=7000, help="sampling r uses the generator [seed + r, object]")
    p.add_argument("--samples", type=int, default=8, help="network samples K per case")
    p.add_argument("--workers", type=int, default=2, help="processes re-sampling the objects")
    p.add_argument("--seed", type=int, default=0)
    p.set_defaults(func=_run)


def _run(args: argparse.Namespace) -> int:
    import numpy as np
    import torch
    from tqdm import tqdm

    from manifoundation.core.robots import get_hand
    from research.commands.resampled_regions import resampled_regions
    from research.commands.weights import load_weights
    from research.evaluation.label_agreement import label_agreement
    from research.evaluation.properties import _inputs, judges_top_point
    from research.evaluation.testset import data_config, load_cases

    torch.set_num_threads(1)
    cfg, hand = data_config(args.data), get_hand(args.hand)
    cases = [c for c in load_cases(args.data, args.split, args.cases, args.seed, articulated=False,
                                   label_hand=args.hand) if judges_top_point(c)]  # fmt: skip
    objects = sorted({c.object_index for c in cases})
    regions, counts = resampled_regions(args.data, cases, args.hand, args.resamples, args.resample_seed,
                                        args.workers)  # fmt: skip
    weights = args.weights.split(",")
    predictors = [load_weights(w) for w in weights]
    tops: list[list[np.ndarray]] = [[] for _ in weights]
    for n, case in enumerate(tqdm(cases, desc="cases")):
        inputs = [_inputs(case, hand)]
        for w, predictor in enumerate(predictors):
            out = predictor.predict(inputs, num_samples=args.samples, seed=args.seed + n)[0]
            tops[w].append(out.heatmaps.argmax(axis=1))
    reports = [label_agreement(regions, t) for t in tops]
    report = reports[0]
    print(f"{args.hand}, {args.split}: {report.cases} unmasked rigid cases of {len(objects)} objects; "
          f"{args.resamples} re-samplings of each object ({cfg.palms} palms, {cfg.grasps_per_job} grasps); "
          f"K = {args.samples}")
    own = np.mean([np.isfinite(c.grasp_contacts[:, 0, 0]).sum() for c in cases if c.grasp_contacts is not None])
    print(f"valid grasps a case: the data's {own:.1f}, a re-sampling's {np.mean(counts):.1f}")
    heads = " | ".join(f"top point: {w}" for w in weights)
    rule = "--:|" * len(weights)
    print(f"\n| valid region | points it marks (a random point's hit) | {heads} |\n|---|--:|{rule}")
    names = ["the data's (its own sampling run)"] + [f"re-sampling {r + 1}" for r in range(args.resamples)]
    for k, (name, cov) in enumerate(zip(names, report.coverage, strict=True)):
        print(f"| {name} | {cov:.1%} | " + " | ".join(f"{r.top_hit[k]:.1%}" for r in reports) + " |")
    print(f"| union of the {report.sources} | {report.union_coverage:.1%} | "
          + " | ".join(f"{r.union_top_hit:.1%}" for r in reports) + " |")  # fmt: skip
    print(f"\n| label sources in the union (the data's first) | points it marks | {heads} |\n|--:|--:|{rule}")
    for k, cov in enumerate(report.denser_coverage):
        print(f"| {k + 1} | {cov:.1%} | " + " | ".join(f"{r.denser_top_hit[k]:.1%}" for r in reports) + " |")
    print(f"\nlabel sources against each other: a point of one region in another {report.oracle_pair:.1%}; "
          f"the point most of the others mark in the held-out one {report.oracle_held_out:.1%}")
    return 0
