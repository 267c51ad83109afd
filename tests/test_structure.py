"""The tree's shape (docs/layering.md): no import circle, the science's subpackages in one stated order, small
modules. Read statically from every import statement, lazy ones (inside functions) included: an import moved into
a function to dodge a circle is still a circle."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("manifoundation", "research")

CORE_ORDER = (
    "errors", "objects", "robots", "geometry", "physics", "network", "refine", "compiled", "deformable", "pipeline",
    "planning", "weights",
)  # fmt: skip
"""Bottom to top: a subpackage of `manifoundation.core` imports only from those before it (and itself)."""
RESEARCH_ORDER = (
    "audit", "hostile_archives", "staged_pipeline", "data", "offline", "training", "evaluation", "commands", "bench",
    "benchmarks", "cli",
)  # fmt: skip
"""The same for `research`. ``audit`` imports nothing of the science: it is the outside check and shares no code
with what it checks."""
MAX_LINES = 300
REASON = "Why one module:"
GENERATED = ("_pb2.py", "_pb2_grpc.py")
"""protoc's output (`manifoundation/contract/protos/manifoundation`): regenerated, never edited, so no size rule (ruff
and mypy
skip it too)."""


def _modules() -> dict[str, Path]:
    found = {}
    for package in PACKAGES:
        for path in (ROOT / package).rglob("*.py"):
            name = ".".join(path.relative_to(ROOT).with_suffix("").parts)
            found[name.removesuffix(".__init__")] = path
    return found


def _imports(path: Path, modules: dict[str, Path]) -> set[str]:
    """The product modules ``path`` imports (``from a.b import c`` counts as a.b.c when that is a module)."""
    out: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        targets: list[str] = []
        if isinstance(node, ast.Import):
            targets = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            targets = [node.module, *(f"{node.module}.{alias.name}" for alias in node.names)]
        for target in targets:
            while target and target not in modules:
                target = target.rpartition(".")[0]
            if target:
                out.add(target)
    return out


def _graph() -> dict[str, set[str]]:
    modules = _modules()
    return {name: _imports(path, modules) - {name} for name, path in modules.items()}


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of more than one module (Tarjan, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []
    for root in graph:
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = len(index)
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(graph[child]))))
                elif child in on_stack:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                component = []
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    component.append(member)
                    if member == node:
                        break
                if len(component) > 1:
                    found.append(sorted(component))
    return found


def test_the_cycle_finder_finds_a_cycle() -> None:
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


def test_no_import_circle() -> None:
    assert _cycles(_graph()) == []


@pytest.mark.parametrize(("package", "order"), [("manifoundation.core", CORE_ORDER), ("research", RESEARCH_ORDER)])
def test_subpackages_import_only_downwards(package: str, order: tuple[str, ...]) -> None:
    rank = {name: i for i, name in enumerate(order)}
    depth = package.count(".") + 1
    offenders = []
    for module, imported in _graph().items():
        parts = module.split(".")
        if not module.startswith(package + ".") or len(parts) <= depth:
            continue
        sub = parts[depth]
        assert sub in rank, f"{package}.{sub} has no place in its order (tests/test_structure.py)"
        for target in imported:
            tparts = target.split(".")
            if target.startswith(package + ".") and len(tparts) > depth and rank.get(tparts[depth], -1) > rank[sub]:
                offenders.append(f"{module} imports {target}")
    assert not offenders, "\n".join(sorted(offenders))


def test_audit_shares_no_code_with_the_science() -> None:
    graph = _graph()
    borrowed = sorted(
        f"{m} imports {t}" for m, ts in graph.items() if m.startswith("research.audit") for t in ts
        if t.startswith(("manifoundation.", "research.")) and not t.startswith("research.audit")
    )  # fmt: skip
    assert not borrowed, "\n".join(borrowed)


def test_long_modules_say_why() -> None:
    long = []
    for name, path in _modules().items():
        text = path.read_text()
        if path.name.endswith(GENERATED):
            continue
        if text.count("\n") > MAX_LINES and REASON not in (ast.get_docstring(ast.parse(text)) or ""):
            long.append(f"{name}: {text.count(chr(10))} lines, no '{REASON}' in its docstring")
    assert not long, "\n".join(long)
