"""`mani-lab bench NAME`: the benchmarks of every component, found through the ``mani_lab.bench`` entry points.

Each benchmark module (``research.commands.bench_refine``, ``research.bench.service``, ...) has ``register(subparsers)``
and adds its own sub-parser to the ``bench`` sub-parsers, exactly like the top-level commands.
"""

from __future__ import annotations

import argparse
import sys

from manifoundation.cli import common
from manifoundation.cli.plugins import load_plugins


def register(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add ``mani_lab.bench`` and one sub-command per installed benchmark."""
    parser = common.command_parser(
        subparsers,
        "bench",
        "Run a benchmark (the names below are the installed ones).",
        "mani-lab bench service --help",
    )
    benches = parser.add_subparsers(dest="bench", metavar="NAME")
    for register_bench in load_plugins("mani_lab.bench").values():
        register_bench(benches)

    def usage(args: argparse.Namespace) -> int:
        parser.print_help(sys.stderr)
        return common.EXIT_USAGE

    parser.set_defaults(func=usage)
