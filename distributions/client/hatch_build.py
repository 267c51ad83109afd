"""Where the client distribution's files come from: the repository's `manifoundation/{contract,sdk,cli}`, two
folders up.

The packages stay where the rest of the repository imports them from; this hook copies their files into the wheel
and the sdist under ``manifoundation/`` (sources, type stubs, the proto, ``py.typed``; no caches). `manifoundation`
itself is a namespace package (no ``__init__.py``): the server distribution adds ``manifoundation/core`` and
``manifoundation/server`` beside these. Built from an sdist, the files are already beside this hook. An editable
install copies nothing: ``dev-mode-dirs`` puts the checkout on ``sys.path`` instead.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from hatchling.builders.hooks.plugin.interface import BuildHookInterface

SUFFIXES = {".py", ".pyi", ".proto", ".typed"}
NAMESPACE = "manifoundation"
PACKAGES = ("contract", "sdk", "cli")


def package_files(source: Path, package: str) -> dict[str, str]:
    """Every file of ``package`` under ``source`` that ships: its path → its path inside the archive."""
    files = {}
    for path in sorted(source.rglob("*")):
        if path.is_file() and path.suffix in SUFFIXES and "__pycache__" not in path.parts:
            files[str(path)] = f"{NAMESPACE}/{package}/{path.relative_to(source).as_posix()}"
    return files


class ClientSources(BuildHookInterface):
    """Add `manifoundation/{contract,sdk,cli}` to the wheel and the sdist (not to an editable wheel)."""

    def initialize(self, version: str, build_data: dict[str, Any]) -> None:
        if self.target_name == "wheel" and version == "editable":
            return
        root = Path(self.root)
        unpacked = root / NAMESPACE
        base = unpacked if unpacked.is_dir() else root.parents[1] / NAMESPACE
        for package in PACKAGES:
            source = base / package
            if not (source / "__init__.py").is_file():
                raise FileNotFoundError(f"no {NAMESPACE}.{package} package at {source}")
            build_data["force_include"].update(package_files(source, package))
