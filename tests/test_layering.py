"""docs/layering.md: imports run one way. Checked statically (every import statement) and at run time."""

from __future__ import annotations

import ast
import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

# package → top-level modules it must never import (anywhere in its files, lazily or not)
FORBIDDEN: dict[str, set[str]] = {
    "models": {"service", "workers", "clients", "lab", "fastapi", "starlette", "redis", "pydantic_settings", "uvicorn",
               "rich"},
    "clients": {"models", "workers", "service", "lab", "torch", "numba", "fastapi", "uvicorn"},
    "lab": {"service", "workers", "clients", "fastapi", "starlette", "redis", "uvicorn"},
    "service": {
        "models", "lab", "torch", "numba", "pytorch_kinematics", "cvxpy", "clarabel", "fcl", "trimesh", "ompl",
        "mujoco",
    },
    "workers/queue": {"service", "models", "torch"},
    "workers": {"service", "lab"},
}


def _imported_modules(path: Path) -> set[str]:
    tree = ast.parse(path.read_text(), filename=str(path))
    names: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.update(alias.name.split(".")[0] for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names.add(node.module.split(".")[0])
    return names


@pytest.mark.parametrize("package", sorted(FORBIDDEN))
def test_static_imports_respect_layers(package: str) -> None:
    offenders = []
    for path in sorted((ROOT / package).rglob("*.py")):
        bad = _imported_modules(path) & FORBIDDEN[package]
        if bad:
            offenders.append(f"{path.relative_to(ROOT)} imports {sorted(bad)}")
    assert not offenders, "\n".join(offenders)


def _modules_after_import(*modules: str) -> set[str]:
    code = "import json, sys\n" + "".join(f"import {m}\n" for m in modules) + "print(json.dumps(sorted(sys.modules)))"
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, check=True)
    return set(json.loads(out.stdout))


@pytest.mark.parametrize(
    "module",
    [
        "clients",
        "clients.schemas",
        "clients.codec",
        "clients.cli.main",
        "workers.queue",
        "service.app",
        "service.grpc.server",
    ],
)
def test_torch_free_at_run_time(module: str) -> None:
    loaded = _modules_after_import(module)
    heavy = {"torch", "pytorch_kinematics", "cvxpy", "models"} & {m.split(".")[0] for m in loaded}
    assert not heavy, f"importing {module} loaded {sorted(heavy)}"


def test_cli_help_does_not_import_science() -> None:
    code = (
        "import json, sys, contextlib, io\n"
        "from clients.cli.main import build_parser\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        "    build_parser()\n"
        "print(json.dumps(sorted(sys.modules)))"
    )
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, check=True)
    loaded = {m.split(".")[0] for m in json.loads(out.stdout)}
    assert "torch" not in loaded, "building the `mani` parser must not import torch"
