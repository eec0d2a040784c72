"""One way to describe faults (docs/faults.md): a fault plan is a seed and a list of faults, each a
table with a `kind`, what triggers it and the kind's own settings.

    seed = 7
    [[fault]]
    name = "third-move"          # optional: trigger it by name (CLI, dashboard, Python)
    kind = "drop_reply"
    command = "MVP"              # matching requests: a mnemonic or a command number
    count = 3                    # the third of them (once)

The same tables appear in a scenario file, a fault file (`opentmcl serve --faults FILE`), a
``sim://...?faults=FILE`` URL, the pytest marker and the Python API (as dicts or `Fault`s).
Malformed input is a `FaultError` (a ValueError) of one line naming the key at fault.
"""
from __future__ import annotations

import math
import os
import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, replace
from typing import Any

from ..datafile import DocumentError, read_document
from ..protocol.opcodes import UnknownCommand, by_mnemonic, by_number

LINK_KINDS = ("drop_request", "drop_reply", "corrupt_request", "corrupt_reply", "delay", "split_request",
              "split_reply", "link_down")
"""Faults of the link between host and module: applied by the endpoint or the in-process transport."""
MODULE_KINDS = ("power_loss", "hang", "overtemperature", "stuck_switch", "bouncing_switch", "step_loss")
"""Faults of the module and its world: applied by the virtual module (firmware/faults.py)."""
KINDS = LINK_KINDS + MODULE_KINDS

TRIGGER_KEYS = ("probability", "at", "command", "type", "motor", "count")
COMMON_KEYS = ("kind", "name", "description", *TRIGGER_KEYS)
KIND_KEYS: dict[str, tuple[str, ...]] = {
    "drop_request": (), "drop_reply": (),
    "corrupt_request": ("byte",), "corrupt_reply": ("byte",),
    "delay": ("delay", "jitter"),
    "split_request": ("pieces", "gap"), "split_reply": ("pieces", "gap"),
    "link_down": ("duration",),
    "power_loss": ("address", "duration", "store"),
    "hang": ("address", "duration"),
    "overtemperature": ("address", "axis", "level", "duration"),
    "stuck_switch": ("address", "axis", "switch", "level", "duration"),
    "bouncing_switch": ("address", "axis", "switch", "bounces", "period"),
    "step_loss": ("address", "axis", "load", "duration"),
}
REQUIRED: dict[str, tuple[str, ...]] = {"delay": ("delay",), "link_down": ("duration",), "hang": ("duration",),
                                        "stuck_switch": ("switch",), "bouncing_switch": ("switch",)}
SWITCHES = ("left", "right", "home")
TEMPERATURES = ("prewarning", "shutdown")
STORES = ("complete", "absent", "either")
NAME = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.-]{0,63}\Z")
MAX_FAULTS = 1000
"""The most faults one plan may hold."""
MAX_SECONDS = 1e6
"""The longest time a fault may name (`at`, `delay`, `duration`, ...): about 11.6 days."""


class FaultError(ValueError):
    """A fault description that does not follow docs/faults.md (one line, naming the key)."""


@dataclass(frozen=True)
class Fault:
    """One fault: its kind, its trigger and its settings (docs/faults.md)."""

    kind: str
    name: str | None = None
    probability: float | None = None
    """Fire on each matching request with this probability (0..1), from `at` on."""
    at: float | None = None
    """Seconds: alone, fire once at this time; with the others, armed from this time on."""
    command: int | None = None
    """The command number of the requests that count (None: every request)."""
    type: int | None = None
    motor: int | None = None
    count: int | None = None
    """Fire once, on the count-th matching request."""
    delay: float = 0.0
    jitter: float = 0.0
    pieces: int = 3
    gap: float = 0.01
    byte: int | None = None
    duration: float | None = None
    address: int | None = None
    axis: int = 0
    level: str | int | None = None
    switch: str = "left"
    bounces: int = 4
    period: float = 0.001
    store: str = "either"
    load: float = 2.0
    description: str = ""

    @property
    def link(self) -> bool:
        """A fault of the link (applied by endpoints and transports), not of the module."""
        return self.kind in LINK_KINDS

    @property
    def timed(self) -> bool:
        """Fires once at `at`, not on a request: a module fault with `at` and no other trigger."""
        return self.at is not None and self.command is None and self.probability is None and self.count is None

    def matches(self, command: int, type_: int, motor: int) -> bool:
        return (self.command is None or command == self.command) and (self.type is None or type_ == self.type) \
            and (self.motor is None or motor == self.motor)

    @property
    def label(self) -> str:
        """The name, or the kind when the fault has none."""
        return self.name or self.kind


@dataclass(frozen=True)
class FaultPlan:
    """A seed (None: one is chosen and reported when the plan is armed) and the faults."""

    faults: tuple[Fault, ...] = ()
    seed: int | None = None
    description: str = ""

    @property
    def link_faults(self) -> tuple[Fault, ...]:
        return tuple(f for f in self.faults if f.link)

    @property
    def module_faults(self) -> tuple[Fault, ...]:
        return tuple(f for f in self.faults if not f.link)

    def names(self) -> list[str]:
        return [f.name for f in self.faults if f.name]

    def __bool__(self) -> bool:
        return bool(self.faults)

    def with_seed(self, seed: int) -> FaultPlan:
        return replace(self, seed=seed)

    def check_addresses(self, addresses: Iterable[int]) -> None:
        """FaultError for a module fault whose `address` none of the modules at `addresses` has."""
        have = sorted(set(addresses))
        for f in self.module_faults:
            if f.address is not None and f.address not in have:
                raise FaultError(f"fault {f.label}: no module at address {f.address} "
                                 f"(modules at {', '.join(map(str, have))})")

    def merged(self, other: FaultPlan) -> FaultPlan:
        """Both plans' faults (names must stay distinct); this plan's seed unless it has none."""
        names = set(self.names())
        twice = [n for n in other.names() if n in names]
        if twice:
            raise FaultError(f"fault name {twice[0]!r} is given twice")
        return FaultPlan(self.faults + other.faults, self.seed if self.seed is not None else other.seed,
                         self.description or other.description)


# --- parsing ---------------------------------------------------------------------------------------

def _number(value: object, where: str, lo: float = 0.0, hi: float = math.inf) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise FaultError(f"{where}: expected a number of seconds, got {value!r}")
    if not lo <= value <= hi:
        bound = f"{lo:g}..{hi:g}" if hi < math.inf else f">= {lo:g}"
        raise FaultError(f"{where}: must be {bound}, got {value!r}")
    return float(value)


def _seconds(value: object, where: str) -> float:
    """A time of a fault: >= 0 and at most MAX_SECONDS."""
    out = _number(value, where)
    if out > MAX_SECONDS:
        raise FaultError(f"{where}: must be at most {MAX_SECONDS:g} s (about 11.6 days), got {value!r}")
    return out


def _int(value: object, where: str, lo: int, hi: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        raise FaultError(f"{where}: expected an integer, got {value!r}")
    if not lo <= value <= hi:
        raise FaultError(f"{where}: must be {lo}..{hi}, got {value!r}")
    return value


def _choice(value: object, where: str, choices: tuple[str, ...]) -> str:
    if value not in choices:
        raise FaultError(f"{where}: one of {', '.join(choices)}, got {value!r}")
    return str(value)


def command_number(value: object, where: str) -> int:
    """A TMCL command given as its mnemonic ("MVP") or its number (4); FaultError if unknown."""
    try:
        if isinstance(value, str):
            return by_mnemonic(value).number
        if isinstance(value, int) and not isinstance(value, bool):
            return by_number(value).number
    except UnknownCommand as exc:
        raise FaultError(f"{where}: {exc}") from None
    raise FaultError(f"{where}: a command mnemonic or number, got {value!r}")


def _level(kind: str, value: object, where: str) -> str | int:
    if kind == "overtemperature":
        return _choice(value, where, TEMPERATURES)
    return _int(value, where, 0, 1)


_READERS: dict[str, Any] = {
    "probability": lambda v, w: _number(v, w, 0.0, 1.0),
    "at": _seconds, "delay": _seconds, "jitter": _seconds, "gap": _seconds, "period": _seconds,
    "count": lambda v, w: _int(v, w, 1, 2**31),
    "type": lambda v, w: _int(v, w, 0, 255), "motor": lambda v, w: _int(v, w, 0, 255),
    "pieces": lambda v, w: _int(v, w, 2, 9), "byte": lambda v, w: _int(v, w, 0, 8),
    "address": lambda v, w: _int(v, w, 0, 255), "axis": lambda v, w: _int(v, w, 0, 255),
    "bounces": lambda v, w: _int(v, w, 1, 1000),
    "load": lambda v, w: _number(v, w, 0.0, 1000.0),
    "switch": lambda v, w: _choice(v, w, SWITCHES), "store": lambda v, w: _choice(v, w, STORES),
    "command": command_number,
}


def _duration(value: object, where: str) -> float:
    out = _seconds(value, where)
    if out == 0:
        raise FaultError(f"{where}: must be > 0, got {value!r}")
    return out


def _check_keys(kind: str, d: Mapping[Any, Any], where: str) -> None:
    allowed = set(COMMON_KEYS) | set(KIND_KEYS[kind])
    extra = sorted(str(k) for k in d if k not in allowed)
    if extra:
        hint = " (YAML reads a key 'on' as true: the requests that count are given with 'command')" \
            if any(k is True for k in d) else ""
        raise FaultError(f"{where}: unknown key(s) {', '.join(extra)} for a {kind} fault{hint}")


def _check_trigger(kind: str, d: Mapping[str, Any], where: str) -> None:
    if ("type" in d or "motor" in d or "count" in d) and "command" not in d:
        raise FaultError(f"{where}: 'type', 'motor' and 'count' narrow 'command': give the command too")
    if "count" in d and "probability" in d:
        raise FaultError(f"{where}: give 'count' or 'probability', not both")
    if not any(k in d for k in ("probability", "at", "count", "name")):
        raise FaultError(f"{where}: it would never fire: give 'probability', 'at', 'count' or a 'name' "
                         "to trigger it by")
    missing = [k for k in REQUIRED.get(kind, ()) if k not in d]
    if missing:
        raise FaultError(f"{where}: a {kind} fault needs {missing[0]!r}")


def parse_fault(data: object, where: str = "fault") -> Fault:
    """One fault table (a dict, or a `Fault` as it is)."""
    if isinstance(data, Fault):
        return data
    if not isinstance(data, Mapping):
        raise FaultError(f"{where}: expected a table, got {data!r}")
    if "kind" not in data:
        raise FaultError(f"{where}: 'kind' is required (one of {', '.join(KINDS)})")
    kind = data["kind"]
    if kind not in KIND_KEYS:
        raise FaultError(f"{where}.kind: unknown fault kind {kind!r} (known: {', '.join(KINDS)})")
    _check_keys(kind, data, where)
    _check_trigger(kind, data, where)
    values: dict[str, Any] = {"kind": kind}
    for key, value in data.items():
        at = f"{where}.{key}"
        if key == "name":
            if not isinstance(value, str) or not NAME.match(value):
                raise FaultError(f"{at}: 1..64 letters, digits, '_', '.' or '-', got {value!r}")
            values[key] = value
        elif key == "description":
            values[key] = str(value)
        elif key == "duration":
            values[key] = _duration(value, at)
        elif key == "level":
            values[key] = _level(kind, value, at)
        elif key != "kind":
            values[key] = _READERS[key](value, at)
    if kind == "overtemperature" and "level" not in values:
        values["level"] = "shutdown"
    if kind == "stuck_switch" and "level" not in values:
        values["level"] = 1
    return Fault(**values)


def parse_faults(items: object, where: str = "fault") -> tuple[Fault, ...]:
    """A list of fault tables ([[fault]]); names distinct."""
    if isinstance(items, (Fault, Mapping)):
        items = [items]
    if not isinstance(items, (list, tuple)):
        raise FaultError(f"{where}: expected a list of tables ([[{where}]]), got {items!r}")
    if len(items) > MAX_FAULTS:
        raise FaultError(f"{where}: {len(items)} faults, more than the {MAX_FAULTS} a plan may hold")
    out = tuple(parse_fault(item, f"{where}[{i}]") for i, item in enumerate(items))
    seen: set[str] = set()
    for i, f in enumerate(out):
        if f.name in seen:
            raise FaultError(f"{where}[{i}].name: {f.name!r} is given twice")
        if f.name:
            seen.add(f.name)
    return out


def parse_seed(value: object, where: str = "seed") -> int | None:
    """A plan's seed: an integer 0..2**63-1, or None (one is chosen when the plan is armed)."""
    if value is None:
        return None
    return _int(value, where, 0, 2**63 - 1)


def seed_of(value: object, where: str = "seed") -> int:
    """A seed given explicitly (a CLI option, a URL): an integer 0..2**63-1."""
    return _int(value, where, 0, 2**63 - 1)


def parse_plan(data: object, where: str = "faults") -> FaultPlan:
    """A fault plan from its parsed file: {seed, description, fault = [...]}."""
    if data is None:
        return FaultPlan()
    if isinstance(data, FaultPlan):
        return data
    if not isinstance(data, Mapping):
        raise FaultError(f"{where}: expected a table, got {data!r}")
    extra = sorted(str(k) for k in data if k not in ("seed", "fault", "description"))
    if extra:
        raise FaultError(f"{where}: unknown key(s) {', '.join(extra)} (a fault file has seed, description "
                         "and [[fault]] tables)")
    return FaultPlan(parse_faults(data.get("fault", []), "fault"), parse_seed(data.get("seed")),
                     str(data.get("description", "")))


def load_plan(source: object) -> FaultPlan:
    """A plan from a file path (TOML, or YAML with .yaml/.yml), its parsed dict, a plan, a list of
    faults, or None (no faults)."""
    if source is None or isinstance(source, FaultPlan):
        return source or FaultPlan()
    if isinstance(source, (Mapping, Fault)):
        if isinstance(source, Mapping) and "kind" not in source:
            return parse_plan(source)
        return FaultPlan(parse_faults([source]))
    if isinstance(source, (list, tuple)):
        return FaultPlan(parse_faults(source))
    if not isinstance(source, (str, os.PathLike)):
        raise FaultError(f"faults are a file path, a table or a list of tables, not {type(source).__name__}")
    try:
        data = read_document(source, "fault plan")
    except DocumentError as exc:
        raise FaultError(str(exc)) from None
    try:
        return parse_plan(data)
    except FaultError as exc:
        raise FaultError(f"{os.fspath(source)}: {exc}") from None
