"""`mani eval network`: the Table I protocol and the network property checks (see models/evaluation).

The ``eval`` parser is owned by `lab.evaluate`; it calls :func:`add_network_parser` with its
sub-parsers.
"""

from __future__ import annotations

import argparse
from typing import Any


def add_network_parser(eval_subparsers: Any) -> None:
    """Add ``network`` under ``mani eval``."""
    p = eval_subparsers.add_parser("network", help="network + pipeline success (paper Table I) and properties")
    p.add_argument("--weights", default="models/weights/cpu", help="checkpoint directory")
    p.add_argument("--data", default="data/v3", help="generated data directory (test splits)")
    p.add_argument("--splits", default="test_so,test_uo")
    p.add_argument("--hands", default="leap,barrett", help="hands to evaluate (shadow/barrett are held out)")
    p.add_argument("--methods", default="network,network_no_refine,random_contacts,direct_grasp")
    p.add_argument("--cases", type=int, default=20, help="cases per split")
    p.add_argument("--proposals", type=int, default=4, help="K proposals per case (network / random)")
    p.add_argument("--max-iterations", type=int, default=100)
    p.add_argument("--property-cases", type=int, default=10, help="cases for the property checks (0: skip)")
    p.add_argument("--rigid-only", action="store_true", help="leave articulated cases out")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--json", default=None, help="write all figures to this JSON file")
    p.add_argument("--no-progress", action="store_true")
    p.set_defaults(func=_run)


def _run(args: argparse.Namespace) -> int:
    import dataclasses
    import json
    import time

    import torch

    from models.evaluation.properties import evaluate_properties
    from models.evaluation.protocol import evaluate, table
    from models.evaluation.testset import load_cases
    from models.network import ContactPredictor
    from models.robots import get_hand

    torch.set_num_threads(1)
    predictor = ContactPredictor.from_checkpoint(args.weights)
    methods = tuple(args.methods.split(","))
    rows = []
    props: dict[str, Any] = {}
    t0 = time.perf_counter()
    for split in args.splits.split(","):
        cases = load_cases(args.data, split, args.cases, args.seed, articulated=False if args.rigid_only else None)
        for name in args.hands.split(","):
            hand = get_hand(name)
            rows += evaluate(
                cases,
                hand,
                methods,
                predictor,
                args.proposals,
                args.seed,
                args.max_iterations,
                progress=not args.no_progress,
            )
            if args.property_cases:
                rep = evaluate_properties(cases[: args.property_cases], hand, predictor, seed=args.seed)
                props[f"{name}/{split}"] = dataclasses.asdict(rep)
    print(table(rows))
    for key, rep in props.items():
        print(key, json.dumps(rep))
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(
                {
                    "table": [dataclasses.asdict(r) | {"rate": r.rate} for r in rows],
                    "properties": props,
                    "args": vars(args) | {"func": None},
                    "seconds": time.perf_counter() - t0,
                },
                fh,
                indent=1,
            )
    return 0
