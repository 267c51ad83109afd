"""The audit shares no code with the service: it imports nothing from other ``models.*`` packages."""

from __future__ import annotations

import ast
import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[3]
AUDIT = ROOT / "models" / "audit"
ALLOWED_THIRD_PARTY = {"numpy", "scipy", "torch", "pytorch_kinematics", "trimesh", "fcl", "mujoco", "lxml", "xml"}


def test_fresh_interpreter_imports_no_service_module() -> None:
    code = "import json, sys\nimport research.audit\nprint(json.dumps(sorted(sys.modules)))"
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, check=True)
    loaded = set(json.loads(out.stdout))
    for banned in (
        "manifoundation.core.refine",
        "manifoundation.core.robots",
        "manifoundation.core.pipeline",
        "manifoundation.core.geometry",
        "research.data",
    ):
        assert banned not in loaded
    foreign = sorted(m for m in loaded if m.startswith("models.") and not m.startswith("research.audit"))
    assert foreign == []
    assert not [m for m in loaded if m.startswith(("manifoundation.server", "manifoundation.contract"))]


def test_every_import_statement_is_allowed() -> None:
    offenders = []
    for path in sorted(AUDIT.glob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
            names: list[str] = []
            if isinstance(node, ast.Import):
                names = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom):
                assert node.level == 0, f"{path.name}: relative import"
                names = [node.module or ""]
            for name in names:
                top = name.split(".")[0]
                ok = name.startswith("research.audit") or top in ALLOWED_THIRD_PARTY or top in sys.stdlib_module_names
                if not ok:
                    offenders.append(f"{path.name} imports {name}")
    assert offenders == []
