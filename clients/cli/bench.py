"""`mani bench NAME`: the benchmarks of every component, found through the ``mani.bench`` entry points.

Each benchmark module (``lab.bench_refine``, ``service.bench``, ...) has ``register(subparsers)`` and adds
its own sub-parser to the ``bench`` sub-parsers, exactly like the top-level commands.
"""

from __future__ import annotations

import argparse
import sys

from clients.cli import common
from clients.cli.plugins import load_plugins


def register(subparsers: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add ``mani bench`` and one sub-command per installed benchmark."""
    parser = common.command_parser(
        subparsers,
        "bench",
        "Run a benchmark (the names below are the installed ones).",
        "mani bench service --help",
    )
    benches = parser.add_subparsers(dest="bench", metavar="NAME")
    for register_bench in load_plugins("mani.bench").values():
        register_bench(benches)

    def usage(args: argparse.Namespace) -> int:
        parser.print_help(sys.stderr)
        return common.EXIT_USAGE

    parser.set_defaults(func=usage)
