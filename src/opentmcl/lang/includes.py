"""Where ``#include file`` is found (docs/tmcl-assembler.md "Bundled include files"): the including
file's directory, the include path, then the bundled include files of the selected module
(``include/<key>_<name>`` before ``include/<name>``)."""
from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path

INCLUDE_DIR = Path(__file__).resolve().parent / "include"
DEFAULT_MODULE = "TMCM-6212"


def bundled_include(name: str, module: str | None = None) -> Path | None:
    """Path of a bundled include file: the module's own variant (``<key>_<name>``) first."""
    try:
        key = include_key(module)
    except KeyError:
        key = None
    for candidate in ([f"{key}_{name}"] if key else []) + [name]:
        path = INCLUDE_DIR / candidate
        if _is_file(path):
            return path
    return None


def _is_file(path: Path) -> bool:
    try:
        return path.is_file()
    except (OSError, ValueError):  # e.g. a NUL byte or an over-long name
        return False


def include_key(module: str | None) -> str:
    """File-name key of a module's bundled includes: TMCM-6212 -> tmcm6212, PD86-1180 -> pd86_1180."""
    from ..modules.profile import load_profile
    name = load_profile(module or DEFAULT_MODULE).name
    head, _, tail = name.lower().partition("-")
    return f"{head}{tail}" if head == "tmcm" else f"{head}_{tail}"


def find_include(name: str, current: Path | None, include_path: Iterable[Path], module: str | None) -> Path | None:
    """The file ``#include name`` reads from the file `current` (None: text without a file)."""
    dirs = ([current.parent] if current else []) + list(include_path)
    for d in dirs:
        p = d / name
        if _is_file(p):
            return p
    return bundled_include(name, module)


def display_name(path: Path) -> str:
    """How an include file is named in diagnostics and listings: ``<bundled>/name`` for a bundled one."""
    return f"<bundled>/{path.name}" if path.parent == INCLUDE_DIR else str(path)
