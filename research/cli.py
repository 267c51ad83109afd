"""`mani-lab`: the research commands (data, train, eval, bench), apart from the product's `mani`.

Exit codes as `mani`: 0 success, 1 the work failed, 2 bad usage or invalid input, 130 interrupted.
"""

from __future__ import annotations

import argparse
import sys

from manifoundation.cli.plugins import load_plugins

EXIT_USAGE = 2
EXIT_INTERRUPTED = 130


def build_parser() -> argparse.ArgumentParser:
    """Build the `mani-lab` parser with every installed research command."""
    parser = argparse.ArgumentParser(
        prog="mani-lab",
        description="ManiFoundation research: training data, training, evaluations and benchmarks.",
        epilog="Run `mani-lab COMMAND --help` for a command's options and an example.",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for register in load_plugins("mani_lab.commands").values():
        register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run `mani-lab` with ``argv`` (default: ``sys.argv[1:]``) and return its exit code."""
    parser = build_parser()
    args = parser.parse_args(argv)
    func = getattr(args, "func", None)
    if func is None:
        parser.print_help()
        return EXIT_USAGE
    try:
        code = func(args)
    except KeyboardInterrupt:
        return EXIT_INTERRUPTED
    return int(code or 0)


if __name__ == "__main__":
    sys.exit(main())
