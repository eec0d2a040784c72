"""Module profiles as data (docs/profiles.md; docs/architecture.md "Capabilities").

A profile is read from `data/<key>.toml`. Schema (all numbers are plain ints):

    [module]
    name = "TMCM-6212"            # canonical name
    aliases = ["..."]             # other accepted names
    axes = 6
    engine = "sixpoint"           # the ramp engine (firmware/engines.py): sixpoint | linear | tmc429
    firmware_version = "6212V105" # string reply of command 136 type 0 (8 chars)
    firmware_binary = 0x...       # value of the reply of command 136 type 1
    program_memory = 6144         # TMCL program memory size in commands
    opcodes = [1, 2, ...]         # opcodes this firmware executes
    ascii_mode = false            # command 139 / ASCII interface available
    coordinates = 20              # coordinates per axis (coordinate 0 is RAM only)
    user_variables = 256          # bank 2 size
    storable_user_variables = 56  # variables 0..N-1 can be stored in EEPROM

    [module.capabilities]         # what the firmware has; every key but usb required (docs/profiles.md)
    velocity_unit = "pps"         # pps | tmc429: unit of the velocity and acceleration parameters
    unit_mode = true              # AP255 switches to TMC5130 internal units (TMCM-6212 4.1)
    encoder = "resolution"        # resolution (AP210 counts per round) | prescaler (AP210 = p/512)
    encoder_counts = 1024         # encoder counts per round unless the scenario gives its own
    null_channel = false          # AP210 + 4 clears the encoder at the next null channel
    reference_input = "HOME"      # HOME | REFL: where the home switch is wired
    freewheel_delay = false       # AP204 is a delay in ms after which the motor current is cut
    usb = true                    # the module has a USB port (default true; PD28-1021: false)

    [[axis_parameter]]            # one per axis parameter of the manual
    number = 4
    name = "max_positioning_speed"   # snake_case of the manual's name
    aliases = ["MaxVelocity"]     # optional: other accepted names (case and separators ignored)
    title = "Maximum positioning speed"
    description = "The maximum speed used for positioning ramps."
    min = 0
    max = 7999774
    values = []                   # optional: the only allowed values (enumerations)
    excluded = []                 # optional: values inside min..max the manual forbids
    access = "RWE"                # letters of the manual: R read, W write, E storable (STAP), A auto-stored
    default = 51200
    unit = "pps"
    engine = "max_positioning_speed" # optional: the ramp engine setting this parameter drives

    [[global_parameter]]          # same fields plus `bank`
    bank = 0
    number = 66
    ...

    [[io]]                        # one per SIO/GIO port
    bank = 0                      # 0 digital inputs, 1 analog inputs, 2 outputs (per manual)
    port = 0
    name = "IN0"
    kind = "digital"              # digital | analog | output
    access = "R"                  # R for inputs, RW for outputs
    min = 0
    max = 1
    measures = "supply_voltage"   # optional: the world's quantity the port reads (supply_voltage in
    per_unit = 10                 #   volts, temperature in degrees C), per_unit counts per unit

    [[interrupt]]                 # interrupt vector table
    number = 0
    name = "TI_TIMER0"
    description = "Timer 0"
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field, fields
from functools import cache, cached_property
from typing import Any

from .. import registry
from .names import NameIndex


@dataclass(frozen=True, slots=True)
class Param:
    number: int
    name: str
    title: str
    min: int
    max: int
    access: str
    default: int
    unit: str = ""
    description: str = ""
    values: tuple[int, ...] = ()
    bank: int | None = None
    excluded: tuple[int, ...] = ()
    engine: str = ""
    """Keyword of the ramp engine setting this axis parameter drives ("" for none)."""
    aliases: tuple[str, ...] = ()
    """Other names accepted for this parameter (built-in profiles: PyTrinamic's; modules/names.py)."""

    @property
    def readable(self) -> bool:
        return "R" in self.access

    @property
    def writable(self) -> bool:
        return "W" in self.access

    @property
    def storable(self) -> bool:
        """Can be stored to EEPROM with STAP/STGP."""
        return "E" in self.access or "A" in self.access

    @property
    def auto_stored(self) -> bool:
        return "A" in self.access

    def accepts(self, value: int) -> bool:
        if self.values:
            return value in self.values
        return self.min <= value <= self.max and value not in self.excluded


@dataclass(frozen=True, slots=True)
class IOPort:
    bank: int
    port: int
    name: str
    kind: str
    access: str
    min: int = 0
    max: int = 1
    measures: str = ""
    """The quantity of the world the port reads ("supply_voltage" in V, "temperature" in °C; the
    scenario keys of the same names, docs/scenarios.md); "" for an input the scenario drives."""
    per_unit: int = 1
    """Counts per volt or per degree of a `measures` port (10: the reading is in 0.1 V)."""


@dataclass(frozen=True, slots=True)
class Interrupt:
    number: int
    name: str
    description: str = ""


RawProfile = dict[str, Any]
"""A profile as read from TOML (values are TOML values)."""

CAPABILITY_VALUES: dict[str, tuple[str, ...] | type] = {
    "velocity_unit": ("pps", "tmc429"),
    "unit_mode": bool,
    "encoder": ("resolution", "prescaler"),
    "encoder_counts": int,
    "null_channel": bool,
    "reference_input": ("HOME", "REFL"),
    "freewheel_delay": bool,
    "usb": bool,
}
"""Every capability a profile declares: its allowed strings, or its TOML type (docs/profiles.md)."""
CAPABILITY_DEFAULTS: dict[str, object] = {"usb": True}
MEASURES = ("supply_voltage", "temperature")
"""What an I/O port may measure (`IOPort.measures`): the scenario keys of the world's quantities."""
"""Capabilities a profile may leave out (added after the schema was first published), and their value."""


@dataclass(frozen=True, slots=True)
class Capabilities:
    """What a module's firmware has, beyond its parameter tables (docs/profiles.md "Capabilities")."""

    velocity_unit: str
    """"pps", or "tmc429": TMC429 internal units scaled by the pulse divisor AP154 (PD86-1180 5)."""
    unit_mode: bool
    """AP255 = 0 selects TMC5130 internal units for velocities and accelerations (TMCM-6212 4.1)."""
    encoder: str
    """"resolution": AP210 is the encoder's counts per round, converted with AP202 and AP140
    (TMCM-6212 6.2); "prescaler": AP210 is a prescaler p/512 (PD86-1180 7.2)."""
    encoder_counts: int
    """Counts per round of the encoder when the scenario does not give them."""
    null_channel: bool
    """AP210 + 4 clears the encoder at the next null channel (PD86-1180 7.2)."""
    reference_input: str
    """"HOME": a home switch input of its own; "REFL": the home switch is wired in series with the
    left limit switch (three-switch wiring, PD86-1180 7.1) and search mode + 128 inverts REFL."""
    freewheel_delay: bool
    """AP204 is a time in ms after which the current of a standing motor is cut (PD86-1180 5)."""
    usb: bool = True
    """The module has a USB port (TMCM-6212 1 "USB full speed ... device interface"; PD86-1180
    "USB, RS232, RS485 and CAN"); the PD28-1021's manual lists an RS485 interface only. A pty that
    serves one such module alone stands for USB by default, otherwise for RS-485 (server/bus.py)."""


@dataclass(frozen=True)
class ModuleProfile:
    name: str
    aliases: tuple[str, ...]
    axes: int
    engine: str
    firmware_version: str
    firmware_binary: int
    program_memory: int
    opcodes: frozenset[int]
    ascii_mode: bool
    coordinates: int
    user_variables: int
    storable_user_variables: int
    axis_parameters: dict[int, Param]
    global_parameters: dict[tuple[int, int], Param]  # (bank, number) -> Param
    io: dict[tuple[int, int], IOPort]  # (bank, port) -> IOPort
    interrupts: dict[int, Interrupt]
    capabilities: Capabilities
    extra: dict[str, Any] = field(default_factory=dict)
    """Other [module] keys (e.g. `based_on`, `pullups`), as read."""

    @property
    def engine_params(self) -> dict[int, str]:
        """Axis parameter number -> the ramp engine keyword it drives (the `engine` field)."""
        return {n: p.engine for n, p in self.axis_parameters.items() if p.engine}

    @cached_property
    def global_banks(self) -> frozenset[int]:
        """The banks SGP/GGP/STGP/RSGP take: those of the global parameters, plus bank 2 (TMCM-6212
        manual 3.6.7: "bank 2 is used for user variables")."""
        return frozenset({b for b, _ in self.global_parameters} | {2})

    @cached_property
    def axis_names(self) -> NameIndex:
        """Names, titles and aliases of the axis parameters (modules/names.py)."""
        return NameIndex(self.axis_parameters.values())

    @cached_property
    def global_names(self) -> NameIndex:
        """Names, titles and aliases of the global parameters of every bank."""
        return NameIndex(self.global_parameters.values())

    def axis_parameter(self, name_or_number: str | int) -> Param:
        """By number, or by name, title or alias (modules/names.py); KeyError if there is none."""
        if isinstance(name_or_number, int):
            return self.axis_parameters[name_or_number]
        found = self.axis_names.find(name_or_number)
        if found is None:
            raise KeyError(name_or_number)
        return found

    def global_parameter(self, name_or_number: str | int, bank: int = 0) -> Param:
        """By number in `bank`, or by name, title or alias (which imply the bank); KeyError if none."""
        if isinstance(name_or_number, int):
            return self.global_parameters[(bank, name_or_number)]
        found = self.global_names.find(name_or_number)
        if found is None:
            raise KeyError(name_or_number)
        return found


def _param(d: RawProfile) -> Param:
    return Param(
        number=d["number"], name=d["name"], title=d["title"] if "title" in d else d["name"], min=d["min"], max=d["max"],
        access=d["access"], default=d.get("default", 0), unit=d.get("unit", ""),
        description=d.get("description", ""), values=tuple(d.get("values", ())), bank=d.get("bank"),
        excluded=tuple(d.get("excluded", ())), engine=d.get("engine", ""), aliases=tuple(d.get("aliases", ())),
    )


def _capabilities(d: RawProfile) -> Capabilities:
    return Capabilities(**{f.name: d[f.name] for f in fields(Capabilities) if f.name in d})


USER_VARIABLES, STORABLE_USER_VARIABLES = 256, 56
"""`user_variables` and `storable_user_variables` of a profile that does not give them."""


def parse_profile(data: RawProfile) -> ModuleProfile:
    m = data["module"]
    known = {"name", "aliases", "axes", "engine", "firmware_version", "firmware_binary", "program_memory",
             "opcodes", "ascii_mode", "coordinates", "user_variables", "storable_user_variables",
             "capabilities"}
    return ModuleProfile(
        name=m["name"], aliases=tuple(m.get("aliases", ())), axes=m["axes"], engine=m["engine"],
        firmware_version=m["firmware_version"], firmware_binary=m["firmware_binary"],
        program_memory=m["program_memory"], opcodes=frozenset(m["opcodes"]),
        ascii_mode=m.get("ascii_mode", False), coordinates=m.get("coordinates", 20),
        user_variables=m.get("user_variables", USER_VARIABLES),
        storable_user_variables=m.get("storable_user_variables", STORABLE_USER_VARIABLES),
        axis_parameters={p["number"]: _param(p) for p in data.get("axis_parameter", [])},
        global_parameters={(p["bank"], p["number"]): _param(p) for p in data.get("global_parameter", [])},
        io={(p["bank"], p["port"]): IOPort(p["bank"], p["port"], p["name"], p["kind"], p["access"],
                                           p.get("min", 0), p.get("max", 1), p.get("measures", ""),
                                           p.get("per_unit", 1)) for p in data.get("io", [])},
        interrupts={i["number"]: Interrupt(i["number"], i["name"], i.get("description", ""))
                    for i in data.get("interrupt", [])},
        capabilities=_capabilities(m["capabilities"]),
        extra={k: v for k, v in m.items() if k not in known},
    )


BUILTIN = {"TMCM-6212": "tmcm6212.toml", "PD86-1180": "pd86_1180.toml", "PD28-1021": "pd28_1021.toml"}
"""The profiles this package carries (modules/data/); registered under their names."""


class _DataFile:
    """A profile this package carries: called, the path of its file in modules/data/."""

    def __init__(self, fname: str) -> None:
        self.fname = fname

    def __call__(self) -> object:
        from importlib import resources

        return resources.files("opentmcl.modules").joinpath("data", self.fname)


_PROFILES = registry.of(registry.PROFILES)
for _name, _file in BUILTIN.items():
    _PROFILES.register(_name, _DataFile(_file))


def _normalise(name: str) -> str:
    return name.strip().upper().replace("_", "-")


@cache
def _builtin_raw(fname: str) -> RawProfile:
    # imported here, on the first profile read: `import opentmcl` stays cheap (docs/host.md)
    import tomllib
    from importlib import resources

    text = resources.files("opentmcl.modules").joinpath("data", fname).read_text(encoding="utf-8")
    return tomllib.loads(text)  # a TOML document is a table


def _registered_raw(name: str) -> RawProfile:
    """The raw dict of the profile registered as `name`: a built-in data file, or the file an
    installed distribution names (its `extends` resolved against the registered profiles)."""
    target = _PROFILES.find(name)
    if target is None:
        raise KeyError(name)
    if isinstance(target, _DataFile):
        return _builtin_raw(target.fname)
    path = target() if callable(target) else target
    if not isinstance(path, (str, os.PathLike)):
        raise ValueError(f"profile {name!r}: its entry point names no file path but {path!r}")
    return raw_profile(os.fspath(path))


@cache
def _all() -> dict[str, ModuleProfile]:
    out: dict[str, ModuleProfile] = {}
    for key in _PROFILES.available():
        prof = parse_profile(_registered_raw(key))
        for alias in (prof.name, *prof.aliases):
            out.setdefault(_normalise(alias), prof)
    return out


def refresh() -> None:
    """Look the registered profiles up again (after a profile was registered at run time)."""
    _all.cache_clear()


def builtin_raw(name: str) -> RawProfile:
    """The raw TOML dict of a registered profile by name or alias (KeyError if unknown)."""
    wanted = _normalise(name)
    try:
        return _registered_raw(wanted.lower())
    except (KeyError, ValueError):
        pass
    for key in _PROFILES.available():
        module = _registered_raw(key).get("module", {})
        if wanted in {_normalise(str(n)) for n in (module.get("name", ""), *module.get("aliases", ()))}:
            return _registered_raw(key)
    raise KeyError(f"unknown module {name!r}; known: {', '.join(module_names())} or a profile file NAME.toml")


def raw_profile(name_or_path: str) -> RawProfile:
    """The resolved raw dict of a built-in name or a profile file (`extends` applied, checked)."""
    from .profile_file import ProfileError, looks_like_path, resolve, validate

    if not looks_like_path(str(name_or_path)):
        return builtin_raw(name_or_path)
    data = resolve(name_or_path, builtin_raw)
    errors = validate(data)
    if errors:
        raise ProfileError([f"{name_or_path}: {e}" for e in errors])
    return data


def load_profile(name: str | os.PathLike[str]) -> ModuleProfile:
    """Profile by module name or alias ("TMCM-6212", "PD28-1021", "TMCM-1021", "PD86-1180", "TMCM-1180"),
    or by the path of a profile file (ending in .toml or containing a path separator; docs/profiles.md).
    A bad file raises profile_file.ProfileError (a ValueError) with one line per problem."""
    from .profile_file import looks_like_path

    if isinstance(name, os.PathLike):
        name = os.fspath(name)
    if isinstance(name, str) and looks_like_path(name):
        return parse_profile(raw_profile(name))
    try:
        return _all()[_normalise(name)]
    except KeyError:
        raise KeyError(f"unknown module {name!r}; known: {', '.join(module_names())} "
                       "or a profile file NAME.toml") from None


def module_names() -> list[str]:
    """The names of the registered profiles (built-in and from installed distributions)."""
    return sorted({prof.name for prof in _all().values()})
