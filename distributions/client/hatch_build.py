"""Where the client distribution's files come from: the repository's `clients/` package, two folders up.

The package stays where the rest of the repository imports it from; this hook copies its files into the wheel
and the sdist under ``clients/`` (sources, type stubs, the proto, ``py.typed``; no caches). Built from an sdist,
the files are already beside this hook. An editable install copies nothing: ``dev-mode-dirs`` puts the checkout
on ``sys.path`` instead, so an editable and a wheel install never both provide ``clients``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from hatchling.builders.hooks.plugin.interface import BuildHookInterface

SUFFIXES = {".py", ".pyi", ".proto", ".typed"}
PACKAGE = "clients"


def package_files(source: Path) -> dict[str, str]:
    """Every file of the package under ``source`` that ships: its path → its path inside the archive."""
    files = {}
    for path in sorted(source.rglob("*")):
        if path.is_file() and path.suffix in SUFFIXES and "__pycache__" not in path.parts:
            files[str(path)] = f"{PACKAGE}/{path.relative_to(source).as_posix()}"
    return files


class ClientSources(BuildHookInterface):
    """Add `clients/` to the wheel and the sdist (not to an editable wheel)."""

    def initialize(self, version: str, build_data: dict[str, Any]) -> None:
        if self.target_name == "wheel" and version == "editable":
            return
        root = Path(self.root)
        unpacked = root / PACKAGE
        source = unpacked if unpacked.is_dir() else root.parents[1] / PACKAGE
        if not (source / "__init__.py").is_file():
            raise FileNotFoundError(f"no {PACKAGE} package at {source}")
        build_data["force_include"].update(package_files(source))
