"""Coupling the build checks (issue 33, docs/architecture.md "Layers"):

- "No module reads another module's private attributes": a name with a leading underscore that a
  file of the package defines (an attribute set on `self`, a method, a class attribute, a module
  global) is used on an object only where that object is `self`/`cls`, or shown by the same file to
  be of a class of that file that has the name (the class's name itself, a parameter annotated
  with it, a local or `self.attr` bound to an instance of it); also spelt as a string (getattr,
  setattr, hasattr, delattr). No file imports another's private name. A file that has a private
  name of its own gets no licence to read the same spelling on other objects: `vm.scheduler._limit`
  in capture/conform.py is the scheduler's `_limit`, not conform.py's. Dunder names are public
  protocol.
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


def _class_of_annotation(node: ast.expr | None, classes: dict[str, ast.ClassDef]) -> str | None:
    """The class of this file an annotation names (`Proxy` or "Proxy"), else None."""
    if isinstance(node, ast.Name) and node.id in classes:
        return node.id
    if isinstance(node, ast.Constant) and isinstance(node.value, str) and node.value in classes:
        return node.value
    return None


class _Receivers:
    """The class of the object an attribute is read on, where this file alone shows it: `self`/`cls`;
    the name of a class of this file; a parameter annotated with one; a local bound to `C(...)`,
    `C.__new__(...)`, `cls(...)` or a call of a method annotated to return one on an object so
    shown; `self.attr` bound so in a method of the same class (or annotated so in its body).
    Anything else: unknown."""

    def __init__(self, tree: ast.AST) -> None:
        self.classes = {n.name: n for n in ast.walk(tree) if isinstance(n, ast.ClassDef)}
        self.attrs: dict[str, dict[str, str | None]] = {name: {} for name in self.classes}
        for _ in range(2):  # `self.a = self.b.c()`: what the first round found types the second
            for name, cls in self.classes.items():
                self._bind_attributes(name, cls)

    def members(self, name: str) -> set[str]:
        """Names class `name` defines (methods, class attributes, `self.x` set in its methods), with
        those of its bases in this file."""
        cls, out = self.classes[name], set()
        for node in _walk_class(cls):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                out.add(node.name)
            elif isinstance(node, ast.Attribute) and isinstance(node.ctx, ast.Store) and _is_self(node.value):
                out.add(node.attr)
        for stmt in cls.body:
            targets = stmt.targets if isinstance(stmt, ast.Assign) else [stmt.target] if isinstance(stmt, ast.AnnAssign) else []
            out.update(t.id for t in targets if isinstance(t, ast.Name))
        for base in cls.bases:
            if isinstance(base, ast.Name) and base.id in self.classes and base.id != name:
                out |= self.members(base.id)
        return out

    def scope(self, func: ast.FunctionDef | ast.AsyncFunctionDef, owner: str | None, outer: dict[str, str]) -> dict[str, str]:
        """Locals of `func` whose class is known: its annotated parameters, and names every binding of
        which gives the same class (a name bound otherwise as well, by a for, a with, ..., is unknown)."""
        bound: dict[str, set[str | None]] = defaultdict(set)
        args = func.args
        for arg in (*args.posonlyargs, *args.args, *args.kwonlyargs, args.vararg, args.kwarg):
            if arg is not None:
                bound[arg.arg].add(None if arg is args.vararg or arg is args.kwarg
                                   else _class_of_annotation(arg.annotation, self.classes))
        typed: set[int] = set()
        for node in ast.walk(func):
            if isinstance(node, ast.Assign) and len(node.targets) == 1 and isinstance(node.targets[0], ast.Name):
                bound[node.targets[0].id].add(self.class_of(node.value, owner, outer))
                typed.add(id(node.targets[0]))
            elif isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Name):
                bound[node.target.id].add(_class_of_annotation(node.annotation, self.classes))
                typed.add(id(node.target))
        for node in ast.walk(func):
            if isinstance(node, ast.Name) and isinstance(node.ctx, ast.Store) and id(node) not in typed:
                bound[node.id].add(None)
        env = {k: v for k, v in outer.items() if k not in bound}
        env.update({k: next(iter(v)) for k, v in bound.items() if len(v) == 1 and None not in v})
        return env

    def class_of(self, node: ast.expr, owner: str | None, env: dict[str, str]) -> str | None:
        """The class of this file `node` evaluates to an instance of (or is, for a class name)."""
        if isinstance(node, ast.Name):
            if node.id in ("self", "cls") and owner:
                return owner
            return env.get(node.id) or (node.id if node.id in self.classes else None)
        if isinstance(node, ast.Attribute) and _is_self(node.value) and owner:
            return self.attrs[owner].get(node.attr)
        if isinstance(node, ast.Call):
            f = node.func
            if isinstance(f, ast.Name) and (f.id in self.classes or f.id == "cls"):
                return owner if f.id == "cls" else f.id
            if isinstance(f, ast.Attribute) and f.attr == "__new__" and isinstance(f.value, ast.Name):
                return f.value.id if f.value.id in self.classes else None
            if isinstance(f, ast.Attribute):
                cls = self.class_of(f.value, owner, env)
                return self._returns(cls, f.attr) if cls else None
        return None

    def _returns(self, name: str, method: str) -> str | None:
        """The class of this file that method `method` of class `name` (or of a base in this file)
        is annotated to return."""
        cls = self.classes[name]
        for node in cls.body:
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and node.name == method:
                return _class_of_annotation(node.returns, self.classes)
        for base in cls.bases:
            if isinstance(base, ast.Name) and base.id in self.classes and base.id != name:
                return self._returns(base.id, method)
        return None

    def _bind_attributes(self, name: str, cls: ast.ClassDef) -> None:
        types = self.attrs[name]
        for stmt in cls.body:
            if isinstance(stmt, ast.AnnAssign) and isinstance(stmt.target, ast.Name):
                types[stmt.target.id] = _class_of_annotation(stmt.annotation, self.classes)
        for func in cls.body:
            if not isinstance(func, (ast.FunctionDef, ast.AsyncFunctionDef)):
                continue
            env = self.scope(func, name, {})
            for node in ast.walk(func):
                if isinstance(node, ast.AnnAssign) and isinstance(node.target, ast.Attribute) and _is_self(node.target.value):
                    types[node.target.attr] = _class_of_annotation(node.annotation, self.classes)
                elif isinstance(node, ast.Assign):
                    for target in node.targets:
                        if isinstance(target, ast.Attribute) and _is_self(target.value):
                            cls_of = self.class_of(node.value, name, env)
                            if target.attr in types and types[target.attr] != cls_of:
                                cls_of = None  # bound to different things: unknown
                            types[target.attr] = cls_of


def _walk_class(cls: ast.ClassDef):
    """The nodes of a class's body, not those of the classes nested in it (they have their own)."""
    stack = list(cls.body)
    while stack:
        node = stack.pop()
        yield node
        if not isinstance(node, ast.ClassDef):
            stack.extend(ast.iter_child_nodes(node))


def _is_self(node: ast.expr) -> bool:
    return isinstance(node, ast.Name) and node.id in ("self", "cls")


def _read_elsewhere(tree: ast.AST) -> list[tuple[int, str, str]]:
    """(line, name, receiver) of private attributes used on an object that is not shown to be of a
    class of this file that has them (a private name is its class's own: `vm.scheduler._limit` is
    not conform.py's `_limit` because conform.py has a `_limit` too), and of private names imported
    from another module (receiver "import")."""
    rec = _Receivers(tree)
    out: list[tuple[int, str, str]] = []

    def check(node: ast.AST, receiver: ast.expr, name: str, owner: str | None, env: dict[str, str]) -> None:
        cls = rec.class_of(receiver, owner, env)
        if _is_self(receiver) or (cls is not None and name in rec.members(cls)):
            return
        out.append((node.lineno, name, ast.unparse(receiver)))

    def visit(node: ast.AST, owner: str | None, env: dict[str, str]) -> None:
        if isinstance(node, ast.ClassDef):
            owner, env = node.name, {}
        elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            env = rec.scope(node, owner, env)
        if isinstance(node, ast.Attribute) and _private(node.attr):
            check(node, node.value, node.attr, owner, env)
        elif isinstance(node, ast.ImportFrom):
            out.extend((node.lineno, alias.name, "import") for alias in node.names if _private(alias.name))
        elif _by_string(node):  # getattr(vm.scheduler, "_limit"): the name spelt as a string
            assert isinstance(node, ast.Call)
            check(node, node.args[0], node.args[1].value, owner, env)
        for child in ast.iter_child_nodes(node):
            visit(child, owner, env)

    visit(tree, None, {})
    return out


_BY_NAME = ("getattr", "setattr", "hasattr", "delattr")


def _by_string(node: ast.AST) -> bool:
    """getattr/setattr/hasattr/delattr of a private name given as a string (what neither mypy nor
    import-linter sees; issue 33: `_accel.c` looked names up so)."""
    if not (isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id in _BY_NAME
            and len(node.args) >= 2):
        return False
    name = node.args[1]
    return isinstance(name, ast.Constant) and isinstance(name.value, str) and _private(name.value)


def test_no_module_reads_another_modules_private_names():
    """A private name the package defines is read only on `self`/`cls` or on an object of a class
    of the same file that has it; one that no file of the package defines (argparse's, a
    namedtuple's `_replace`) is no concern of this test."""
    trees = {path: ast.parse(path.read_text(encoding="utf-8")) for path in _files()}
    owners: dict[str, set[Path]] = defaultdict(set)
    for path, tree in trees.items():
        for name in _defined(tree):
            owners[name].add(path)
    found = []
    for path, tree in trees.items():
        for line, name, receiver in _read_elsewhere(tree):
            defined = owners.get(name, set()) - ({path} if receiver == "import" else set())
            if defined:
                where = ", ".join(str(p.relative_to(SRC)) for p in sorted(owners[name]))
                found.append(f"{path.relative_to(SRC)}:{line} reads {name} on {receiver}, not an object "
                             f"of a class of this file that has it ({name} is defined in {where})")
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
