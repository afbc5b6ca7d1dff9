"""The validation library's boundaries: it never reads the command line, and its optional modules load lazily."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import mien.validate

PACKAGE = Path(mien.validate.__file__).parent


def test_the_library_never_imports_argparse_or_the_cli() -> None:
    found = []
    for path in sorted(PACKAGE.glob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            names = [a.name for a in node.names] if isinstance(node, ast.Import) else []
            names += [node.module or ""] if isinstance(node, ast.ImportFrom) else []
            found += [f"{path.name}: {n}" for n in names if n == "argparse" or n.startswith("mien.commands")]
    assert found == []


def test_importing_every_module_loads_no_optional_dependency() -> None:
    modules = sorted(f"mien.validate.{path.stem}" for path in PACKAGE.glob("*.py") if path.stem != "__init__")
    optional = ("mediapipe", "ai_edge_litert", "moderngl", "matplotlib", "scipy")
    code = "import sys\n" + "".join(f"import {m}\n" for m in modules)
    code += f"print(sorted(m for m in {optional!r} if m in sys.modules))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"
