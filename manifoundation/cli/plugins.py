"""Discovery of `mani` subcommands from entry points.

Subcommands live next to the code they drive (`manifoundation.server.api.cli`, `research.commands.train`, ...). They are
found through the `mani.commands` entry-point group so that the `clients` package never imports server or science code;
a command's module must keep its top level light and import its heavy dependencies when the command runs.
"""

from __future__ import annotations

import argparse
import importlib
from collections.abc import Callable
from importlib.metadata import entry_points

Register = Callable[["argparse._SubParsersAction[argparse.ArgumentParser]"], None]


def load_plugins(group: str) -> dict[str, Register]:
    """Load every `register` function of an entry-point group.

    An entry whose module is not part of this installation (a component not built yet, or an optional part
    left out) is skipped; any other import error is raised, so a broken command is never hidden.

    Args:
        group: entry-point group name, e.g. ``"mani.commands"``.

    Returns:
        Command name → its `register(subparsers)` function, sorted by name.
    """
    found: dict[str, Register] = {}
    for ep in sorted(entry_points(group=group), key=lambda e: e.name):
        module_name, _, attr = ep.value.partition(":")
        try:
            module = importlib.import_module(module_name)
        except ModuleNotFoundError as exc:
            if exc.name is not None and module_name.startswith(exc.name):
                continue
            raise
        found[ep.name] = getattr(module, attr)
    return found
