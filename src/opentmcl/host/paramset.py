"""Parameter sets: a module's configuration as a JSON or TOML file, the diff against a module and
applying it (docs/dashboard-parameters.md; TMCM-6212 manual 3.6.5-3.6.8 SAP/GAP/SGP/GGP).

    ps = export_set(module)                    # GAP/GGP of every parameter a set holds
    text = to_toml(ps)                         # or to_json(ps); read back with parse(text)
    changes = diff(module, parse(text))        # [Change(kind, index, number, name, current, value)]
    apply(module, changes)                     # SAP/SGP of each change, after checking them all

A set holds the parameters that are readable and writable (access letters R and W), minus the
motion state (positions, target speed: importing them would move the motor) and the settings of
the link itself (address, baud rate, CAN ids, reply suppression): see docs/assumptions.md.
Every check runs before the first write: a file for another module, an unknown or read-only
parameter, or a value outside the manual's range raises `ParamSetError` and nothing is applied.
"""
from __future__ import annotations

import json
import tomllib
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

from ..modules.profile import ModuleProfile, Param
from ..protocol.opcodes import Op
from .errors import TmclValueError
from .module import Module

_GAP, _GGP, _SAP, _SGP = int(Op.GAP), int(Op.GGP), int(Op.SAP), int(Op.SGP)  # plain ints for the requests
FORMAT = "opentmcl-parameters"
FORMAT_VERSION = 1
MAX_TEXT = 1 << 20       # characters of a parameter-set file read at most
MAX_ENTRIES = 4096       # entries of one file at most (a TMCM-6212 set has about 440)
KINDS = ("axis", "global")
MOTION_STATE = frozenset({"target_position", "actual_position", "target_speed", "encoder_position",
                          "tick_timer", "random_number"})
LINK_SETTINGS = frozenset({"rs485_baud_rate", "serial_address", "serial_host_address",
                           "serial_secondary_address", "can_bit_rate", "can_id", "can_reply_id",
                           "can_secondary_address", "ascii_mode", "suppress_reply", "eeprom_magic",
                           "eeprom_lock"})


class ParamSetError(TmclValueError):
    """A parameter-set file that cannot be applied to this module; `problems` lists every reason."""

    def __init__(self, problems: Sequence[str]) -> None:
        self.problems = list(problems)
        more = f" (and {len(self.problems) - 1} more)" if len(self.problems) > 1 else ""
        super().__init__(f"{self.problems[0]}{more}" if self.problems else "invalid parameter set")


@dataclass(frozen=True)
class Entry:
    """One parameter value: `kind` "axis" (index = axis) or "global" (index = bank)."""

    kind: str
    index: int
    number: int
    name: str
    value: int


@dataclass(frozen=True)
class ParamSet:
    module: str
    firmware: str
    entries: tuple[Entry, ...]


@dataclass(frozen=True)
class Change:
    """A parameter whose value on the module (`current`, None: unreadable) differs from the file's."""

    kind: str
    index: int
    number: int
    name: str
    current: int | None
    value: int


def in_set(p: Param) -> bool:
    """Whether parameter `p` belongs in a parameter set (readable, writable, not state or link)."""
    return p.readable and p.writable and p.name not in MOTION_STATE and p.name not in LINK_SETTINGS


def members(profile: ModuleProfile) -> list[tuple[str, int, Param]]:
    """(kind, axis or bank, parameter) of every value a set of this module holds, in file order."""
    out: list[tuple[str, int, Param]] = []
    axis_params = [p for _, p in sorted(profile.axis_parameters.items()) if in_set(p)]
    for axis in range(profile.axes):
        out.extend(("axis", axis, p) for p in axis_params)
    out.extend(("global", bank, p) for (bank, _), p in sorted(profile.global_parameters.items()) if in_set(p))
    return out


def _read(module: Module, kind: str, index: int, number: int) -> int:
    return module.reply(_GAP if kind == "axis" else _GGP, number, index).value


def export_set(module: Module) -> ParamSet:
    """The module's current parameter set: GAP/GGP of each member (a status error raises)."""
    prof = module.profile
    entries = tuple(Entry(kind, index, p.number, p.name, _read(module, kind, index, p.number))
                    for kind, index, p in members(prof))
    return ParamSet(prof.name, module.firmware_version(), entries)


# --- files -----------------------------------------------------------------------------------

def to_dict(ps: ParamSet) -> dict[str, object]:
    axis = [{"axis": e.index, "number": e.number, "name": e.name, "value": e.value}
            for e in ps.entries if e.kind == "axis"]
    glob = [{"bank": e.index, "number": e.number, "name": e.name, "value": e.value}
            for e in ps.entries if e.kind == "global"]
    return {"format": FORMAT, "version": FORMAT_VERSION, "module": ps.module, "firmware": ps.firmware,
            "axis": axis, "global": glob}


def to_json(ps: ParamSet) -> str:
    return json.dumps(to_dict(ps), indent=1) + "\n"


def _toml_str(text: str) -> str:
    return json.dumps(text)  # a JSON string with ASCII escapes is a TOML basic string


def to_toml(ps: ParamSet) -> str:
    lines = [f"format = {_toml_str(FORMAT)}", f"version = {FORMAT_VERSION}",
             f"module = {_toml_str(ps.module)}", f"firmware = {_toml_str(ps.firmware)}"]
    for e in ps.entries:
        key = "axis" if e.kind == "axis" else "bank"
        lines += ["", f"[[{e.kind}]]", f"{key} = {e.index}", f"number = {e.number}",
                  f"name = {_toml_str(e.name)}", f"value = {e.value}"]
    return "\n".join(lines) + "\n"


def _load(text: str) -> object:
    """JSON when the text starts with "{", else TOML."""
    if text.lstrip().startswith("{"):
        try:
            return json.loads(text)
        except (json.JSONDecodeError, RecursionError) as exc:
            raise ParamSetError([f"not a JSON parameter set: {exc}"]) from None
    try:
        return tomllib.loads(text)
    except (tomllib.TOMLDecodeError, RecursionError) as exc:
        raise ParamSetError([f"not a TOML or JSON parameter set: {exc}"]) from None


def _int_field(item: dict[str, object], key: str, where: str, problems: list[str]) -> int | None:
    v = item.get(key)
    if isinstance(v, bool) or not isinstance(v, int):
        problems.append(f"{where}: {key} must be an integer, got {v!r}"[:200])
        return None
    return v


def _entries(kind: str, items: object, problems: list[str]) -> list[Entry]:
    if items is None:
        return []
    if not isinstance(items, list):
        problems.append(f"{kind!r} must be a list of tables")
        return []
    key = "axis" if kind == "axis" else "bank"
    out = []
    for n, item in enumerate(items, 1):
        where = f"{kind} entry {n}"
        if not isinstance(item, dict):
            problems.append(f"{where} is not a table")
            continue
        index, number, value = (_int_field(item, k, where, problems) for k in (key, "number", "value"))
        name = item.get("name", "")
        if not isinstance(name, str):
            problems.append(f"{where}: name must be a string")
            continue
        if index is not None and number is not None and value is not None:
            out.append(Entry(kind, index, number, name, value))
    return out


def parse(text: str) -> ParamSet:
    """A parameter set from the text of a JSON or TOML file (`to_json` / `to_toml`)."""
    if not isinstance(text, str):
        raise ParamSetError(["a parameter set is text"])
    if len(text) > MAX_TEXT:
        raise ParamSetError([f"parameter set larger than {MAX_TEXT} characters"])
    data = _load(text)
    if not isinstance(data, dict) or data.get("format") != FORMAT:
        raise ParamSetError([f"not an OpenTMCL parameter set (format = {FORMAT!r} missing)"])
    if data.get("version") != FORMAT_VERSION:
        raise ParamSetError([f"parameter-set version {data.get('version')!r} is not {FORMAT_VERSION}"])
    module, firmware = data.get("module"), data.get("firmware", "")
    if not isinstance(module, str) or not isinstance(firmware, str):
        raise ParamSetError(["module and firmware must be strings"])
    problems: list[str] = []
    entries = _entries("axis", data.get("axis"), problems) + _entries("global", data.get("global"), problems)
    if len(entries) > MAX_ENTRIES:
        problems.append(f"more than {MAX_ENTRIES} entries")
    if problems:
        raise ParamSetError(problems)
    return ParamSet(module, firmware, tuple(entries))


# --- checking, diff, apply ---------------------------------------------------------------------

def _param(profile: ModuleProfile, e: Entry) -> Param | str:
    """The profile's parameter for `e`, or why `e` cannot be applied."""
    where = f"{e.kind} parameter {e.number}" + (f" of axis {e.index}" if e.kind == "axis" else f" of bank {e.index}")
    if e.kind == "axis":
        if not 0 <= e.index < profile.axes:
            return f"{profile.name} has axes 0..{profile.axes - 1}, not {e.index}"
        p = profile.axis_parameters.get(e.number)
    else:
        p = profile.global_parameters.get((e.index, e.number))
    if p is None:
        return f"{where} does not exist on {profile.name}"
    if e.name and e.name != p.name:
        return f"{where} is {p.name}, the file names it {e.name!r}"
    if not in_set(p):
        return f"{where} ({p.name}) is not part of a parameter set"
    if not p.accepts(e.value):
        allowed = ", ".join(map(str, p.values)) if p.values else f"{p.min}..{p.max}"
        return f"{where} ({p.name}) takes {allowed}, not {e.value}"
    return p


def check(profile: ModuleProfile, ps: ParamSet) -> None:
    """Raise `ParamSetError` with every reason `ps` cannot be applied to a module of `profile`."""
    if ps.module != profile.name:
        raise ParamSetError([f"the file is for a {ps.module}, this module is a {profile.name}; nothing applied"])
    problems, seen = [], set()
    for e in ps.entries:
        key = (e.kind, e.index, e.number)
        if key in seen:
            problems.append(f"{e.kind} parameter {e.number} of {e.index} appears twice")
        seen.add(key)
        found = _param(profile, e)
        if isinstance(found, str):
            problems.append(found)
    if problems:
        raise ParamSetError(problems)


def diff(module: Module, ps: ParamSet) -> list[Change]:
    """Check `ps` against the module's profile, then GAP/GGP each entry: the entries that differ."""
    check(module.profile, ps)
    out = []
    for e in ps.entries:
        current = _read(module, e.kind, e.index, e.number)
        if current != e.value:
            p = _param(module.profile, e)
            name = p.name if isinstance(p, Param) else e.name
            out.append(Change(e.kind, e.index, e.number, name, current, e.value))
    return out


def apply(module: Module, changes: Iterable[Change | Entry]) -> int:
    """SAP/SGP each change after checking them all against the profile; the number written."""
    items = list(changes)
    prof = module.profile
    entries = [Entry(c.kind, c.index, c.number, c.name, c.value) for c in items]
    check(prof, ParamSet(prof.name, "", tuple(entries)))
    for e in entries:
        module.request(_SAP if e.kind == "axis" else _SGP, e.number, e.index, e.value)
    return len(entries)
