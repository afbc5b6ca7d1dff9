"""The layering contract: each stage imports only from the stages below it, and no modules import in a circle.

Stages run from the base (files, errors) through the face vocabulary, intent (FACS, emotions, laughter), the
character, the rig, rendering and file formats, to tracking, learning, validation, studies, the servers and
the CLI on top. Every ``import`` counts, including those inside functions: a lazy import that runs back up is
still a dependency. Read from the source with :mod:`ast`, so the test needs no optional dependency.
"""

from __future__ import annotations

import ast
from collections import defaultdict
from pathlib import Path

SRC = Path(__file__).resolve().parents[2] / "src"

LAYERS: tuple[tuple[str, ...], ...] = (
    ("mien.version", "mien.errors", "mien.extras", "mien.paths", "mien.progress", "mien.ports", "mien.fileio",
     "mien.small_matmul", "mien.htmlpage", "mien.stats", "mien.signals"),
    ("mien.facs",),
    ("mien.affect",),
    ("mien.plot",),
    ("mien.laughter",),
    ("mien.speech",),
    ("mien.character",),
    ("mien.rig",),
    ("mien.render",),
    ("mien.exchange",),
    ("mien.tracking",),
    ("mien.learning", "mien.assets", "mien.heads", "mien.capture"),
    ("mien.validate",),
    ("mien.study",),
    ("mien.viewer",),
    ("mien.server",),
    ("mien.client",),
    ("mien.commands",),
    ("mien.cli",),
    ("mien",),
)  # fmt: skip
"""Stages from the base up; a module may import its own stage and those before it."""


def _modules() -> dict[str, tuple[Path, bool]]:
    found = {}
    for path in (SRC / "mien").rglob("*.py"):
        parts = list(path.relative_to(SRC).with_suffix("").parts)
        is_package = parts[-1] == "__init__"
        found[".".join(parts[:-1] if is_package else parts)] = (path, is_package)
    return found


MODULES = _modules()


def _targets(module: str, is_package: bool, node: ast.Import | ast.ImportFrom) -> list[str]:
    if isinstance(node, ast.Import):
        return [alias.name for alias in node.names]
    if node.level:
        base = module.split(".")[: len(module.split(".")) - (0 if is_package else 1) - (node.level - 1)]
        name = ".".join(base + ([node.module] if node.module else []))
    else:
        name = node.module or ""
    return [f"{name}.{alias.name}" if f"{name}.{alias.name}" in MODULES else name for alias in node.names]


def _internal(name: str) -> str | None:
    while name not in MODULES and "." in name:
        name = name.rsplit(".", 1)[0]
    return name if name in MODULES and name.startswith("mien") else None


def import_graph() -> tuple[dict[str, set[str]], int, int]:
    """``(module -> modules it imports, internal imports, those inside functions)``."""
    edges: dict[str, set[str]] = defaultdict(set)
    total = inside = 0
    for module, (path, is_package) in MODULES.items():
        tree = ast.parse(path.read_text(encoding="utf-8"))
        top = {id(node) for statement in tree.body for node in ast.walk(statement)
               if not isinstance(statement, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef)}  # fmt: skip
        for node in ast.walk(tree):
            if not isinstance(node, ast.Import | ast.ImportFrom):
                continue
            for target in {_internal(name) for name in _targets(module, is_package, node)} - {None, module}:
                assert target is not None
                edges[module].add(target)
                total += 1
                inside += id(node) not in top
    return edges, total, inside


def stage(module: str) -> int:
    """The index in :data:`LAYERS` of the longest prefix that owns ``module``."""
    owners = [(len(prefix), index) for index, layer in enumerate(LAYERS) for prefix in layer
              if module == prefix or module.startswith(prefix + ".")]  # fmt: skip
    if not owners:
        raise AssertionError(f"{module} belongs to no stage of LAYERS: add it where its imports put it")
    return max(owners)[1]


def circles(edges: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected groups of more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []

    def visit(node: str) -> None:
        index[node] = low[node] = len(index)
        stack.append(node)
        on_stack.add(node)
        for other in sorted(edges.get(node, ())):
            if other not in index:
                visit(other)
                low[node] = min(low[node], low[other])
            elif other in on_stack:
                low[node] = min(low[node], index[other])
        if low[node] == index[node]:
            group = []
            while True:
                member = stack.pop()
                on_stack.discard(member)
                group.append(member)
                if member == node:
                    break
            if len(group) > 1:
                found.append(sorted(group))

    for node in sorted(MODULES):
        if node not in index:
            visit(node)
    return found


def test_every_module_has_a_stage() -> None:
    for module in MODULES:
        stage(module)


def test_no_import_runs_back_up() -> None:
    edges, _, _ = import_graph()
    back = sorted(f"{a} -> {b}" for a, targets in edges.items() for b in targets if stage(b) > stage(a))
    assert back == []


def test_no_import_circles() -> None:
    edges, _, _ = import_graph()
    assert circles(edges) == []


def test_the_package_root_is_imported_by_no_module() -> None:
    """``mien/__init__`` is the public face; modules import the home of each name instead."""
    edges, _, _ = import_graph()
    assert sorted(a for a, targets in edges.items() if "mien" in targets) == []
