"""The API process never imports torch or the science (docs/layering.md)."""

from __future__ import annotations

import re
import subprocess
import sys

CODE = """
import sys
import manifoundation.server.api.app, manifoundation.server.api.cli, research.bench.service
from manifoundation.server.api.settings import Settings
manifoundation.server.api.app.create_app(Settings())
heavy = sorted(m for m in sys.modules if m.split(".")[0] in ("torch", "models", "cvxpy", "plotly"))
print(",".join(heavy))
"""


def test_service_imports_no_torch_and_no_models() -> None:
    out = subprocess.run([sys.executable, "-c", CODE], capture_output=True, text=True, timeout=120, check=True)
    assert out.stdout.strip() == "", out.stdout


def test_service_sources_do_not_import_models() -> None:
    from pathlib import Path

    import manifoundation.server.api

    root = Path(manifoundation.server.api.__file__).parent
    pattern = re.compile(r"^\s*(from|import)\s+(torch|models)\b", re.MULTILINE)
    for path in root.rglob("*.py"):
        assert not pattern.search(path.read_text()), path
