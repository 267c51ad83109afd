"""`mani-lab bench faults` is installed; at tiny sizes (slow) it finds nothing lost, stuck or duplicated."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from research.cli import build_parser


def test_faults_bench_is_a_mani_bench_command() -> None:
    argv = ["bench", "faults", "--jobs", "8", "--bodies", "2", "--only", "full_queue", "--checkouts", "a,b"]
    args = build_parser().parse_args(argv)
    assert (args.jobs, args.bodies, args.kills, args.only) == (8, 2, 4, "full_queue")
    assert (args.checkouts, args.rounds) == ("a,b", 1)


@pytest.mark.slow
def test_faults_bench_at_tiny_sizes(tmp_path: Path) -> None:
    out = tmp_path / "faults.json"
    cmd = [sys.executable, "-m", "research.cli", "bench", "faults", "--jobs", "24", "--kills", "1",
           "--restarts", "1", "--poison-batches", "1", "--bodies", "4", "--body-mb", "1", "--budget", "60",
           "--slow", "3", "--slow-interval", "0.5", "--slow-seconds", "15", "--json", str(out)]  # fmt: skip
    subprocess.run(cmd, check=True, timeout=300, capture_output=True)
    figures = json.loads(out.read_text())
    assert (figures["soak"]["lost"], figures["soak"]["stuck"], figures["soak"]["duplicated"]) == (0, 0, 0)
    assert figures["poison"]["only_poison"] and figures["poison"]["dead_lettered"] == 1
    assert figures["large_bodies"]["answers"] == {"202": 4}
    assert figures["full_queue"]["small_429"] == figures["full_queue"]["large_expect_429"] == 4
    assert figures["slow_headers"]["closed"] == 3
