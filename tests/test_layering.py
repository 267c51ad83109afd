"""docs/layering.md: imports run one way. Checked statically (every import statement) and at run time."""

from __future__ import annotations

import ast
import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

# folder → module prefixes its files must never import (anywhere in its files, lazily or not)
SCIENCE_LIBS = {"torch", "numba", "pytorch_kinematics", "cvxpy", "clarabel", "fcl", "trimesh", "ompl", "mujoco"}
WEB = {"fastapi", "starlette", "redis", "pydantic_settings", "uvicorn"}
CLIENT = {"manifoundation.contract", "manifoundation.sdk", "manifoundation.cli"}
SERVER = {"manifoundation.server"}
FORBIDDEN: dict[str, set[str]] = {
    "manifoundation": {"research"},
    "manifoundation/core": SERVER | CLIENT | WEB | {"research", "rich"},
    "manifoundation/contract": {"manifoundation.core", "manifoundation.sdk", "manifoundation.cli", "torch", "numba",
                                "fastapi", "uvicorn"} | SERVER,
    "manifoundation/sdk": {"manifoundation.core", "manifoundation.cli", "torch", "numba", "fastapi",
                           "uvicorn"} | SERVER,
    "manifoundation/cli": {"manifoundation.core", "torch", "numba", "fastapi", "uvicorn"} | SERVER,
    "manifoundation/server/api": SCIENCE_LIBS | {"manifoundation.core", "ray"},
    "manifoundation/server/offline": {"manifoundation.server.api"},
    "manifoundation/server/queue": {"manifoundation.server.api", "manifoundation.core", "torch"},
    "manifoundation/server/worker": {"manifoundation.server.api"},
    "manifoundation/server/commands": {"manifoundation.server.api"},
    "research/data": SERVER | CLIENT | WEB,
    "research/training": SERVER | CLIENT | WEB,
    "research/evaluation": SERVER | CLIENT | WEB,
    "research/audit": SERVER | CLIENT | WEB,
}
"""The served code (everything under `manifoundation`) never imports `research`; the science never the server, the
client or web frameworks; the client parts never the server or the science; the API never the science."""


def _imported_modules(path: Path) -> set[str]:
    tree = ast.parse(path.read_text(), filename=str(path))
    names: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names.add(node.module)
            names.update(f"{node.module}.{alias.name}" for alias in node.names)
    return names


def _banned(name: str, banned: set[str]) -> bool:
    return any(name == b or name.startswith(b + ".") for b in banned)


def test_the_rule_matches_prefixes_only() -> None:
    assert _banned("manifoundation.core.robots", {"manifoundation.core"})
    assert not _banned("manifoundation.corevalues", {"manifoundation.core"})


@pytest.mark.parametrize("package", sorted(FORBIDDEN))
def test_static_imports_respect_layers(package: str) -> None:
    offenders = []
    for path in sorted((ROOT / package).rglob("*.py")):
        bad = {name for name in _imported_modules(path) if _banned(name, FORBIDDEN[package])}
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
        "manifoundation.contract",
        "manifoundation.sdk",
        "manifoundation.contract.codec",
        "manifoundation.cli.main",
        "manifoundation.server.queue",
        "manifoundation.server.api.app",
        "manifoundation.server.api.grpc.server",
    ],
)
def test_torch_free_at_run_time(module: str) -> None:
    loaded = _modules_after_import(module)
    banned = {"torch", "pytorch_kinematics", "cvxpy", "manifoundation.core", "research"}
    heavy = {m for m in loaded if _banned(m, banned)}
    assert not heavy, f"importing {module} loaded {sorted(heavy)}"


def test_ray_is_imported_inside_functions_only() -> None:
    """Ray is an optional extra (`manifoundation[ray]`): no module of the product imports it at its top level."""
    offenders = []
    for path in sorted((ROOT / "manifoundation").rglob("*.py")):
        for node in ast.parse(path.read_text(), filename=str(path)).body:
            names = [a.name for a in node.names] if isinstance(node, ast.Import) else []
            names += [node.module or ""] if isinstance(node, ast.ImportFrom) else []
            if any(_banned(name, {"ray"}) for name in names):
                offenders.append(f"{path.relative_to(ROOT)}:{node.lineno}")
    assert not offenders, offenders


@pytest.mark.parametrize("module", ["manifoundation.server.api.app", "manifoundation.server.commands.offline",
                                    "manifoundation.server.offline.batch", "manifoundation.server.offline.ray_pool"])
def test_ray_free_at_run_time(module: str) -> None:
    assert not {m for m in _modules_after_import(module) if _banned(m, {"ray"})}


def test_cli_help_does_not_import_science() -> None:
    code = (
        "import json, sys, contextlib, io\n"
        "from manifoundation.cli.main import build_parser\n"
        "with contextlib.redirect_stdout(io.StringIO()):\n"
        "    build_parser()\n"
        "print(json.dumps(sorted(sys.modules)))"
    )
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, check=True)
    loaded = {m.split(".")[0] for m in json.loads(out.stdout)}
    assert "torch" not in loaded, "building the `mani` parser must not import torch"


def test_a_served_request_imports_nothing_from_research() -> None:
    """The worker's pipeline answers a real request (the shipped network, refinement, verification) in a fresh
    interpreter beside the API's app: nothing under `research` is loaded."""
    code = (
        "import json, sys\n"
        "import numpy as np\n"
        "import manifoundation.server.api.app\n"
        "from manifoundation.contract import SynthesisRequest\n"
        "from manifoundation.server.worker.models_pipeline import ModelsPipeline\n"
        "from manifoundation.server.worker.pipeline import JobInput\n"
        "n = np.random.default_rng(0).normal(size=(256, 3)); n /= np.linalg.norm(n, axis=1, keepdims=True)\n"
        "request = SynthesisRequest.model_validate({'object': {'points': 0.03 * n, 'normals': n},\n"
        "    'task': {'kind': 'force_closure'}, 'robot': {'name': 'panda_gripper'},\n"
        "    'options': {'method': 'network', 'max_iterations': 10}})\n"
        "pipeline = ModelsPipeline(hands=['panda_gripper'])\n"
        "[outcome] = pipeline.run([JobInput(id='r', request=request)], lambda *a: None, lambda job_id: False)\n"
        "assert outcome.proposals, outcome\n"
        "print(json.dumps(sorted(sys.modules)))"
    )
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=240)
    assert out.returncode == 0, out.stderr[-3000:]
    loaded = json.loads(out.stdout.strip().splitlines()[-1])
    assert "manifoundation.core.refine.refine" in loaded, "the request did not reach the science"
    assert not [m for m in loaded if _banned(m, {"research"})]
