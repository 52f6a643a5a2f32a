"""Short functions: no function over 80 lines and no class over 300 in the product code (docstrings included)."""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
FOLDERS = ("optimize", "runs", "studies", "sim", "surrogate", "report", "cli")


def _too_long() -> list[str]:
    found = []
    for path in sorted(p for f in FOLDERS for p in (ROOT / f).rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            length = (getattr(node, "end_lineno", None) or 0) - getattr(node, "lineno", 0) + 1
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef) and length > 80:
                found.append(f"{path.relative_to(ROOT)}:{node.lineno} function {node.name} ({length} lines)")
            elif isinstance(node, ast.ClassDef) and length > 300:
                found.append(f"{path.relative_to(ROOT)}:{node.lineno} class {node.name} ({length} lines)")
    return found


def test_no_function_over_80_lines_and_no_class_over_300():
    assert _too_long() == []
