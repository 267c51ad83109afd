"""`mani-lab eval network`: the network against random contacts, both refined, on unseen objects and motions.

One command prints the issue's table (`research/evaluation`): per weights and iteration budget, success by the
verification and by the outside audit, median refinement iterations and fallback cases, for network +
refinement and random contacts + refinement on the same cases, seeds and hand; then the network's own figures
(flat heatmaps, top point in a valid contact region, distinct contact sets of K = 8, region mask, inference
p50); with ``--deformables N`` the deformable goals on N unseen-body cases a material (cloth, rope, plasticine:
the network against the paper's random baseline and random points with the target's motion, the same code as
`mani-lab eval deformable`), with ``--figure N`` the paper's property figure. The ``eval`` parser is owned by
`research.commands.evaluate`; it calls :func:`add_network_parser` with its sub-parsers.
"""

from __future__ import annotations

import argparse
from typing import Any


def add_network_parser(eval_subparsers: Any) -> None:
    """Add ``network`` under ``mani-lab eval``."""
    p = eval_subparsers.add_parser("network", help="network + refinement vs random contacts + refinement")
    p.add_argument("--weights", default="manifoundation/core/weights/cpu1k",
                   help="checkpoint directories, comma-separated; DIR@S samples z ~ N(0, S² I) instead of the "
                        "card's prior_scale (the same weights at two scales side by side)")  # fmt: skip
    p.add_argument("--data", default="data/v4", help="generated data directory (its test split)")
    p.add_argument("--split", default="test_uo", help="test_uo: unseen objects and motions; test_so: seen objects")
    p.add_argument("--hand", default="allegro")
    p.add_argument("--cases", type=int, default=20, help="rigid cases labelled with the hand's grasps")
    p.add_argument("--proposals", type=int, default=4, help="proposals per case (network samples / random sets)")
    p.add_argument("--budgets", default="100,10", help="refinement iteration budgets, comma-separated")
    p.add_argument("--samples", type=int, default=8, help="K for the diversity and heatmap figures")
    p.add_argument("--no-audit", action="store_true", help="skip the outside audit of claimed successes")
    p.add_argument("--no-random", action="store_true", help="skip the random-contacts rows (e.g. run separately)")
    p.add_argument("--oracle", action="store_true",
                   help="also the ceiling: each case's own valid grasps as the heatmaps (research.evaluation.oracle)")
    p.add_argument("--resamples", type=int, default=0,
                   help="also judge the top point on the union of the data's valid region and this many "
                        "re-sampled ones per case (a lower bound of its hit on the true valid region)")
    p.add_argument("--resample-seed", type=int, default=7000,
                   help="re-sampling r uses the generator [seed + r, object]")
    p.add_argument("--workers", type=int, default=2, help="processes re-sampling the objects")
    p.add_argument("--deformables", type=int, default=0,
                   help="also the deformable goals: this many unseen-body cases of cloth, rope and plasticine, the "
                        "network (first weights) against the paper's random baseline and random points with the "
                        "target's motion (`mani-lab eval deformable`)")
    p.add_argument("--deformable-data-seed", type=int, default=5,
                   help="seed of the data set whose bodies the deformable cases use (the shipped weights: 5)")
    p.add_argument("--figure", type=int, default=0,
                   help="also the paper's property figure (handkerchief / card, rope / stick) on this many shapes")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--json", default=None, help="write all figures to this JSON file")
    p.add_argument("--no-progress", action="store_true")
    p.set_defaults(func=_run)


def _run(args: argparse.Namespace) -> int:
    import dataclasses
    import json
    import time
    from collections import Counter

    import numpy as np
    import torch

    from manifoundation.core.robots import get_hand
    from research.commands.weights import load_weights
    from research.evaluation.properties import evaluate_properties, judges_top_point
    from research.evaluation.protocol import evaluate
    from research.evaluation.testset import load_cases, motion_kind

    torch.set_num_threads(1)
    t0 = time.perf_counter()
    hand = get_hand(args.hand)
    cases = load_cases(args.data, args.split, args.cases, args.seed, articulated=False, label_hand=args.hand)
    budgets = [int(b) for b in args.budgets.split(",")]
    weights = args.weights.split(",")
    runs: list[dict[str, Any]] = []

    def run(name: str, method: str, predictor: Any, budget: int) -> None:
        r = evaluate(cases, hand, (method,), predictor, args.proposals, args.seed, budget,
                     progress=not args.no_progress, audit=not args.no_audit)[0]  # fmt: skip
        runs.append({"name": name, "budget": budget, **dataclasses.asdict(r)})

    resampled = None
    if args.resamples > 0:
        from research.commands.resampled_regions import resampled_regions

        judged = [i for i, c in enumerate(cases) if judges_top_point(c)]
        found, _ = resampled_regions(args.data, [cases[i] for i in judged], args.hand, args.resamples,
                                     args.resample_seed, args.workers, progress=not args.no_progress)  # fmt: skip
        resampled = dict(zip(judged, found, strict=True))
    props = {}
    for w in weights:
        predictor = load_weights(w)
        for budget in budgets:
            run(f"network ({w})", "network", predictor, budget)
        props[w] = dataclasses.asdict(evaluate_properties(cases, hand, predictor, k=args.samples, seed=args.seed,
                                                          resampled=resampled))  # fmt: skip
    if args.oracle:
        from research.evaluation.oracle import OraclePredictor

        oracle = OraclePredictor(cases)
        for budget in budgets:
            run("valid grasps (oracle)", "network", oracle, budget)
        props["valid grasps (oracle)"] = dataclasses.asdict(
            evaluate_properties(cases, hand, oracle, k=args.samples, seed=args.seed))
    for budget in [] if args.no_random else budgets:
        run("random contacts", "random_contacts", None, budget)
    n = len(cases)
    kinds = ", ".join(f"{v} {k}" for k, v in sorted(Counter(motion_kind(c) for c in cases).items()))
    print(f"{args.hand}, {args.split}: {n} rigid cases ({kinds}) of {len({c.object_id for c in cases})} objects, "
          f"{args.proposals} proposals, seed {args.seed}; success: best proposal verified / confirmed by the audit")
    print("\n| contacts + refinement | budget | success (verification) | success (audit) | median iterations "
          "| fallback cases |\n|---|--:|--:|--:|--:|--:|")  # fmt: skip
    for r in sorted(runs, key=lambda r: (-r["budget"], r["name"])):
        audit = "–" if args.no_audit else f"{r['audited'] / n:.0%} ({r['audited']})"
        print(f"| {r['name']} | {r['budget']} | {r['successes'] / n:.0%} ({r['successes']}/{n}) | {audit} | "
              f"{float(np.median(r['iterations'])) if r['iterations'] else 0:.0f} | {r['fallbacks']} |")  # fmt: skip
    union_head = f"top point in the union of {args.resamples + 1} valid regions (a lower bound) | "
    union_head = union_head if args.resamples else ""
    print(f"\n| weights | flat heatmaps (samples; unmasked cases) | top point in a valid region (unmasked cases) | "
          f"{union_head}distinct sets of K = {args.samples} | contacts inside the mask "
          f"| inference p50 (batch 1, K = 1) |\n|---|--:|--:|{'--:|' if args.resamples else ''}--:|--:|--:|")
    for w, p in props.items():
        union = (f"{p['top_in_union']:.0%} (a random point {p['union_share']:.0%}) | " if args.resamples else "")
        print(f"| {w} | {p['empty_selections']:.0%}; {p['empty_unmasked']:.0%} | "
              f"{p['top_in_region']:.0%} ({p['top_cases']}; a random point {p['region_share']:.0%}) | {union}"
              f"{p['mean_modes']:.2f} | {p['mask_compliance']:.0%} ({p['mask_cases']} masked cases) | "
              f"{p['inference_ms_p50']:.0f} ms |")
    deformables = _deformables(args, weights[0]) if args.deformables or args.figure else None
    if args.json:
        with open(args.json, "w") as fh:
            json.dump({"runs": runs, "properties": props, "args": vars(args) | {"func": None}, "cases": n,
                       "motions": kinds, "deformables": deformables, "seconds": time.perf_counter() - t0}, fh,
                      indent=1)  # fmt: skip
    return 0


def _deformables(args: argparse.Namespace, weights: str) -> dict[str, Any] | None:
    """The deformable rows of the issue's table (`research.commands.eval_deformable.deformable_figures`) for
    ``weights``, with
    `mani-lab eval deformable`'s own options and defaults."""
    from research.commands.eval_deformable import add_deformable, deformable_figures

    cases = max(args.deformables, 1)
    print(f"\ndeformables: {cases} unseen-body case(s) a material, data seed {args.deformable_data_seed}, "
          f"weights {weights}")
    parser = argparse.ArgumentParser(prog="mani-lab eval")
    add_deformable(parser.add_subparsers())
    options = parser.parse_args([
        "deformable", "--splits", "test_uo", "--cases", str(cases), "--weights", weights, "--seed", str(args.seed),
        "--data-seed", str(args.deformable_data_seed), "--figure", str(args.figure),
        *(["--materials", "cloth,rope,plasticine", "--methods", "random_motion,random_target_motion,network"]
          if args.deformables else ["--materials", "cloth,rope", "--methods", "network"]),
        *(["--no-progress"] if args.no_progress else []),
    ])  # fmt: skip
    return deformable_figures(options)
