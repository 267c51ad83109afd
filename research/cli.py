"""`mani-lab`: the research commands (data, train, eval, bench), apart from the product's `mani`.

Exit codes as `mani`: 0 success, 1 the work failed, 2 bad usage or invalid input, 130 interrupted.
"""

from __future__ import annotations

import argparse
import sys

from manifoundation.cli.main import EXIT_USAGE, plugin_parser, run

__all__ = ["EXIT_USAGE", "build_parser", "main"]


def build_parser() -> argparse.ArgumentParser:
    """Build the `mani-lab` parser with every installed research command."""
    return plugin_parser(
        "mani-lab", "ManiFoundation research: training data, training, evaluations and benchmarks.", "mani_lab.commands"
    )


def main(argv: list[str] | None = None) -> int:
    """Run `mani-lab` with ``argv`` (default: ``sys.argv[1:]``) and return its exit code."""
    return run(build_parser(), argv)


if __name__ == "__main__":
    sys.exit(main())
