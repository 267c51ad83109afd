"""`manifoundation.core.deformable` sits between `manifoundation.core.refine` and `manifoundation.core.pipeline` in the
science's stack: it may import
numpy, scipy, matplotlib, mujoco and the subpackages below it, never the pipeline, data, training, evaluation or
command line (those import it)."""

from __future__ import annotations

import ast
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[3] / "models" / "deformable"
ABOVE = {"pipeline", "data", "training", "evaluation", "cli"}


def test_deformable_imports_only_downwards() -> None:
    offenders = []
    for path in sorted(PACKAGE.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            names = [a.name for a in node.names] if isinstance(node, ast.Import) else (
                [node.module] if isinstance(node, ast.ImportFrom) and node.module and node.level == 0 else [])
            for name in names:
                parts = name.split(".")
                if parts[0] == "models" and len(parts) > 1 and parts[1] in ABOVE:
                    offenders.append(f"{path.name} imports {name}")
    assert not offenders, offenders
