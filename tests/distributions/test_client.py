"""The two distributions of this repository agree: one version, one copy of the client packages
(`manifoundation.contract`, `.sdk`, `.cli`), and the client distribution declares every library they import
(distributions/client/pyproject.toml)."""

from __future__ import annotations

import ast
import re
import sys
import tomllib
from importlib.metadata import packages_distributions
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
CLIENT = tomllib.loads((ROOT / "distributions" / "client" / "pyproject.toml").read_text())["project"]
SERVER = tomllib.loads((ROOT / "pyproject.toml").read_text())
CLIENT_COMMANDS = {"synthesize", "batch", "jobs", "robots"}
CLIENT_PACKAGES = ("manifoundation/contract", "manifoundation/sdk", "manifoundation/cli")
VIA = {"pydantic-core": "pydantic"}
"""Libraries the client packages import that come with a declared one (pydantic pins its core exactly)."""


def _name(requirement: str) -> str:
    """The distribution a requirement names, normalised (``grpcio>=1`` → ``grpcio``)."""
    return re.split(r"[\s\[<>=!~;@]", requirement, maxsplit=1)[0].lower().replace("_", "-")


def test_one_version_and_the_server_requires_exactly_it() -> None:
    assert CLIENT["version"] == SERVER["project"]["version"]
    pins = [r for r in SERVER["project"]["dependencies"] if _name(r) == CLIENT["name"]]
    assert pins == [f"{CLIENT['name']}[grpc,view,mesh]=={CLIENT['version']}"]


def test_the_client_packages_ship_once() -> None:
    server_packages = SERVER["tool"]["setuptools"]["packages"]["find"]["include"]
    assert server_packages == ["manifoundation.core*", "manifoundation.server*"]
    assert "scripts" not in SERVER["project"]  # `mani` is the client distribution's
    assert CLIENT["scripts"] == {"mani": "manifoundation.cli.main:main"}


def test_each_command_is_registered_by_the_distribution_that_ships_its_module() -> None:
    client = CLIENT["entry-points"]["mani.commands"]
    server = SERVER["project"]["entry-points"]["mani.commands"]
    assert set(client) == CLIENT_COMMANDS and not set(client) & set(server)
    for name, target in client.items():
        module = ROOT.joinpath(*target.partition(":")[0].split("."))
        assert target.startswith("manifoundation.cli.") and module.with_suffix(".py").is_file(), f"{name}: {target}"


def _third_party_imports() -> dict[str, set[str]]:
    """Top-level module → the client packages' files that import it (stdlib and `manifoundation` left out)."""
    found: dict[str, set[str]] = {}
    paths = [path for package in CLIENT_PACKAGES for path in (ROOT / package).rglob("*.py")]
    assert len(paths) > 40, "the client packages were not found"
    for path in paths:
        for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
            names = []
            if isinstance(node, ast.Import):
                names = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                names = [node.module]
            for name in names:
                top = name.partition(".")[0]
                if top not in sys.stdlib_module_names and top not in ("manifoundation", "__future__"):
                    found.setdefault(top, set()).add(str(path.relative_to(ROOT)))
    return found


def test_every_library_the_client_imports_is_a_dependency_of_the_client_distribution() -> None:
    declared = {_name(r) for r in CLIENT["dependencies"]}
    for requirements in CLIENT["optional-dependencies"].values():
        declared |= {_name(r) for r in requirements}
    providers = packages_distributions()  # top-level module → the installed distributions that provide it
    undeclared = {}
    for module, files in _third_party_imports().items():
        names = {VIA.get(_name(d), _name(d)) for d in providers.get(module, [module])}
        if not names & declared:
            undeclared[module] = sorted(files)
    assert not undeclared, (
        f"imported by the client packages but not declared in distributions/client: {undeclared}"
    )
