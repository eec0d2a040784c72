"""The layer contract of docs/architecture.md "Layers", read from pyproject's [tool.importlinter].

"Lower layers never import higher ones, and the packages of one layer never import each other."
import-linter checks `import` statements; this test also reads what it cannot see: module names
in string literals (``importlib.import_module("opentmcl.firmware.vm")``, lazy registry targets
``"opentmcl.sim:open_sim"``) and imports inside functions, by walking every module's syntax tree.
The root package (`opentmcl/__init__.py`) is the top of the tree and may name every layer.
"""
from __future__ import annotations

import ast
import re
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src"
MODULE_NAME = re.compile(r"opentmcl(?:\.[A-Za-z_]\w*)+(?::[A-Za-z_][\w.]*)?")


def layer_of() -> dict[str, int]:
    """Top-level package -> layer index (0 is the top) of the "layers" contract in pyproject."""
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["importlinter"]
    (contract,) = [c for c in config["contracts"] if c["type"] == "layers"]
    return {pkg.strip().removeprefix("opentmcl."): i
            for i, layer in enumerate(contract["layers"]) for pkg in layer.split("|")}


LAYER = layer_of()


def _package(name: str) -> str | None:
    parts = name.split(":")[0].split(".")
    return parts[1] if len(parts) > 1 and parts[0] == "opentmcl" else None


def _named_modules(module: str, tree: ast.AST) -> list[tuple[int, str]]:
    """(line, absolute module name) of every import and every module-name string literal."""
    is_package = module.endswith(".__init__")
    module = module.removesuffix(".__init__")
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out += [(node.lineno, alias.name) for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parts = module.split(".")
                keep = len(parts) - node.level + (1 if is_package else 0)
                base = ".".join(parts[:keep] + ([node.module] if node.module else []))
            out.append((node.lineno, base))
            out += [(node.lineno, f"{base}.{alias.name}") for alias in node.names if base == "opentmcl"]
        elif isinstance(node, ast.Constant) and isinstance(node.value, str) and MODULE_NAME.fullmatch(node.value):
            out.append((node.lineno, node.value))
    return out


def violations(module: str, source: str) -> list[str]:
    """Where `module` (e.g. ``opentmcl.host.connect``) names a package it must not depend on."""
    own = _package(module)
    if own not in LAYER:
        return []  # the root package, __main__, the pytest plugin: above every layer
    found = []
    for line, name in _named_modules(module, ast.parse(source)):
        other = _package(name)
        if other in LAYER and other != own and LAYER[other] <= LAYER[own]:
            found.append(f"{module}:{line} names {name} ({other} is not below {own})")
    return found


def test_no_module_names_a_higher_or_sibling_layer():
    """docs/architecture.md "Layers": host never reaches firmware, server, web or cli, web never
    cli, and no lower layer names a higher one, neither by import nor by an importlib string."""
    found = []
    for path in sorted((SRC / "opentmcl").rglob("*.py")):
        module = ".".join(path.relative_to(SRC).with_suffix("").parts)
        found += violations(module, path.read_text())
    assert found == []


def test_the_check_sees_strings_and_function_level_imports():
    """The check itself: an importlib string and a relative import inside a function both count."""
    source = ('import importlib\n'
              'def f():\n'
              '    from ...cli.send import parse\n'
              '    return importlib.import_module("opentmcl.firmware.vm"), parse\n')
    assert len(violations("opentmcl.host.transports.x", source)) == 2
    assert violations("opentmcl.web.service", "from ..cli import CliError\n") != []
    assert violations("opentmcl.cli.send", "from ..web import service\n'opentmcl.host:connect'\n") == []


def test_the_contract_keeps_host_below_the_packages_it_must_not_import():
    """issue 12 item 2: host never imports firmware, server, web or cli; web does not import cli."""
    for higher in ("server", "web", "cli", "sim", "urlhandler"):
        assert LAYER[higher] < LAYER["host"]
    assert LAYER["firmware"] == LAYER["host"]  # independent siblings: neither imports the other
    assert LAYER["cli"] < LAYER["web"]
