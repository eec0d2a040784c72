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

import tomllib
from collections.abc import Callable
from pathlib import Path

from .. import registry
from ..limits import InputTooLarge, read_bytes, size_text
from .bounds import AXES_MAX, NESTING_MAX, excess, too_deep
from .names import compact
from .profile import (
    CAPABILITY_DEFAULTS,
    CAPABILITY_VALUES,
    MEASURES,
    STORABLE_USER_VARIABLES,
    USER_VARIABLES,
    RawProfile,
)
from .state import snapshot_errors

MAX_FILE_BYTES = 1024 * 1024
"""Largest profile file read (the built-in ones are about 60 kB)."""
MAX_DEPTH = 8

_TABLES = {"axis_parameter": ("number",), "global_parameter": ("bank", "number"), "io": ("bank", "port"),
           "interrupt": ("number",)}
_MODULE_INT = ("axes", "firmware_binary", "program_memory", "coordinates", "user_variables",
               "storable_user_variables")
_REQUIRED = {"axis_parameter": ("number", "name", "min", "max", "access"),
             "global_parameter": ("bank", "number", "name", "min", "max", "access"),
             "io": ("bank", "port", "name", "kind", "access"), "interrupt": ("number", "name")}
_INT_FIELDS = ("number", "bank", "port", "min", "max", "default")
_VALUE_FIELDS = ("min", "max", "default")   # a 32-bit value of a reply, signed or unsigned
INT32_MIN, INT32_MAX, UINT32 = -(1 << 31), (1 << 31) - 1, (1 << 32) - 1
_STR_FIELDS = ("name", "kind", "access", "title", "unit", "description", "engine")
_TOP = {"extends", "module", "remove", "snapshot", *_TABLES}
"""`snapshot`: state values read by `profile probe` (modules/state.py); not inherited, no effect on the module."""
_FILE_INDEX = "_file_index"  # of a keyless entry after merging: its index in the user's file


class ProfileError(ValueError):
    """A profile file that cannot be used; `errors` holds one line per problem."""

    def __init__(self, errors: list[str]) -> None:
        super().__init__(errors[0] if len(errors) == 1 else f"{errors[0]} (and {len(errors) - 1} more)")
        self.errors = errors


class ProfileLimitError(ProfileError):
    """A profile file beyond a size bound (docs/profiles.md "Bounds"): larger than MAX_FILE_BYTES,
    nested too deeply, or a value above its bound in modules/bounds.py. One line; refused before
    the schema is checked (`profile check` exits 2, as for a file it cannot read)."""

    def __init__(self, line: str) -> None:
        super().__init__([line])


def looks_like_path(name: str) -> bool:
    """A module argument names a file when it ends in .toml or contains a path separator."""
    return name.lower().endswith(".toml") or "/" in name or "\\" in name


def read_toml(path: Path) -> RawProfile:
    """The TOML document of a profile file (a regular file, limits.open_regular); ProfileError."""
    try:
        text = read_bytes(path, MAX_FILE_BYTES, "profile file").decode("utf-8")
    except InputTooLarge:
        raise ProfileLimitError(f"{path}: larger than the {size_text(MAX_FILE_BYTES)} a profile file may have") from None
    except OSError as exc:
        raise ProfileError([f"{path}: cannot read: {exc.strerror or exc}"]) from None
    except UnicodeDecodeError:
        raise ProfileError([f"{path}: not UTF-8 text"]) from None
    too_deep_line = f"{path}: tables and arrays nested more than {NESTING_MAX} levels deep"
    try:
        data = tomllib.loads(text)
    except RecursionError:   # deeper than the parser can go: far beyond NESTING_MAX
        raise ProfileLimitError(too_deep_line) from None
    except ValueError as exc:   # TOMLDecodeError, and an integer of more than 4300 digits
        raise ProfileError([f"{path}: not TOML: {exc}"]) from None
    if too_deep(data):
        raise ProfileLimitError(too_deep_line)
    return data


def check_bounds(data: RawProfile, path: str | Path) -> None:
    """ProfileLimitError naming the first value of `data` above its bound (modules/bounds.py)."""
    line = excess(data, lambda table, i, entry: _entry_path(table, i, entry, _key(table, entry)))
    if line is not None:
        raise ProfileLimitError(f"{path}: {line}")


def _key(table: str, entry: RawProfile) -> tuple[int, ...] | None:
    try:
        return tuple(int(entry[k]) for k in _TABLES[table])
    except (KeyError, TypeError, ValueError):
        return None


def merge(base: RawProfile, child: RawProfile, where: str = "") -> tuple[RawProfile, list[str]]:
    """`child` applied on `base` (both raw TOML dicts): module keys replace, capabilities and table
    entries with a known key merge field by field, new entries are appended, [remove] drops entries."""
    errors: list[str] = []
    base_module, child_module = base.get("module", {}), child.get("module", {})
    out: RawProfile = {"module": {**base_module, **child_module}}
    caps = base_module.get("capabilities"), child_module.get("capabilities")
    if isinstance(caps[0], dict) and isinstance(caps[1], dict):
        out["module"]["capabilities"] = {**caps[0], **caps[1]}
    removals = child.get("remove", {})
    if not isinstance(removals, dict):
        errors.append(f"{where}remove: expected a table")
        removals = {}
    for name in removals:
        if name not in _TABLES:
            errors.append(f"{where}remove.{name}: unknown table (use {', '.join(_TABLES)})")
    for table, key_fields in _TABLES.items():
        entries: dict[tuple[object, ...] | None, RawProfile] = {}
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
            own = _key(table, entry)
            if own is None:  # no usable key: kept apart (never merged into another) and named by its index in the file
                entries[("?", i)] = {**entry, _FILE_INDEX: i}
                continue
            entries[own] = {**entries.get(own, {}), **entry}
        out[table] = list(entries.values())
    return out, errors


def validate(data: RawProfile) -> list[str]:
    """Schema errors of a resolved profile dict, one line each with its key path."""
    errors = [f"{key}: unknown key (a profile has {', '.join(sorted(_TOP))})" for key in data if key not in _TOP]
    if "snapshot" in data:
        errors += snapshot_errors(data["snapshot"])
    m = data.get("module")
    if not isinstance(m, dict):
        return errors + ["module: missing table [module]"]
    errors += _check_module(m)
    errors += _check_capabilities(m.get("capabilities"))
    for table in _TABLES:
        entries = data.get(table, [])
        if not isinstance(entries, list):
            errors.append(f"{table}: expected an array of tables [[{table}]]")
            continue
        seen: dict[tuple[int, ...], int] = {}
        for i, entry in enumerate(entries):
            errors += _check_entry(table, i, entry, seen)
        if table in ("axis_parameter", "global_parameter") and not errors:
            errors += _name_clashes(table, entries)
    return errors


def _name_clashes(table: str, entries: list[RawProfile]) -> list[str]:
    """A name or alias (compared as modules/names.py does) that two entries of a table share."""
    errors: list[str] = []
    owner: dict[str, str] = {}
    for i, entry in enumerate(entries):
        path = _entry_path(table, i, entry, _key(table, entry))
        for name in (entry["name"], *entry.get("aliases", [])):
            first = owner.setdefault(compact(name), path)
            if first != path:
                errors.append(f"{path}: name {name!r} is also a name or alias of {first}")
    return errors


def _check_module(m: RawProfile) -> list[str]:
    """The keys of [module] (without its capabilities)."""
    errors = [f"module.{key}: expected a non-empty string" for key in ("name", "firmware_version")
              if not isinstance(m.get(key), str) or not m.get(key)]
    fw = m.get("firmware_version")
    if isinstance(fw, str) and (len(fw) != 8 or not fw.isascii()):
        errors.append(f"module.firmware_version: must be 8 ASCII characters (command 136 type 0), got {fw!r}")
    errors += [f"module.{key}: expected an integer" for key in _MODULE_INT if key in m and not _is_int(m[key])]
    errors += [f"module.{key}: missing" for key in ("axes", "firmware_binary", "program_memory") if key not in m]
    if _is_int(m.get("axes")) and not 1 <= m["axes"] <= AXES_MAX:
        errors.append(f"module.axes: must be 1..{AXES_MAX}, got {m['axes']}")
    return errors + _check_module_counts(m) + _check_module_choices(m) + _check_extras(m)


def _check_module_counts(m: RawProfile) -> list[str]:
    """Sizes below their least value, more storable than user variables, a 32-bit binary version
    (the upper bounds of sizes are modules/bounds.py's)."""
    errors = [f"module.{key}: must be at least {low}, got {m[key]}"
              for key, low in (("program_memory", 1), ("coordinates", 0), ("user_variables", 0),
                               ("storable_user_variables", 0)) if _is_int(m.get(key)) and m[key] < low]
    variables = m.get("user_variables", USER_VARIABLES)
    storable = m.get("storable_user_variables", STORABLE_USER_VARIABLES)
    if _is_int(variables) and _is_int(storable) and storable > variables:
        errors.append(f"module.storable_user_variables: {storable} is more than the {variables} user variables")
    if _is_int(m.get("firmware_binary")) and not 0 <= m["firmware_binary"] <= UINT32:
        errors.append(f"module.firmware_binary: must be a 32-bit value 0..{UINT32}, got {m['firmware_binary']}")
    return errors


def _check_extras(m: RawProfile) -> list[str]:
    """The [module] keys the firmware reads besides the schema's: `sio_all_max`, `pullups`,
    `rotate_range`."""
    errors = []
    top = m.get("sio_all_max")
    if top is not None and not (_is_int(top) and 0 <= top <= UINT32):
        errors.append(f"module.sio_all_max: expected an integer 0..{UINT32}, got {top!r}")
    rotate = m.get("rotate_range")
    if rotate is not None and not (isinstance(rotate, list) and len(rotate) == 2 and all(
            _is_int(v) and INT32_MIN <= v <= INT32_MAX for v in rotate) and rotate[0] <= rotate[1]):
        errors.append(f"module.rotate_range: expected [min, max], two 32-bit integers, got {rotate!r}"[:200])
    pullups = m.get("pullups")
    if pullups is not None and not (isinstance(pullups, dict) and all(
            _is_int(pullups.get(k)) and 0 <= pullups[k] <= hi for k, hi in (("bank", 255), ("port", 255),
                                                                            ("max", UINT32)))):
        errors.append("module.pullups: expected a table {bank = 0..255, port = 0..255, max = 0.."
                      f"{UINT32}}}, got {pullups!r}"[:200])
    return errors + _check_dashboard_extras(m)


def _check_dashboard_extras(m: RawProfile) -> list[str]:
    """The [module] keys the dashboard reads (docs/profiles.md "For the dashboard"): `current_scale`,
    `reference_modes`, `analog_full_scale_volts`."""
    errors = []
    scale = m.get("current_scale")
    if scale is not None:
        ok = isinstance(scale, dict) and _is_int(scale.get("rms_ma")) and 0 < scale["rms_ma"] <= 1_000_000 \
            and _is_int(scale.get("peak_ma", 1)) and 0 < scale.get("peak_ma", 1) <= 1_000_000 \
            and scale.get("steps", 0) in (0, 32) and isinstance(scale.get("source", ""), str) \
            and set(scale) <= {"rms_ma", "peak_ma", "steps", "source"}
        if not ok:
            errors.append("module.current_scale: expected a table {rms_ma = 1..1000000, peak_ma = 1..1000000, "
                          f"steps = 0 or 32, source = text}}, got {scale!r}"[:200])
    modes = m.get("reference_modes")
    if modes is not None and not (isinstance(modes, list) and 0 < len(modes) <= 63
                                  and all(isinstance(t, str) and 0 < len(t) <= 200 for t in modes)):
        errors.append(f"module.reference_modes: expected a list of 1..63 texts (mode 1 first), got {modes!r}"[:200])
    volts = m.get("analog_full_scale_volts")
    if volts is not None and not (type(volts) in (int, float) and 0 < volts <= 1000):
        errors.append(f"module.analog_full_scale_volts: expected a number of volts 0 < v <= 1000, got {volts!r}")
    return errors


def _check_module_choices(m: RawProfile) -> list[str]:
    """The engine name and the lists of [module]."""
    errors = []
    engines = registry.of(registry.ENGINES).available()
    if m.get("engine") not in engines:
        errors.append(f"module.engine: must be one of {', '.join(engines)}, got {m.get('engine')!r}")
    ops = m.get("opcodes")
    if not isinstance(ops, list) or not all(_is_int(o) and 0 <= o <= 255 for o in ops):
        errors.append("module.opcodes: expected a list of command numbers 0..255")
    if "aliases" in m and not (isinstance(m["aliases"], list) and all(isinstance(a, str) for a in m["aliases"])):
        errors.append("module.aliases: expected a list of strings")
    return errors


def _check_capabilities(caps: object) -> list[str]:
    """[module.capabilities]: every capability of CAPABILITY_VALUES, of its type or one of its values."""
    where = "module.capabilities"
    if caps is None:
        return [f"{where}: missing table [module.capabilities] (docs/profiles.md)"]
    if not isinstance(caps, dict):
        return [f"{where}: expected a table, got {caps!r}"]
    errors = [f"{where}.{key}: unknown capability (known: {', '.join(CAPABILITY_VALUES)})"
              for key in caps if key not in CAPABILITY_VALUES]
    for key, allowed in CAPABILITY_VALUES.items():
        if key not in caps:
            if key not in CAPABILITY_DEFAULTS:
                errors.append(f"{where}.{key}: missing")
            continue
        value = caps[key]
        if isinstance(allowed, tuple):
            if value not in allowed:
                errors.append(f"{where}.{key}: must be one of {', '.join(allowed)}, got {value!r}")
        elif type(value) is not allowed:
            errors.append(f"{where}.{key}: expected {'true or false' if allowed is bool else 'an integer'}, "
                          f"got {value!r}")
        elif allowed is int and isinstance(value, int) and value <= 0:
            errors.append(f"{where}.{key}: must be positive, got {value}")
    return errors


def _is_int(value: object) -> bool:
    return type(value) is int


def _entry_path(table: str, i: int, entry: RawProfile, key: tuple[int, ...] | None) -> str:
    """An entry is named by its key (the index of a merged table means little), else by its index."""
    if key is None:
        return f"{table}[{entry.get(_FILE_INDEX, i)}]"
    return f"{table}[{','.join(f'{k}={v}' for k, v in zip(_TABLES[table], key, strict=True))}]"


def _field_types(table: str, path: str, entry: RawProfile) -> list[str]:
    """Required fields present, integers and strings where the schema says so."""
    errors = [f"{path}.{f}: missing" for f in _REQUIRED[table] if f not in entry]
    errors += [f"{path}.{f}: expected an integer, got {entry[f]!r}" for f in _INT_FIELDS
               if f in entry and not _is_int(entry[f])]
    errors += [f"{path}.{f}: expected a string" for f in _STR_FIELDS if f in entry and not isinstance(entry[f], str)]
    aliases = entry.get("aliases", [])
    if not isinstance(aliases, list) or not all(isinstance(a, str) and compact(a) for a in aliases):
        errors.append(f"{path}.aliases: expected a list of names")
    errors += [f"{path}.{f}: expected a list of integers" for f in ("values", "excluded")
               if f in entry and not (isinstance(entry[f], list) and all(_is_int(v) for v in entry[f]))]
    return errors


def _field_values(table: str, path: str, entry: RawProfile) -> list[str]:
    """Ranges and letters of well-typed fields."""
    errors = [f"{path}.{f}: must be 0..255, got {entry[f]}" for f in ("number", "bank", "port")
              if f in entry and not 0 <= entry[f] <= 255]
    errors += _value_widths(path, entry)
    lo, hi = _range(table, entry) or (0, 0)
    if lo > hi:
        errors.append(f"{path}: min {lo} is greater than max {hi}")
    if "access" in entry and (not entry["access"] or set(entry["access"]) - set("RWEA")):
        errors.append(f"{path}.access: letters R, W, E, A only, got {entry['access']!r}")
    if table != "interrupt" and "default" in entry and lo <= hi and not entry.get("values") \
            and not lo <= entry["default"] <= hi:
        errors.append(f"{path}.default: {entry['default']} outside min..max {lo}..{hi}")
    if table == "io" and entry["kind"] not in ("digital", "analog", "output"):
        errors.append(f"{path}.kind: must be digital, analog or output, got {entry['kind']!r}")
    return errors + _engine_field(table, path, entry) + _measure_fields(table, path, entry)


def _measure_fields(table: str, path: str, entry: RawProfile) -> list[str]:
    """`measures` (one of MEASURES) and `per_unit` (counts per unit, > 0) of an I/O port."""
    errors = []
    given = [f for f in ("measures", "per_unit") if f in entry]
    if given and table != "io":
        return [f"{path}.{given[0]}: only an I/O port measures a quantity of the world"]
    if "measures" in entry and entry["measures"] not in MEASURES:
        errors.append(f"{path}.measures: must be one of {', '.join(MEASURES)}, got {entry['measures']!r}"[:200])
    if "per_unit" in entry and not (_is_int(entry["per_unit"]) and 0 < entry["per_unit"] <= 1_000_000):
        errors.append(f"{path}.per_unit: expected counts per unit 1..1000000, got {entry['per_unit']!r}"[:200])
    return errors


def _value_widths(path: str, entry: RawProfile) -> list[str]:
    """Values a 32-bit reply can carry, read as signed or unsigned."""
    errors = [f"{path}.{f}: must be a 32-bit value {INT32_MIN}..{UINT32}, got {entry[f]}" for f in _VALUE_FIELDS
              if f in entry and not INT32_MIN <= entry[f] <= UINT32]
    for f in ("values", "excluded"):
        wide = [v for v in entry.get(f, ()) if not INT32_MIN <= v <= UINT32]
        if wide:
            errors.append(f"{path}.{f}: {wide[0]} is not a 32-bit value {INT32_MIN}..{UINT32}")
    return errors


def _range(table: str, entry: RawProfile) -> tuple[int, int] | None:
    """(min, max) of an entry: required in parameter tables, 0 and 1 unless given in io (IOPort)."""
    if table == "io":
        return entry.get("min", 0), entry.get("max", 1)
    if "min" in entry and "max" in entry:
        return entry["min"], entry["max"]
    return None


def _engine_field(table: str, path: str, entry: RawProfile) -> list[str]:
    """`engine`: the ramp engine keyword an axis parameter drives ("" none)."""
    errors = []
    if "engine" in entry and table != "axis_parameter":
        errors.append(f"{path}.engine: only an axis parameter drives the ramp engine")
    elif entry.get("engine") and not entry["engine"].isidentifier():
        errors.append(f"{path}.engine: expected a ramp engine keyword (a name like max_acceleration), "
                      f"got {entry['engine']!r}")
    return errors


def _check_entry(table: str, i: int, entry: object, seen: dict[tuple[int, ...], int]) -> list[str]:
    if not isinstance(entry, dict):
        return [f"{table}[{i}]: expected a table"]
    key = _key(table, entry)
    path = _entry_path(table, i, entry, key)
    errors = _field_types(table, path, entry)
    if errors or key is None:   # a well-typed entry has its key
        return errors
    errors += _field_values(table, path, entry)
    if key in seen:
        errors.append(f"{path}: same {'/'.join(_TABLES[table])} {list(key)} as {table}[{seen[key]}]")
    seen[key] = i
    return errors


def resolve(path: str | Path, builtin: Callable[[str], RawProfile], _depth: int = 0,
            _via: Path | None = None) -> RawProfile:
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
        check_bounds(data, path)
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
    check_bounds(merged, path)
    for key in data:
        if key not in _TOP:
            errors.append(f"{path}: {key}: unknown key (a profile has {', '.join(sorted(_TOP))})")
    if "snapshot" in data:   # the file's own state values: not merged into the module
        errors += [f"{path}: {line}" for line in snapshot_errors(data["snapshot"])]
    if errors:  # with the schema errors of the rest: every error at once, not in rounds
        raise ProfileError(errors + [f"{path}: {line}" for line in validate(merged)])
    if not data.get("module", {}).get("aliases"):
        merged["module"]["aliases"] = []  # a derived module does not answer to its parent's aliases
    parent_module = base.get("module", {})
    # The chain of modules this one derives from (ModuleProfile.extra["based_on"]): a scenario
    # written for the parent fits the derived module too (firmware/world.py).
    merged["module"]["based_on"] = [parent_module.get("name"), *parent_module.get("based_on", [])]
    return merged
