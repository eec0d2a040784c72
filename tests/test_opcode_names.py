"""No bare command numbers outside the command table.

Issue 33: "Opcode knowledge is scattered in sets of bare opcode numbers" ... "One command table,
built from `protocol/opcodes.py` ... No bare opcode sets remain outside it." Code names a TMCL
command by `opentmcl.protocol.opcodes.Op` (or a plain int bound from it, or a named set there),
never by its number.

Every .py file under src/opentmcl except protocol/opcodes.py is parsed (ast). An integer literal
1..255 is a bare command number when it is used as a command:

1. compared (==, !=, <, <=, >, >=, in, not in) with a command expression, alone or inside a
   tuple, list, set, frozenset(...), set(...), tuple(...) or range(...) on the other side. A command
   expression is a name or attribute called `command`, `cmd` or `opcode`, or a subscript or
   `.get()` with the key "command" (`rec["command"]`, `r.get("command")`);
2. assigned (in the same way) to a command expression, to a name with a word COMMAND(S), CMD(S)
   or OPCODE(S) (`AXIS_COMMANDS`, `CMD_FIRMWARE_VERSION`), to a name that is a command's name in
   `Op` (`GAP = 6`, `_MST = 3`), or given as the value of the key "command" in a dict literal;
3. passed for a parameter named `command`, `cmd` or `opcode`: by keyword, or by position to a
   function, method or NamedTuple/dataclass of src/opentmcl of that name whose parameter at that
   position has that name (`client.request(136, 0)`, `Instruction(28)`; `self.name(...)` is
   looked up in the enclosing class first); or as the first item of a literal tuple in the list
   passed for a parameter named `requests` (`read_many([(6, n, axis, 0) ...])`); or as the item of
   a literal tuple bound to a command name by a `for` loop (`for command, axis in [(128, 0)]`);
4. bound in the same file to a name (alone, in a tuple or set, a range, or as the key or value of
   a dict) that is used as in 1-3 (`IDENTITY = 136` ... `rec["command"] == IDENTITY`,
   `KINDS = {"axis": 6}` ... `request(KINDS[kind], ...)`): the literal where it is bound.

Parameter numbers, status codes, register numbers and counts are other numbers: the rule only
looks at the places above, and not at the members of an enumeration (`Status.INVALID_COMMAND = 2`). src/opentmcl/firmware/ is checked by its own test, so that the rest
stays clean while the firmware moves to the command table (issue 33).
"""
from __future__ import annotations

import ast
from collections import defaultdict
from pathlib import Path

from opentmcl.protocol.opcodes import Op

SRC = Path(__file__).resolve().parent.parent / "src" / "opentmcl"
TABLE = SRC / "protocol" / "opcodes.py"
FIRMWARE = SRC / "firmware"

COMMAND_NAMES = frozenset({"command", "cmd", "opcode"})
COMMAND_WORDS = frozenset({"COMMAND", "COMMANDS", "CMD", "CMDS", "OPCODE", "OPCODES"})
MNEMONICS = frozenset(Op.__members__)
COLLECTIONS = frozenset({"frozenset", "set", "tuple", "list", "range"})


def _int(node: ast.AST) -> bool:
    return isinstance(node, ast.Constant) and type(node.value) is int and 1 <= node.value <= 255


def _literals(node: ast.AST | None) -> list[ast.Constant]:
    """The int literals 1..255 of an expression that is a literal number or collection of them."""
    if node is None:
        return []
    if _int(node):
        return [node]  # type: ignore[list-item]
    if isinstance(node, (ast.Tuple, ast.List, ast.Set)):
        return [c for e in node.elts for c in _literals(e)]
    if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id in COLLECTIONS:
        return [c for a in node.args for c in _literals(a)]
    if isinstance(node, ast.BinOp) and not (_int(node.left) or _int(node.right)):  # joined collections
        return _literals(node.left) + _literals(node.right)
    return []


def _dict_literals(node: ast.Dict, part: str) -> list[ast.Constant]:
    return [k for k in (node.keys if part == "keys" else node.values) if k is not None and _int(k)]


def _key(node: ast.AST) -> object:
    return node.value if isinstance(node, ast.Constant) else None


def _is_command(node: ast.AST) -> bool:
    """`command`, `x.cmd`, `rec["command"]`, `r.get("command")`."""
    if isinstance(node, ast.Name):
        return node.id in COMMAND_NAMES
    if isinstance(node, ast.Attribute):
        return node.attr in COMMAND_NAMES
    if isinstance(node, ast.Subscript):
        return _key(node.slice) in COMMAND_NAMES
    if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "get" \
            and node.args:
        return _key(node.args[0]) in COMMAND_NAMES
    return False


def _names_a_set_or_command(target: ast.AST) -> bool:
    if _is_command(target):
        return True
    if isinstance(target, ast.Name):
        name = target.id
        return bool(COMMAND_WORDS & set(name.upper().split("_"))) or name.lstrip("_") in MNEMONICS
    return False


def _params(node: ast.FunctionDef | ast.AsyncFunctionDef, method: bool) -> list[str]:
    names = [a.arg for a in (*node.args.posonlyargs, *node.args.args)]
    return names[1:] if method and names and names[0] in ("self", "cls") else names


def _signatures(trees: dict[Path, ast.Module]) -> dict[str, list[list[str]]]:
    """Name -> the positional parameter names of every function, method and NamedTuple/dataclass
    (its annotated fields) of that name in the tree."""
    out: dict[str, list[list[str]]] = defaultdict(list)
    for tree in trees.values():
        methods = set()
        for node in ast.walk(tree):
            if isinstance(node, ast.ClassDef):
                fields = [s.target.id for s in node.body
                          if isinstance(s, ast.AnnAssign) and isinstance(s.target, ast.Name)
                          and "ClassVar" not in ast.unparse(s.annotation)]
                if fields:
                    out[node.name].append(fields)
                for item in node.body:
                    if isinstance(item, (ast.FunctionDef, ast.AsyncFunctionDef)):
                        out[item.name].append(_params(item, True))
                        methods.add(id(item))
        for node in ast.walk(tree):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and id(node) not in methods:
                out[node.name].append(_params(node, False))
    return out


class _File(ast.NodeVisitor):
    """The bare command numbers of one file (module docstring)."""

    def __init__(self, tree: ast.Module, signatures: dict[str, list[list[str]]]) -> None:
        self.signatures = signatures
        self.found: set[int] = set()  # ids of flagged Constant nodes
        self.nodes: dict[int, ast.Constant] = {}
        self.classes: list[ast.ClassDef] = []
        self.bound: dict[str, list[ast.AST]] = defaultdict(list)  # name -> values bound to it in the file
        for node in ast.walk(tree):
            if isinstance(node, (ast.Assign, ast.AnnAssign)):
                targets = node.targets if isinstance(node, ast.Assign) else [node.target]
                for target in targets:
                    for name, value in self._pairs(target, node.value):
                        if isinstance(name, ast.Name):
                            self.bound[name.id].append(value)
        self.visit(tree)

    @staticmethod
    def _pairs(target: ast.AST, value: ast.AST | None) -> list[tuple[ast.AST, ast.AST | None]]:
        """(target, value) pairs, `A, B = 1, 2` taken apart."""
        if isinstance(target, (ast.Tuple, ast.List)) and isinstance(value, (ast.Tuple, ast.List)) \
                and len(target.elts) == len(value.elts):
            return [p for t, v in zip(target.elts, value.elts, strict=True) for p in _File._pairs(t, v)]
        return [(target, value)]

    def flag(self, constants: list[ast.Constant]) -> None:
        for c in constants:
            self.found.add(id(c))
            self.nodes[id(c)] = c

    def flag_value(self, node: ast.AST | None, part: str = "keys") -> None:
        """Flag the literals of `node`, or of what a name in it is bound to in this file."""
        if node is None:
            return
        self.flag(_literals(node))
        if isinstance(node, ast.Dict):
            self.flag(_dict_literals(node, part))
        names = [node] if isinstance(node, ast.Name) else \
            [e for e in node.elts if isinstance(e, ast.Name)] if isinstance(node, (ast.Tuple, ast.List, ast.Set)) \
            else []
        for name in names:
            for value in self.bound.get(name.id, []):
                self.flag(_literals(value))
                if isinstance(value, ast.Dict):
                    self.flag(_dict_literals(value, part))

    def flag_argument(self, node: ast.AST) -> None:
        """An argument given for a command parameter: a literal, a bound name, or `MAP[...]`."""
        if isinstance(node, ast.Subscript) and isinstance(node.value, ast.Name):
            self.flag_value(node.value, "values")
        elif isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "get" \
                and isinstance(node.func.value, ast.Name):
            self.flag_value(node.func.value, "values")
        else:
            self.flag_value(node)

    # -- 1. comparisons --------------------------------------------------------------------
    def visit_Compare(self, node: ast.Compare) -> None:
        parts = [node.left, *node.comparators]
        for a, b in zip(parts, parts[1:], strict=False):
            for x, y in ((a, b), (b, a)):
                if _is_command(x):
                    self.flag_value(y)
        self.generic_visit(node)

    # -- 2. assignments --------------------------------------------------------------------
    def visit_Assign(self, node: ast.Assign) -> None:
        for target in node.targets:
            for t, v in self._pairs(target, node.value):
                if _names_a_set_or_command(t):
                    self.flag_value(v)
        self.generic_visit(node)

    def visit_AnnAssign(self, node: ast.AnnAssign) -> None:
        if _names_a_set_or_command(node.target):
            self.flag_value(node.value)
        self.generic_visit(node)

    def visit_Dict(self, node: ast.Dict) -> None:
        for k, v in zip(node.keys, node.values, strict=True):
            if k is not None and _key(k) in COMMAND_NAMES:
                self.flag_argument(v)
        self.generic_visit(node)

    # -- 3. arguments ----------------------------------------------------------------------
    def visit_ClassDef(self, node: ast.ClassDef) -> None:
        self.classes.append(node)
        if any(ast.unparse(base).endswith(("Enum", "Flag")) for base in node.bases):
            for item in node.body:  # members of an enumeration: named numbers of their own (status codes)
                if not isinstance(item, (ast.Assign, ast.AnnAssign)):
                    self.visit(item)
        else:
            self.generic_visit(node)
        self.classes.pop()

    def _positions(self, call: ast.Call) -> list[list[str]]:
        func = call.func
        if isinstance(func, ast.Attribute) and isinstance(func.value, ast.Name) and func.value.id == "self" \
                and self.classes:
            own = [item for item in self.classes[-1].body
                   if isinstance(item, (ast.FunctionDef, ast.AsyncFunctionDef)) and item.name == func.attr]
            if own:
                return [_params(own[0], True)]
        name = func.id if isinstance(func, ast.Name) else func.attr if isinstance(func, ast.Attribute) else None
        return self.signatures.get(name, []) if name else []

    def visit_Call(self, node: ast.Call) -> None:
        for keyword in node.keywords:
            if keyword.arg in COMMAND_NAMES:
                self.flag_argument(keyword.value)
            elif keyword.arg == "requests":
                self._requests(keyword.value)
        for params in self._positions(node):
            for i, arg in enumerate(node.args):
                if isinstance(arg, ast.Starred) or i >= len(params):
                    break
                if params[i] in COMMAND_NAMES:
                    self.flag_argument(arg)
                elif params[i] == "requests":
                    self._requests(arg)
        self.generic_visit(node)

    def _requests(self, node: ast.AST) -> None:
        """The first items of the (command, type, motor, value) tuples of a literal batch."""
        if isinstance(node, ast.BinOp):
            self._requests(node.left)
            self._requests(node.right)
        elif isinstance(node, (ast.List, ast.Tuple)):
            for e in node.elts:
                if isinstance(e, ast.Tuple) and e.elts:
                    self.flag_argument(e.elts[0])
        elif isinstance(node, (ast.ListComp, ast.GeneratorExp)) and isinstance(node.elt, ast.Tuple) \
                and node.elt.elts:
            self.flag_argument(node.elt.elts[0])

    def visit_For(self, node: ast.For) -> None:
        if isinstance(node.target, ast.Tuple):
            at = [i for i, e in enumerate(node.target.elts) if isinstance(e, ast.Name) and e.id in COMMAND_NAMES]
            for row in self._rows(node.iter):
                for i in at:
                    if i < len(row.elts):
                        self.flag_argument(row.elts[i])
        self.generic_visit(node)

    def _rows(self, node: ast.AST) -> list[ast.Tuple]:
        if isinstance(node, ast.BinOp):
            return self._rows(node.left) + self._rows(node.right)
        if isinstance(node, ast.IfExp):
            return self._rows(node.body) + self._rows(node.orelse)
        if isinstance(node, (ast.List, ast.Tuple)):
            return [e for e in node.elts if isinstance(e, ast.Tuple)]
        if isinstance(node, ast.ListComp) and isinstance(node.elt, ast.Tuple):
            return [node.elt]
        return []


def bare_command_numbers(files: list[Path]) -> list[str]:
    """"path:line: source" of every bare command number in `files` (module docstring)."""
    trees = {f: ast.parse(f.read_text(encoding="utf-8"), str(f)) for f in sorted(SRC.rglob("*.py"))}
    signatures = _signatures(trees)
    out = []
    for f in files:
        lines = f.read_text(encoding="utf-8").splitlines()
        found = _File(trees[f], signatures)
        for line in sorted({c.lineno for c in found.nodes.values()}):
            out.append(f"{f.relative_to(SRC.parent)}:{line}: {lines[line - 1].strip()}")
    return out


def _files(firmware: bool) -> list[Path]:
    return [f for f in sorted(SRC.rglob("*.py"))
            if f != TABLE and (FIRMWARE in f.parents) == firmware]


def test_no_bare_command_numbers_outside_the_firmware():
    found = bare_command_numbers(_files(firmware=False))
    assert not found, "name these commands by opentmcl.protocol.opcodes.Op:\n" + "\n".join(found)


def test_no_bare_command_numbers_in_the_firmware():
    found = bare_command_numbers(_files(firmware=True))
    assert not found, "name these commands by opentmcl.protocol.opcodes.Op:\n" + "\n".join(found)


def _found_in(source: str) -> list[int]:
    tree = ast.parse(source)
    return sorted({c.lineno for c in _File(tree, _signatures({Path("x.py"): tree})).nodes.values()})


def test_the_rule_flags_each_pattern_of_the_docstring():
    """Each numbered pattern of the module docstring, with a near miss that is no command beside it."""
    source = """
IDENTITY = 136
PROGRAM_COMMANDS = frozenset(range(128, 136))
GAP, SAP = 6, 5
KINDS = {"axis": 6}
AP_POSITION = 1
def request(command, type=0, motor=0, value=0): ...
def read(number, motor): ...
def f(rec, command, client, reqs):
    if rec["command"] == IDENTITY or command in (4, 13) or rec.get("command") >= 128:
        pass
    client.request(136, AP_POSITION)
    read(1, 0)
    request(command=15)
    request(KINDS["axis"], 1)
    client.read_many([(10, n, 2, 0) for n in range(8)])
    for command, axis in [(3, 0)]:
        pass
    return {"command": 138, "type": 0}, rec["type"] == 2, rec["motor"] in (0, 1)
def read_many(requests): ...
CMD_FIRMWARE_VERSION = 136
class Status(IntEnum):
    INVALID_COMMAND = 2
"""
    assert _found_in(source) == [2, 3, 4, 5, 10, 12, 14, 16, 17, 19, 21]


def test_the_rule_looks_up_self_methods_in_their_class_first():
    """`self.read(1, axis)` calls the class's own `read(number, motor)` although another `read`
    takes a command first: no command there; `self.send(136, 1)` is one."""
    source = """
class Twin:
    def read(self, command, type_, motor): ...
class Run:
    def read(self, number, motor): ...
    def send(self, command, type_=0): ...
    def go(self):
        self.read(1, 0)
        self.send(136, 1)
"""
    assert _found_in(source) == [9]
