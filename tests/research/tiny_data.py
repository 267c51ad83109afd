"""The ``mani`` parser with its ``data`` and ``eval`` commands, and a tiny generated rigid test set for the
evaluation commands' end-to-end tests."""

from __future__ import annotations

import argparse
from pathlib import Path

from research.commands import data, evaluate


def cli() -> argparse.ArgumentParser:
    """A parser with ``mani-lab data`` and ``mani-lab eval`` registered."""
    p = argparse.ArgumentParser()
    sub = p.add_subparsers()
    data.register(sub)
    evaluate.register(sub)
    return p


def tiny_test_set(out: Path) -> Path:
    """Generate 8 objects' test split (Allegro, 8 palms, 6 grasps a job) into ``out``; returns ``out``."""
    gen = cli().parse_args(["data", "generate", "--out", str(out), "--objects", "8", "--seed", "1",
                            "--test-objects-only", "--workers", "1", "--hands", "allegro", "--held-out-hands", "",
                            "--palms", "8", "--grasps-per-job", "6", "--examples-per-grasp", "1",
                            "--no-progress"])  # fmt: skip
    assert gen.func(gen) == 0
    return out
