"""The package's layout rules (issue 18, docs/architecture.md), checked on the source.

* no function or method over 60 lines (``def`` to its last line, docstring included);
* no module over 400 lines;
* no library module imports the command line (``tiremodal_cli.cli``; ``__main__`` is the
  command line's entry point for ``python -m tiremodal_cli``);
* no private name (``_x``) imported from another module of the package.

Each rule is checked by walking the syntax tree of every module; the last test shows that
the checks see what they look for (a planted offender is found).
"""

from __future__ import annotations

import ast
from pathlib import Path

PKG = Path(__file__).resolve().parents[1] / "tiremodal_cli"
MAX_FUNCTION_LINES = 60
MAX_MODULE_LINES = 400


def _modules():
    return sorted(p for p in PKG.rglob("*.py") if "__pycache__" not in p.parts)


def long_functions(source: str, limit: int = MAX_FUNCTION_LINES) -> list[tuple[str, int]]:
    """(name, lines) of every function or method of ``source`` longer than ``limit``."""
    return [(node.name, node.end_lineno - node.lineno + 1) for node in ast.walk(ast.parse(source))
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and node.end_lineno - node.lineno + 1 > limit]


def bad_imports(source: str, library: bool) -> list[str]:
    """Imports of ``source`` that break the rules: a private name from another module of the
    package, or (for a library module) the command line."""
    out = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("tiremodal_cli"):
            if library and (node.module == "tiremodal_cli.cli" or node.module.startswith("tiremodal_cli.cli.")):
                out.append(f"from {node.module} import …")
            out += [f"from {node.module} import {a.name}" for a in node.names
                    if a.name.startswith("_") and not a.name.startswith("__")]
        elif isinstance(node, ast.Import) and library:
            out += [a.name for a in node.names if a.name.startswith("tiremodal_cli.cli")]
    return out


def test_no_function_over_60_lines():
    found = {str(p.relative_to(PKG)): long_functions(p.read_text(encoding="utf-8")) for p in _modules()}
    assert {k: v for k, v in found.items() if v} == {}


def test_no_module_over_400_lines():
    sizes = {str(p.relative_to(PKG)): p.read_text(encoding="utf-8").count("\n") for p in _modules()}
    assert {k: n for k, n in sizes.items() if n > MAX_MODULE_LINES} == {}


def test_no_private_name_across_modules_and_no_library_module_imports_the_cli():
    found = {}
    for p in _modules():
        rel = p.relative_to(PKG)
        library = "cli" not in rel.parts and rel.name != "__main__.py"  # ``python -m`` is the command line
        bad = bad_imports(p.read_text(encoding="utf-8"), library)
        if bad:
            found[str(p.relative_to(PKG))] = bad
    assert found == {}


def test_the_checks_find_a_planted_offender():
    long = "def f():\n" + "    x = 1\n" * 60 + "    return x\n"
    assert long_functions(long) == [("f", 62)]
    assert long_functions("def g():\n    return 1\n") == []
    src = "from tiremodal_cli.io.files import _private, public\nfrom tiremodal_cli.cli.options import x\n"
    assert bad_imports(src, library=True) == ["from tiremodal_cli.io.files import _private",
                                              "from tiremodal_cli.cli.options import …"]
    assert bad_imports(src, library=False) == ["from tiremodal_cli.io.files import _private"]
