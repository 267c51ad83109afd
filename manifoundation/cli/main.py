"""`mani`: the single command-line entry point.

Exit codes: 0 success, 1 the work failed (e.g. a job failed), 2 bad usage or invalid input, 3 the service could
not be reached, 130 interrupted.
"""

from __future__ import annotations

import argparse
import sys

from manifoundation.cli.plugins import load_plugins

EXIT_OK = 0
EXIT_FAILED = 1
EXIT_USAGE = 2
EXIT_UNREACHABLE = 3
EXIT_INTERRUPTED = 130


def plugin_parser(prog: str, description: str, group: str) -> argparse.ArgumentParser:
    """A command line whose subcommands are the ``register`` functions of the entry-point ``group``."""
    epilog = f"Run `{prog} COMMAND --help` for a command's options and an example."
    parser = argparse.ArgumentParser(prog=prog, description=description, epilog=epilog)
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for register in load_plugins(group).values():
        register(sub)
    return parser


def build_parser() -> argparse.ArgumentParser:
    """Build the `mani` parser with every installed subcommand."""
    return plugin_parser("mani", "ManiFoundation Service: contact synthesis for robot manipulation.", "mani.commands")


def main(argv: list[str] | None = None) -> int:
    """Run `mani` with ``argv`` (default: ``sys.argv[1:]``) and return its exit code."""
    return run(build_parser(), argv)


def run(parser: argparse.ArgumentParser, argv: list[str] | None = None) -> int:
    """Parse ``argv`` with ``parser`` and run the chosen command's ``func``; usage (exit 2) without one."""
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
