"""Size bounds of a profile file (docs/profiles.md "Bounds"): how much a profile may make OpenTMCL
allocate. Each is well above every module of the manuals (in parentheses: the largest of the
three built-in profiles) and at or below what the 9-byte TMCL frame can address.

`excess(data)` names the first value beyond its bound, `too_deep(data)` a value nested deeper
than NESTING_MAX; profile_file.py turns either into a one-line ProfileLimitError.
"""
from __future__ import annotations

from collections.abc import Callable, Iterator
from typing import Any

AXES_MAX = 255                  # (6) the motor byte of a request (also a schema rule: 1..255)
PROGRAM_MEMORY_MAX = 65536      # (6144 TMCL commands, TMCM-6212 manual 1) half a 1 MiB binary image
COORDINATES_MAX = 255           # (20) coordinate numbers are the type byte (SCO/GCO/CCO, ACO)
USER_VARIABLES_MAX = 256        # (256) bank 2 variables are the type byte (GGP/SGP)
ENTRIES_MAX = {"axis_parameter": 256, "global_parameter": 1024, "io": 1024, "interrupt": 256}
"""Entries of each table after `extends` is applied (72, 40, 12, 38)."""
LIST_MAX = 1024                 # items of `opcodes`, `values`, `excluded` (70 opcodes, 20 values)
ALIASES_MAX = 16                # names in one `aliases` list (2)
NAME_MAX = 128                  # characters of any other string: name, alias, title, unit, ... (43)
DESCRIPTION_MAX = 4096          # characters of a description (192)
NESTING_MAX = 8                 # levels of tables and arrays, the file itself the first (3; [remove] pairs 4)

_MODULE_MAX = {"axes": AXES_MAX, "program_memory": PROGRAM_MEMORY_MAX, "coordinates": COORDINATES_MAX,
               "user_variables": USER_VARIABLES_MAX, "storable_user_variables": USER_VARIABLES_MAX}
_UNITS = {"axes": "axes", "program_memory": "commands", "coordinates": "coordinates",
          "user_variables": "variables", "storable_user_variables": "variables"}


def _over(key: str, count: int, bound: int, what: str) -> str:
    return f"{key}: {count} {what}, more than the {bound} a profile may have (docs/profiles.md \"Bounds\")"


def _strings(where: str, table: dict[str, Any]) -> Iterator[str]:
    """Bound errors of the strings and lists of one [module] table or table entry."""
    for key, value in table.items():
        if isinstance(value, str):
            bound = DESCRIPTION_MAX if key == "description" else NAME_MAX
            if len(value) > bound:
                yield _over(f"{where}.{key}", len(value), bound, "characters")
        elif isinstance(value, list):
            bound = ALIASES_MAX if key == "aliases" else LIST_MAX
            if len(value) > bound:
                yield _over(f"{where}.{key}", len(value), bound, "items")
            elif key == "aliases":
                for i, alias in enumerate(value):
                    if isinstance(alias, str) and len(alias) > NAME_MAX:
                        yield _over(f"{where}.aliases[{i}]", len(alias), NAME_MAX, "characters")


def _errors(data: dict[str, Any], entry_name: Callable[[str, int, dict[str, Any]], str]) -> Iterator[str]:
    module = data.get("module")
    if isinstance(module, dict):
        for key, bound in _MODULE_MAX.items():
            value = module.get(key)
            if type(value) is int and value > bound:
                yield _over(f"module.{key}", value, bound, _UNITS[key])
        yield from _strings("module", module)
    for table, bound in ENTRIES_MAX.items():
        entries = data.get(table)
        if not isinstance(entries, list):
            continue
        if len(entries) > bound:
            yield _over(table, len(entries), bound, "entries")
        for i, entry in enumerate(entries):
            if isinstance(entry, dict):
                yield from _strings(entry_name(table, i, entry), entry)


def excess(data: dict[str, Any], entry_name: Callable[[str, int, dict[str, Any]], str]) -> str | None:
    """The first value of a profile dict (raw or resolved) beyond its bound, as one line with its
    key path (`entry_name(table, index, entry)` names a table entry); None when all are within.
    Values of the wrong type are left to the schema check."""
    return next(_errors(data, entry_name), None)


def too_deep(data: object, limit: int = NESTING_MAX) -> bool:
    """True if tables and arrays nest more than `limit` levels (the document itself is level 1)."""
    level: list[object] = [data]
    for _ in range(limit):
        level = [child for item in level
                 for child in (item.values() if isinstance(item, dict) else item if isinstance(item, list) else ())
                 if isinstance(child, (dict, list))]
        if not level:
            return False
    return True
