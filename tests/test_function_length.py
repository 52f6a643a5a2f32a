"""Short functions, classes and files in the product code: no function over 60 lines (its docstring not counted;
blank and comment lines counted), no class over 300 lines and no file over 500 lines."""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
FOLDERS = ("optimize", "runs", "studies", "sim", "surrogate", "report", "cli")
MAX_FUNCTION, MAX_CLASS, MAX_FILE = 60, 300, 500


def product_files() -> list[Path]:
    """Every module of the package: the root's own and those of its subpackages."""
    return sorted([*ROOT.glob("*.py"), *(p for f in FOLDERS for p in (ROOT / f).rglob("*.py"))])


def function_length(node: ast.FunctionDef | ast.AsyncFunctionDef) -> int:
    """Lines of a function from its ``def`` to its last line, its docstring excluded (nested functions count)."""
    length = (node.end_lineno or node.lineno) - node.lineno + 1
    first = node.body[0]
    if isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant) and isinstance(first.value.value, str):
        length -= (first.end_lineno or first.lineno) - first.lineno + 1
    return length


def too_long() -> list[str]:
    found = []
    for path in product_files():
        source = path.read_text()
        name = path.relative_to(ROOT)
        if len(source.splitlines()) > MAX_FILE:
            found.append(f"{name}: file of {len(source.splitlines())} lines")
        for node in ast.walk(ast.parse(source)):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef) and function_length(node) > MAX_FUNCTION:
                found.append(f"{name}:{node.lineno} function {node.name} ({function_length(node)} lines)")
            elif isinstance(node, ast.ClassDef) and (node.end_lineno or 0) - node.lineno + 1 > MAX_CLASS:
                found.append(f"{name}:{node.lineno} class {node.name} ({node.end_lineno - node.lineno + 1} lines)")
    return found


def test_no_long_function_class_or_file():
    assert too_long() == []


def test_a_functions_length_leaves_out_its_docstring_only():
    source = 'def f(x):\n    """Doc.\n\n    More.\n    """\n    # why\n\n    y = (x +\n         1)\n    return y\n'
    assert function_length(ast.parse(source).body[0]) == 6  # def, the comment, the blank line, y's two, return
