"""Profile files a user brings: load a path, resolve `extends`, check the schema (docs/profiles.md).

    extends = "PD86-1180"          # a built-in name/alias or another file (relative to this one)
    [module]                       # only the keys that differ
    name = "PD86-1181"
    [[axis_parameter]]             # an entry whose number exists is merged field by field,
    number = 4                     # a new number must define every required field
    default = 1000
    [remove]                       # drop inherited entries
    axis_parameter = [206]
    global_parameter = [[0, 81]]   # [bank, number]
    io = [[0, 3]]                  # [bank, port]
    interrupt = [15]

Every error is one line naming its key path, e.g. ``axis_parameter[2].max: expected an integer``.
"""
from __future__ import annotations

import sys
from pathlib import Path

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

MAX_FILE_BYTES = 1024 * 1024
"""Largest profile file read (the built-in ones are about 60 kB)."""
MAX_DEPTH = 8
ENGINES = ("sixpoint", "linear", "tmc429")
_TABLES = {"axis_parameter": ("number",), "global_parameter": ("bank", "number"), "io": ("bank", "port"),
           "interrupt": ("number",)}
_MODULE_INT = ("axes", "firmware_binary", "program_memory", "coordinates", "user_variables",
               "storable_user_variables")
_REQUIRED = {"axis_parameter": ("number", "name", "min", "max", "access"),
             "global_parameter": ("bank", "number", "name", "min", "max", "access"),
             "io": ("bank", "port", "name", "kind", "access"), "interrupt": ("number", "name")}
_INT_FIELDS = ("number", "bank", "port", "min", "max", "default")
_TOP = {"extends", "module", "remove", *_TABLES}
_FILE_INDEX = "_file_index"  # of a keyless entry after merging: its index in the user's file


class ProfileError(ValueError):
    """A profile file that cannot be used; `errors` holds one line per problem."""

    def __init__(self, errors: list[str]) -> None:
        super().__init__(errors[0] if len(errors) == 1 else f"{errors[0]} (and {len(errors) - 1} more)")
        self.errors = errors


def looks_like_path(name: str) -> bool:
    """A module argument names a file when it ends in .toml or contains a path separator."""
    return name.lower().endswith(".toml") or "/" in name or "\\" in name


def read_toml(path: Path) -> dict:
    try:
        size = path.stat().st_size
    except OSError as exc:
        raise ProfileError([f"{path}: cannot read: {exc.strerror or exc}"]) from None
    if size > MAX_FILE_BYTES:
        raise ProfileError([f"{path}: {size} bytes, larger than the {MAX_FILE_BYTES} bytes a profile may have"])
    try:
        with path.open("rb") as fh:
            return tomllib.loads(fh.read(MAX_FILE_BYTES + 1).decode("utf-8"))
    except UnicodeDecodeError:
        raise ProfileError([f"{path}: not UTF-8 text"]) from None
    except tomllib.TOMLDecodeError as exc:
        raise ProfileError([f"{path}: not TOML: {exc}"]) from None
    except OSError as exc:
        raise ProfileError([f"{path}: cannot read: {exc.strerror or exc}"]) from None


def _key(table: str, entry: dict) -> tuple | None:
    try:
        return tuple(int(entry[k]) for k in _TABLES[table])
    except (KeyError, TypeError, ValueError):
        return None


def merge(base: dict, child: dict, where: str = "") -> tuple[dict, list[str]]:
    """`child` applied on `base` (both raw TOML dicts): module keys replace, table entries with a
    known key merge field by field, new entries are appended, [remove] drops entries."""
    errors: list[str] = []
    out = {"module": {**base.get("module", {}), **child.get("module", {})}}
    removals = child.get("remove", {})
    if not isinstance(removals, dict):
        errors.append(f"{where}remove: expected a table")
        removals = {}
    for name in removals:
        if name not in _TABLES:
            errors.append(f"{where}remove.{name}: unknown table (use {', '.join(_TABLES)})")
    for table, key_fields in _TABLES.items():
        entries = {}
        for entry in base.get(table, []):
            entries[_key(table, entry)] = dict(entry)
        drop = removals.get(table, [])
        for i, item in enumerate(drop if isinstance(drop, list) else [drop]):
            key = tuple(item) if isinstance(item, list) else (item,)
            if len(key) != len(key_fields) or key not in entries:
                errors.append(f"{where}remove.{table}[{i}]: {list(key)} is not an inherited entry "
                              f"({', '.join(key_fields)})")
                continue
            del entries[key]
        for i, entry in enumerate(child.get(table, [])):
            if not isinstance(entry, dict):
                continue  # reported by validate
            key = _key(table, entry)
            if key is None:  # no usable key: kept apart (never merged into another) and named by its index in the file
                entries[("?", i)] = {**entry, _FILE_INDEX: i}
                continue
            entries[key] = {**entries.get(key, {}), **entry}
        out[table] = list(entries.values())
    return out, errors


def validate(data: dict) -> list[str]:
    """Schema errors of a resolved profile dict, one line each with its key path."""
    errors: list[str] = []
    for key in data:
        if key not in _TOP:
            errors.append(f"{key}: unknown key (a profile has {', '.join(sorted(_TOP))})")
    m = data.get("module")
    if not isinstance(m, dict):
        return errors + ["module: missing table [module]"]
    for key in ("name", "firmware_version"):
        if not isinstance(m.get(key), str) or not m.get(key):
            errors.append(f"module.{key}: expected a non-empty string")
    fw = m.get("firmware_version")
    if isinstance(fw, str) and (len(fw) != 8 or not fw.isascii()):
        errors.append(f"module.firmware_version: must be 8 ASCII characters (command 136 type 0), got {fw!r}")
    for key in _MODULE_INT:
        if key in m and not _is_int(m[key]):
            errors.append(f"module.{key}: expected an integer")
    for key in ("axes", "firmware_binary", "program_memory"):
        if key not in m:
            errors.append(f"module.{key}: missing")
    if _is_int(m.get("axes")) and not 1 <= m["axes"] <= 255:
        errors.append(f"module.axes: must be 1..255, got {m['axes']}")
    if m.get("engine") not in ENGINES:
        errors.append(f"module.engine: must be one of {', '.join(ENGINES)}, got {m.get('engine')!r}")
    ops = m.get("opcodes")
    if not isinstance(ops, list) or not all(_is_int(o) and 0 <= o <= 255 for o in ops):
        errors.append("module.opcodes: expected a list of command numbers 0..255")
    if "aliases" in m and not (isinstance(m["aliases"], list) and all(isinstance(a, str) for a in m["aliases"])):
        errors.append("module.aliases: expected a list of strings")
    for table in _TABLES:
        entries = data.get(table, [])
        if not isinstance(entries, list):
            errors.append(f"{table}: expected an array of tables [[{table}]]")
            continue
        seen: dict[tuple, int] = {}
        for i, entry in enumerate(entries):
            errors += _check_entry(table, i, entry, seen)
    return errors


def _is_int(value) -> bool:
    return type(value) is int


def _check_entry(table: str, i: int, entry, seen: dict) -> list[str]:
    if not isinstance(entry, dict):
        return [f"{table}[{i}]: expected a table"]
    key = _key(table, entry)  # entries are named by their key: the index of a merged table means little
    path = f"{table}[{','.join(f'{k}={v}' for k, v in zip(_TABLES[table], key, strict=True))}]" if key else f"{table}[{entry.get(_FILE_INDEX, i)}]"
    errors = [f"{path}.{f}: missing" for f in _REQUIRED[table] if f not in entry]
    for f in _INT_FIELDS:
        if f in entry and not _is_int(entry[f]):
            errors.append(f"{path}.{f}: expected an integer, got {entry[f]!r}")
    for f in ("name", "kind", "access", "title", "unit", "description"):
        if f in entry and not isinstance(entry[f], str):
            errors.append(f"{path}.{f}: expected a string")
    if errors:
        return errors
    for f in ("number", "bank", "port"):
        if f in entry and not 0 <= entry[f] <= 255:
            errors.append(f"{path}.{f}: must be 0..255, got {entry[f]}")
    if "min" in entry and entry["min"] > entry["max"]:
        errors.append(f"{path}: min {entry['min']} is greater than max {entry['max']}")
    if "access" in entry and (not entry["access"] or set(entry["access"]) - set("RWEA")):
        errors.append(f"{path}.access: letters R, W, E, A only, got {entry['access']!r}")
    if table != "interrupt" and "default" in entry and entry["min"] <= entry["max"] and not entry.get("values"):
        if not entry["min"] <= entry["default"] <= entry["max"]:
            errors.append(f"{path}.default: {entry['default']} outside min..max {entry['min']}..{entry['max']}")
    if table == "io" and entry["kind"] not in ("digital", "analog", "output"):
        errors.append(f"{path}.kind: must be digital, analog or output, got {entry['kind']!r}")
    if key in seen:
        errors.append(f"{path}: same {'/'.join(_TABLES[table])} {list(key)} as {table}[{seen[key]}]")
    seen[key] = i
    return errors


def resolve(path: str | Path, builtin, _depth: int = 0, _via: Path | None = None) -> dict:
    """The raw dict of the profile file at `path` with its `extends` chain applied; `builtin(name)`
    returns the raw dict of a built-in profile (KeyError if unknown). ProfileError on any problem."""
    path = Path(path)
    if _depth > MAX_DEPTH:
        raise ProfileError([f"{path}: extends: more than {MAX_DEPTH} levels (a cycle?)"])
    try:
        data = read_toml(path)
    except ProfileError as exc:
        if _via is None:
            raise
        raise ProfileError([f"{_via}: extends: {line}" for line in exc.errors]) from None
    parent = data.get("extends")
    if parent is None:
        return data
    if not isinstance(parent, str) or not parent:
        raise ProfileError([f"{path}: extends: expected a module name or a file name"])
    if looks_like_path(parent):
        base = resolve((path.parent / parent), builtin, _depth + 1, path)
    else:
        try:
            base = builtin(parent)
        except KeyError as exc:
            raise ProfileError([f"{path}: extends: {exc.args[0] if exc.args else parent}"]) from None
    merged, errors = merge(base, data, f"{path}: ")
    for key in data:
        if key not in _TOP:
            errors.append(f"{path}: {key}: unknown key (a profile has {', '.join(sorted(_TOP))})")
    if errors:  # with the schema errors of the rest: every error at once, not in rounds
        raise ProfileError(errors + [f"{path}: {line}" for line in validate(merged)])
    if not data.get("module", {}).get("aliases"):
        merged["module"]["aliases"] = []  # a derived module does not answer to its parent's aliases
    parent_module = base.get("module", {})
    # The chain of modules this one derives from (ModuleProfile.extra["based_on"]): a scenario
    # written for the parent fits the derived module too (firmware/world.py).
    merged["module"]["based_on"] = [parent_module.get("name"), *parent_module.get("based_on", [])]
    return merged
