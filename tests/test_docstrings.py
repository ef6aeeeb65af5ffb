"""Numpydoc ``Parameters`` sections on the public functions of ``estimation``, ``sensor``, ``camera`` and ``core``.

Every public function or method (name without a leading underscore, in a public class or at module level) that
takes an argument has a ``Parameters`` section. The functions that still lack one are listed in
``tests/docstrings_missing.txt``: a new function without one fails this test, and so does a listed function that
has gained one (strike it from the list), so the list only shrinks.
"""

from __future__ import annotations

import ast
from pathlib import Path

import wbsa

PACKAGES = ("estimation", "sensor", "camera", "core")
MISSING_LIST = Path(__file__).with_name("docstrings_missing.txt")


def public_functions_lacking_parameters() -> set[str]:
    """``package/module.py:Class.function`` of every public function with arguments and no Parameters section."""
    root = Path(wbsa.__file__).parent
    lacking = set()

    def visit(body, path: str, prefix: str) -> None:
        for node in body:
            if isinstance(node, ast.ClassDef) and not node.name.startswith("_"):
                visit(node.body, path, f"{prefix}{node.name}.")
            elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and not node.name.startswith("_"):
                if any(isinstance(d, ast.Name) and d.id == "property" for d in node.decorator_list):
                    continue
                a = node.args
                names = [x.arg for x in a.posonlyargs + a.args + a.kwonlyargs if x.arg not in ("self", "cls")]
                names += [x.arg for x in (a.vararg, a.kwarg) if x is not None]
                if names and "Parameters\n----------" not in (ast.get_docstring(node) or ""):
                    lacking.add(f"{path}:{prefix}{node.name}")

    for package in PACKAGES:
        for file in sorted((root / package).rglob("*.py")):
            visit(ast.parse(file.read_text()).body, file.relative_to(root).as_posix(), "")
    return lacking


def test_public_functions_have_numpydoc_parameters():
    lines = MISSING_LIST.read_text().splitlines()
    listed = {line.strip() for line in lines if line.strip() and not line.startswith("#")}
    lacking = public_functions_lacking_parameters()
    new = sorted(lacking - listed)
    assert not new, "public functions without a numpydoc Parameters section:\n" + "\n".join(new)
    fixed = sorted(listed - lacking)
    assert not fixed, "these now have a Parameters section (or are gone); strike them from " + MISSING_LIST.name + \
        ":\n" + "\n".join(fixed)
