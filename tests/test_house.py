"""The house rules a tool can check: no import circles, the library never imports the commands, the project's own
modules imported at the top of a module, modules of at most 500 lines, and the lint exceptions only shrinking."""

from __future__ import annotations

import ast
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "groupfit"

C901_EXCEPTIONS: set[str] = set()
"""Files with a function over ruff's complexity limit (pyproject's per-file-ignores): entries may only leave."""
FBT_EXCEPTIONS: set[str] = set()
"""Library files that may take a boolean positionally (ruff FBT001/FBT002 in pyproject's per-file-ignores): none."""
LONG_MODULES: dict[str, int] = {}
"""Modules over 500 lines and their length today: they may only shrink."""
KNOWN_CIRCLES: set[frozenset[str]] = set()
"""Import circles still in the house: entries may only leave."""
MAX_FUNCTION_LEVEL_OWN_IMPORTS = 0


def module_name(path: Path) -> str:
    parts = path.relative_to(ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


MODULES = {module_name(path): path for path in sorted(PACKAGE.rglob("*.py"))}


def own_imports(name: str) -> list[tuple[str, bool]]:
    """The project's modules ``name`` imports, each with whether the import sits inside a function."""
    path = MODULES[name]
    package = name.split(".") if path.name == "__init__.py" else name.split(".")[:-1]
    found = []

    def visit(node: ast.AST, in_function: bool) -> None:
        for child in ast.iter_child_nodes(node):
            inside = in_function or isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef))
            targets = []
            if isinstance(child, ast.ImportFrom):
                base = child.module or ""
                if child.level:
                    base = ".".join(package[: len(package) - child.level + 1] + ([base] if base else []))
                targets = [base] + [f"{base}.{alias.name}" for alias in child.names]
            elif isinstance(child, ast.Import):
                targets = [alias.name for alias in child.names]
            found.extend((target, inside) for target in targets if target in MODULES and target != name)
            visit(child, inside)

    visit(ast.parse(path.read_text(encoding="utf-8")), False)
    return found


GRAPH = {name: {target for target, _ in own_imports(name)} for name in MODULES}


def circles() -> set[frozenset[str]]:
    """Strongly connected groups of modules (Tarjan), a package's edges to its own modules left out."""
    edges = {
        a: {b for b in targets if not (b.startswith(a + ".") or a.startswith(b + "."))} for a, targets in GRAPH.items()
    }
    index, low, stack, on_stack, found = {}, {}, [], set(), set()

    def strong(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in edges[v]:
            if w not in index:
                strong(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            group = set()
            while True:
                w = stack.pop()
                on_stack.discard(w)
                group.add(w)
                if w == v:
                    break
            if len(group) > 1:
                found.add(frozenset(group))

    for v in edges:
        if v not in index:
            strong(v)
    return found


def test_the_import_graph_finds_a_circle_it_is_shown():
    assert {"groupfit.heldout.scorer", "groupfit.heldout.folds"} <= GRAPH["groupfit.heldout.check"]
    assert "groupfit.errors" in GRAPH["groupfit.cli"]


def test_no_import_circle_beyond_the_known_ones():
    assert circles() <= KNOWN_CIRCLES


def test_the_library_never_imports_the_commands():
    library = [
        name for name in MODULES if not name.startswith(("groupfit.commands", "groupfit.cli", "groupfit.__main__"))
    ]
    offenders = {
        name: sorted(t for t in GRAPH[name] if t.startswith(("groupfit.commands", "groupfit.cli"))) for name in library
    }
    assert not any(offenders.values()), offenders


def test_own_modules_are_imported_at_the_top():
    inside = [(name, target) for name in MODULES for target, in_function in own_imports(name) if in_function]
    assert len(inside) <= MAX_FUNCTION_LEVEL_OWN_IMPORTS, inside


@pytest.mark.parametrize("name", sorted(MODULES))
def test_a_module_holds_at_most_500_lines(name):
    relative = str(MODULES[name].relative_to(ROOT))
    lines = len(MODULES[name].read_text(encoding="utf-8").splitlines())
    assert lines <= LONG_MODULES.get(relative, 500), f"{relative}: {lines} lines"


def test_lint_exceptions_only_shrink():
    ignores = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["ruff"]["lint"]["per-file-ignores"]
    assert {path for path, rules in ignores.items() if "C901" in rules} <= C901_EXCEPTIONS
    library = {path for path in ignores if not path.startswith(("tests/", "bench/"))}
    assert {path for path in library if "FBT001" in ignores[path] or "FBT002" in ignores[path]} <= FBT_EXCEPTIONS
    settings = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["ruff"]["lint"]
    assert settings["mccabe"]["max-complexity"] <= 15 and {"C901", "PLC0415", "FBT001", "FBT002"} <= set(
        settings["select"]
    )
