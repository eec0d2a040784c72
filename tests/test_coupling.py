"""Coupling the build checks (issue 33, docs/architecture.md "Layers"):

- "No module reads another module's private attributes": a name with a leading underscore that a
  file of the package defines (an attribute set on `self`, a method, a class attribute, a module
  global) is used only by that file, through `self`/`cls` or its own objects; no other file reads it
  on an object (also spelt as a string: getattr, setattr, hasattr, delattr) or imports it. Dunder
  names are public protocol.
- "The firmware package has no import cycle through vm.py": the imports a module runs (imports
  under `if TYPE_CHECKING:` excluded, imports inside functions included) form no cycle that passes
  through `opentmcl.firmware.vm`.
"""
from __future__ import annotations

import ast
from collections import defaultdict
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src" / "opentmcl"


def _files() -> list[Path]:
    return sorted(SRC.rglob("*.py"))


def _private(name: str) -> bool:
    return name.startswith("_") and not (name.startswith("__") and name.endswith("__"))


def _defined(tree: ast.AST) -> set[str]:
    """Private names this file defines: attributes assigned anywhere, functions, classes, globals."""
    out: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)) and _private(node.name):
            out.add(node.name)
        elif isinstance(node, ast.Attribute) and isinstance(node.ctx, (ast.Store, ast.Del)) and _private(node.attr):
            out.add(node.attr)
        elif isinstance(node, ast.Name) and isinstance(node.ctx, ast.Store) and _private(node.id):
            out.add(node.id)
        elif isinstance(node, ast.arg) and _private(node.arg):
            out.add(node.arg)
    return out


def _read_elsewhere(tree: ast.AST) -> list[tuple[int, str]]:
    """(line, name) of private attributes read on an object other than self/cls, and private names
    imported from another module."""
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute) and _private(node.attr):
            if not (isinstance(node.value, ast.Name) and node.value.id in ("self", "cls")):
                out.append((node.lineno, node.attr))
        elif isinstance(node, ast.ImportFrom):
            out += [(node.lineno, alias.name) for alias in node.names if _private(alias.name)]
        elif _by_string(node):  # getattr(vm.scheduler, "_limit"): the name spelt as a string
            out.append((node.lineno, node.args[1].value))
    return out


_BY_NAME = ("getattr", "setattr", "hasattr", "delattr")


def _by_string(node: ast.AST) -> bool:
    """getattr/setattr/hasattr/delattr of a private name given as a string on an object other than
    self/cls (what neither mypy nor import-linter sees; issue 33: `_accel.c` looked names up so)."""
    if not (isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id in _BY_NAME
            and len(node.args) >= 2):
        return False
    obj, name = node.args[0], node.args[1]
    return (isinstance(name, ast.Constant) and isinstance(name.value, str) and _private(name.value)
            and not (isinstance(obj, ast.Name) and obj.id in ("self", "cls")))


def test_no_module_reads_another_modules_private_names():
    trees = {path: ast.parse(path.read_text(encoding="utf-8")) for path in _files()}
    owners: dict[str, set[Path]] = defaultdict(set)
    for path, tree in trees.items():
        for name in _defined(tree):
            owners[name].add(path)
    found = []
    for path, tree in trees.items():
        for line, name in _read_elsewhere(tree):
            if owners.get(name) and path not in owners[name]:
                where = ", ".join(str(p.relative_to(SRC)) for p in sorted(owners[name]))
                found.append(f"{path.relative_to(SRC)}:{line} reads {name} of {where}")
    assert not found, "\n".join(found)


def _module_name(path: Path) -> str:
    parts = path.relative_to(SRC.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _runtime_imports(path: Path, tree: ast.Module) -> set[str]:
    """Modules of the package this module imports when it runs (not under TYPE_CHECKING)."""
    module = _module_name(path)
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    out: set[str] = set()

    def visit(node: ast.AST) -> None:
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            for child in node.orelse:
                visit(child)
            return
        if isinstance(node, ast.ImportFrom):
            base = package
            for _ in range(node.level - 1):
                base = base.rpartition(".")[0]
            target = (f"{base}.{node.module}" if node.module else base) if node.level else (node.module or "")
            out.add(target)
            out.update(f"{target}.{alias.name}" for alias in node.names)
        elif isinstance(node, ast.Import):
            out.update(alias.name for alias in node.names)
        for child in ast.iter_child_nodes(node):
            visit(child)
    visit(tree)
    return {name for name in out if name.startswith("opentmcl.")}


def test_the_firmware_has_no_import_cycle_through_vm():
    modules = {_module_name(p): p for p in _files()}
    graph = {name: {m for m in _runtime_imports(p, ast.parse(p.read_text(encoding="utf-8"))) if m in modules}
             for name, p in modules.items()}
    start = "opentmcl.firmware.vm"
    seen, stack = set(), [(start, (start,))]
    cycles = []
    while stack:
        node, path = stack.pop()
        for nxt in graph.get(node, ()):
            if nxt == start:
                cycles.append(" -> ".join((*path, start)))
            elif nxt not in seen and nxt.startswith("opentmcl.firmware"):
                seen.add(nxt)
                stack.append((nxt, (*path, nxt)))
    assert not cycles, "\n".join(cycles)
