"""`mani-lab train`: train the network from a config file plus ``key=value`` overrides (see research/training)."""

from __future__ import annotations

import argparse
from typing import Any


def register(subparsers: Any) -> None:
    """Add the ``train`` command."""
    p = subparsers.add_parser("train", help="train the contact network")
    p.add_argument("--config", default="research/configs/train_cpu.yaml", help="YAML training config")
    p.add_argument("--resume", action="store_true", help="continue the run in the config's `out` directory")
    p.add_argument(
        "--export",
        default=None,
        help="after training, copy the best checkpoint here (e.g. manifoundation/core/weights/cpu1k)",
    )
    p.add_argument(
        "--export-checkpoint",
        choices=("best", "last"),
        default="best",
        help="which checkpoint --export copies: lowest validation loss (default) or the last epoch",
    )
    p.add_argument("--no-progress", action="store_true")
    p.add_argument("overrides", nargs="*", help="key=value settings overriding the config file")
    p.set_defaults(func=_train)


def _train(args: argparse.Namespace) -> int:
    import json
    import shutil
    from pathlib import Path

    from research.training.config import load_config
    from research.training.trainer import train

    cfg = load_config(args.config, args.overrides)
    result = train(cfg, resume=args.resume, progress=not args.no_progress)
    print(
        json.dumps(
            {
                "out": str(result.out),
                "epochs": result.epochs,
                "wall_seconds": round(result.wall_seconds, 1),
                "best_val": result.best_val,
                **result.final,
            },
            indent=1,
        )
    )
    if args.export:
        dst = Path(args.export)
        dst.mkdir(parents=True, exist_ok=True)
        src = result.out / args.export_checkpoint
        for name in ("model.safetensors", "model_card.json"):
            shutil.copy2(src / name, dst / name)
        for name in ("metrics.csv", "curves.png"):  # the run's curves travel with the weights
            shutil.copy2(result.out / name, dst / name)
        print(f"exported {src} -> {dst}")
    return 0
