"""`mani-lab`: the research commands apart from the product's `mani`; `mani --help` lists none of them."""

from __future__ import annotations

import pytest

from manifoundation.cli.main import build_parser as mani_parser
from manifoundation.cli.plugins import load_plugins
from research.cli import EXIT_USAGE, build_parser, main

RESEARCH = {"bench", "data", "eval", "train"}


def test_bench_dispatches_to_installed_benchmarks(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["bench"]) == EXIT_USAGE  # no benchmark named: usage on stderr
    installed = load_plugins("mani_lab.bench")
    assert {"pipeline", "refine", "faults", "service", "queue", "grpc"} <= set(installed)
    with pytest.raises(SystemExit):
        build_parser().parse_args(["bench", "--help"])
    out = capsys.readouterr().out
    assert all(name in out for name in installed)


def test_mani_lists_user_and_operator_commands_and_mani_lab_the_research_ones() -> None:
    lab = set(build_parser()._subparsers._group_actions[0].choices)  # type: ignore[union-attr]
    mani = set(mani_parser()._subparsers._group_actions[0].choices)  # type: ignore[union-attr]
    assert lab == RESEARCH
    assert not mani & RESEARCH and {"serve", "worker", "synthesize", "batch", "robots"} <= mani
