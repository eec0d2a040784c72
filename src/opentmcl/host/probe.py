"""Ask a module which parameters and ports it has, with reading commands only (docs/profiles.md).

Only GAP (6), GGP (10), GIO (15) and command 136 are sent: the module is never written to. A
number exists when the module answers status 100; "wrong type" (3) or "invalid value" (4) means it
does not. Axes are counted by reading axis parameter 1 on motor 0, 1, ... until one is refused.
Every request has a time-out and the whole probe a deadline, so it always ends.
"""
from __future__ import annotations

import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import asdict, dataclass, field
from typing import TYPE_CHECKING

from ..modules.profile import STORABLE_USER_VARIABLES, load_profile
from ..modules.state import SNAPSHOT_TABLES, is_state
from ..protocol.opcodes import COMMANDS, GET_FIRMWARE_VERSION, Op
from .client import Client, VersionReply
from .errors import TmclError, TmclStatusError, TmclTimeout

if TYPE_CHECKING:
    from ..modules.profile import IOPort, ModuleProfile, Param

_GAP, _GGP, _GIO = int(Op.GAP), int(Op.GGP), int(Op.GIO)  # plain ints, which `Client.request` keeps ready
GLOBAL_BANKS = (0, 2, 3)
IO_BANKS = (0, 1, 2)
NUMBERS = range(256)
PORTS = range(255)
"""Port 255 reads a whole bank as a bit mask (PD86-1180 manual 4.6.14): not a port of its own."""
MAX_AXES = 16
GUESSED_OPCODES = tuple(n for n in COMMANDS if n <= Op.ACO or Op.STOP_APPLICATION <= n <= Op.REQUEST_TARGET_REACHED_EVENT)
"""The command set written for a firmware no built-in profile matches (a guess the user edits):
the commands up to ACO 39 of the manuals' overviews (TMCM-6212 3.4.1, PD86-1180 4.4.1) and the
control commands with 138 (TMCM-6212 3.6.35, 3.6.36)."""


class ProbeError(TmclError):
    """The probe could not finish (link lost, deadline passed)."""


@dataclass
class ProbeResult:
    firmware_version: str
    firmware_binary: int | None
    axes: int
    axis: dict[int, dict[int, int]] = field(default_factory=dict)        # motor -> number -> value
    globals: dict[tuple[int, int], int] = field(default_factory=dict)    # (bank, number) -> value
    io: dict[tuple[int, int], int] = field(default_factory=dict)         # (bank, port) -> value


Progress = Callable[[str], None]
Counted = Callable[[int, int], None]
"""(requests sent, requests the probe will send; 0 while the axes are being counted)."""
TomlValue = str | int | bool | Sequence["TomlValue"]


class _Asker:
    def __init__(self, client: Client, deadline: float, progress: Progress, counted: Counted | None) -> None:
        self.client, self.deadline, self.progress, self.counted = client, deadline, progress, counted
        self.requests = 0
        self.total = 0

    def read(self, command: int, type_: int, motor: int) -> int | None:
        if time.monotonic() > self.deadline:
            raise ProbeError(f"probe took longer than its time limit ({self.requests} requests sent)")
        self.requests += 1
        if self.counted is not None:
            self.counted(self.requests, self.total)
        for attempt in range(3):
            try:
                return self.client.reply(command, type_, motor, 0).value
            except TmclStatusError:
                return None
            except TmclTimeout:
                if attempt == 2:
                    raise ProbeError(f"no reply to command {command} type {type_} motor {motor} "
                                     "three times: is the module connected?") from None
        return None


def _no_progress(text: str) -> None:
    return None


def _version_string(client: Client) -> str:
    """Command 136 type 0, the version string (PD86-1180 manual 4.6.39)."""
    try:
        reply = client.request(GET_FIRMWARE_VERSION, 0, 0, 0)
    except TmclError as exc:
        raise ProbeError(f"the module does not answer command 136 (firmware version): {exc}") from None
    if not isinstance(reply, VersionReply):  # pragma: no cover - Client.request returns one for 136 type 0
        raise ProbeError(f"unexpected reply to command 136 type 0: {reply!r}")
    return reply.text


def _version_binary(client: Client) -> int | None:
    """Command 136 type 1, the version number; None when the module refuses it."""
    try:
        return client.reply(GET_FIRMWARE_VERSION, 1, 0, 0).value
    except TmclStatusError:
        return None
    except TmclError as exc:  # the string reply carries no module address; this one does (USB: GP66)
        raise ProbeError(f"the module answers command 136 type 0 but not type 1 at this address ({exc}); "
                         "on USB every address reaches the module, which replies with its own (GP66): "
                         "give that --address") from None


def probe(client: Client, *, max_seconds: float = 300.0, progress: Progress = _no_progress,
          counted: Counted | None = None) -> ProbeResult:
    """Probe the module `client` talks to (its default address). `progress` gets a line per axis
    and bank, `counted` (requests sent, requests in all) each read request, e.g. for a progress bar."""
    ask = _Asker(client, time.monotonic() + max_seconds, progress, counted)
    version = _version_string(client)
    binary = _version_binary(client)
    progress(f"firmware {version!r}")
    axes = 0
    while axes < MAX_AXES and ask.read(_GAP, 1, axes) is not None:
        axes += 1
    result = ProbeResult(version, binary, axes)
    ask.total = ask.requests + len(NUMBERS) * (axes + len(GLOBAL_BANKS)) + len(PORTS) * len(IO_BANKS)
    for motor in range(axes):
        axis = {n: v for n in NUMBERS if (v := ask.read(_GAP, n, motor)) is not None}
        result.axis[motor] = axis
        progress(f"axis {motor}: {len(axis)} axis parameters")
    for bank in GLOBAL_BANKS:
        found = {(bank, n): v for n in NUMBERS if (v := ask.read(_GGP, n, bank)) is not None}
        result.globals.update(found)
        progress(f"bank {bank}: {len(found)} global parameters")
    for bank in IO_BANKS:
        ports = {(bank, p): v for p in PORTS if (v := ask.read(_GIO, p, bank)) is not None}
        result.io.update(ports)
        progress(f"I/O bank {bank}: {len(ports)} ports")
    progress(f"done: {ask.requests} read requests")
    return result


def closest_builtin(version: str | None, binary: int | None = None) -> ModuleProfile | None:
    """The built-in profile with this firmware string, else one with the same module number
    (the characters before 'V', e.g. 6212 of 6212V105; `profile_for_version`), else one whose
    binary version (command 136 type 1) has the same module number in its upper 16 bits
    (0x1844 = 6212 of 0x18440105), else None."""
    from ..modules.profile import module_names
    from .module import profile_for_version

    if version is not None:
        try:
            return profile_for_version(version)
        except TmclError:
            pass
    if binary is not None:
        for name in module_names():
            prof = load_profile(name)
            if prof.firmware_binary >> 16 == (binary & 0xFFFF_FFFF) >> 16:
                return prof
    return None


def _toml(value: TomlValue) -> str:
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(value, list):
        return "[" + ", ".join(_toml(v) for v in value) + "]"
    return str(value).lower() if isinstance(value, bool) else str(value)


def _table(name: str, fields: Mapping[str, TomlValue]) -> list[str]:
    return ["", f"[[{name}]]", *(f"{k} = {_toml(v)}" for k, v in fields.items())]


_UNKNOWN: dict[str, TomlValue] = {"min": -2147483648, "max": 2147483647, "access": "R"}
_IO_KINDS = {0: "digital", 1: "analog", 2: "output"}
USER_VARIABLE_BANK = 2


@dataclass
class _Known:
    """What the base profile already says: axis parameters, global parameters and I/O ports."""

    axis: dict[int, Param] = field(default_factory=dict)
    globals: dict[tuple[int, int], Param] = field(default_factory=dict)
    io: dict[tuple[int, int], IOPort] = field(default_factory=dict)


@dataclass
class _Skeleton:
    """The profile file being written: `[[...]]` tables, comments for values the base already has,
    and the rows of the `[snapshot]` section (state values: modules/state.py)."""

    body: list[str] = field(default_factory=list)
    comments: list[str] = field(default_factory=list)
    snapshot: dict[str, list[list[int]]] = field(default_factory=lambda: {k: [] for k in SNAPSHOT_TABLES})


def _state_numbers() -> tuple[set[int], set[tuple[int, int]]]:
    """Axis numbers and (bank, number) keys that are state in every built-in profile naming them:
    what a parameter of a new module with the same number most likely is."""
    from ..modules.profile import module_names

    axis: dict[int, bool] = {}
    glob: dict[tuple[int, int], bool] = {}
    for name in module_names():
        prof = load_profile(name)
        for n, p in prof.axis_parameters.items():
            axis[n] = axis.get(n, True) and is_state(p.name)
        for k, p in prof.global_parameters.items():
            glob[k] = glob.get(k, True) and is_state(p.name)
    return {n for n, v in axis.items() if v}, {k for k, v in glob.items() if v}


def _header(url: str) -> list[str]:
    when = time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())
    return [f"# Profile skeleton probed from {url} on {when} by opentmcl profile probe.",
            "# UNVERIFIED: only reading commands were used; ranges, access letters and units of parameters",
            "# the base profile does not know are placeholders. Check them against the module's manual.",
            "# Writable parameters whose probed value differs from the base default override it; state values",
            "# (positions, encoder, timers, random number, I/O) go to [snapshot], never to the defaults; every",
            "# other probed value is listed as a comment at the end (read-only values are measurements)."]


def _extending_module(result: ProbeResult, base: ModuleProfile) -> list[str]:
    """`extends` the base profile; the [module] table lists only what differs from it."""
    lines = [f'extends = "{base.name}"', "", "[module]", f'name = "{base.name}-probed"',
             f"firmware_version = {_toml(result.firmware_version)}"]
    if result.firmware_binary is not None and result.firmware_binary != base.firmware_binary:
        lines.append(f"firmware_binary = {result.firmware_binary}")
    if result.axes != base.axes:
        lines.append(f"axes = {result.axes}")
    return lines


def _standalone_module(result: ProbeResult) -> list[str]:
    """A [module] table of its own, for a firmware no built-in profile matches."""
    return ["", "[module]", f'name = "{result.firmware_version}"', "aliases = []",
            f"axes = {max(1, result.axes)}", 'engine = "linear"',
            f"firmware_version = {_toml(result.firmware_version)}",
            f"firmware_binary = {result.firmware_binary or 0}", "program_memory = 2048",
            "opcodes = " + _toml(list(GUESSED_OPCODES)),
            *_linear_capabilities()]


def _overrides_default(p: Param, value: int) -> bool:
    """A writable parameter whose probed value is a valid default other than the base's."""
    return p.writable and p.default != value and p.min <= value <= p.max


def _axis_parameters(out: _Skeleton, axes: dict[int, dict[int, int]], known: dict[int, Param],
                     state: set[int]) -> None:
    """Axis parameters of motor 0 (GAP n, 0): new ones, changed defaults, the rest as comments;
    state values of every axis go to the snapshot section, never to the defaults."""
    for motor, values in sorted(axes.items()):
        for number, value in sorted(values.items()):
            p = known.get(number)
            if (is_state(p.name) if p is not None else number in state):
                out.snapshot["axis_parameter"].append([motor, number, value])
    for number, value in sorted(axes.get(0, {}).items()):
        p = known.get(number)
        if (is_state(p.name) if p is not None else number in state):
            continue
        if p is None:
            out.body += _table("axis_parameter", {"number": number, "name": f"axis_parameter_{number}",
                                                  **_UNKNOWN, "default": value})
        elif _overrides_default(p, value):
            out.body += _table("axis_parameter", {"number": number, "default": value})
        else:
            out.comments.append(f"# GAP {number}, 0 = {value}  ({p.name})")


def _global_parameters(out: _Skeleton, probed: dict[tuple[int, int], int],
                       known: dict[tuple[int, int], Param], state: set[tuple[int, int]]) -> None:
    """Global parameters (GGP n, bank); user variables (bank 2) the base does not name are skipped;
    state values (tick timer, random number, program status) go to the snapshot section."""
    for (bank, number), value in sorted(probed.items()):
        if bank == USER_VARIABLE_BANK and (bank, number) not in known:
            continue  # user variables (bank 2) are counted, not listed
        p = known.get((bank, number))
        if (is_state(p.name) if p is not None else (bank, number) in state):
            out.snapshot["global_parameter"].append([bank, number, value])
            continue
        if p is None:
            out.body += _table("global_parameter", {"bank": bank, "number": number,
                                                    "name": f"global_parameter_{bank}_{number}", **_UNKNOWN,
                                                    "default": value})
        elif _overrides_default(p, value):
            out.body += _table("global_parameter", {"bank": bank, "number": number, "default": value})
        else:
            out.comments.append(f"# GGP {number}, {bank} = {value}  ({p.name})")


def _io_ports(out: _Skeleton, probed: dict[tuple[int, int], int], known: dict[tuple[int, int], IOPort]) -> None:
    """Ports (GIO port, bank) the base does not know become [[io]] tables; every value read goes to
    the snapshot section (inputs and outputs are state)."""
    for (bank, port), value in sorted(probed.items()):
        if (bank, port) not in known:
            out.body += _table("io", {"bank": bank, "port": port, "name": f"IO_{bank}_{port}",
                                      "kind": _IO_KINDS[bank], "access": "R" if bank < 2 else "RW",
                                      "min": 0, "max": max(1, value)})
        out.snapshot["io"].append([bank, port, value])


def _removed(result: ProbeResult, known: _Known) -> list[str]:
    """The [remove] table: readable entries of the base profile the module did not answer."""
    axis0 = result.axis.get(0, {})
    removed: dict[str, TomlValue] = {
        "axis_parameter": [n for n, p in sorted(known.axis.items()) if p.readable and n not in axis0],
        "global_parameter": [[b, n] for (b, n), p in sorted(known.globals.items())
                             if p.readable and b in GLOBAL_BANKS and (b, n) not in result.globals],
        "io": [[b, n] for (b, n), p in sorted(known.io.items()) if "R" in p.access and (b, n) not in result.io],
    }
    removed = {k: v for k, v in removed.items() if v}
    return ["", "[remove]", *(f"{k} = {_toml(v)}" for k, v in removed.items())] if removed else []


def _linear_capabilities() -> list[str]:
    """[module.capabilities] of a standalone skeleton: the linear-engine PD28-1021's (docs/profiles.md)."""
    caps = asdict(load_profile("PD28-1021").capabilities)
    return ["", "[module.capabilities]", *(f"{k} = {_toml(v)}" for k, v in caps.items())]


def skeleton(result: ProbeResult, url: str) -> str:
    """A profile file for the probed module: `extends` the closest built-in profile and overrides
    what differs, or a standalone profile when none matches. Marked unverified."""
    base = closest_builtin(result.firmware_version, result.firmware_binary)
    lines = _header(url)
    if base is not None:
        lines += _extending_module(result, base)
        known = _Known(base.axis_parameters, base.global_parameters, base.io)
    else:
        lines += _standalone_module(result)
        known = _Known()
    out = _Skeleton()
    state_axis, state_globals = _state_numbers()
    _axis_parameters(out, result.axis, known.axis, state_axis)
    _global_parameters(out, result.globals, known.globals, state_globals)
    _io_ports(out, result.io, known.io)
    user_vars = sum(1 for bank, _ in result.globals if bank == USER_VARIABLE_BANK)
    if base is None or user_vars != base.user_variables:
        lines.insert(lines.index("[module]") + 1, f"user_variables = {user_vars}")
        storable = STORABLE_USER_VARIABLES if base is None else base.storable_user_variables
        if user_vars < storable:   # no more storable variables than variables (docs/profiles.md)
            lines.insert(lines.index("[module]") + 2, f"storable_user_variables = {user_vars}")
    body = out.body + _removed(result, known) + _snapshot_section(out, result)
    return "\n".join(lines + body + ["", "# Probed values equal to the base profile:", *out.comments]) + "\n"


def _snapshot_section(out: _Skeleton, result: ProbeResult) -> list[str]:
    """`[snapshot]`: where the module was when probed (positions, encoder, timers, random number,
    I/O): never defaults; `replay --initial-state FILE` starts a twin from it (docs/capture.md)."""
    lines = ["", "# Where the module was when probed: state, not defaults (opentmcl replay --initial-state).",
             "[snapshot]", f"firmware_version = {_toml(result.firmware_version)}"]
    for key, rows in out.snapshot.items():
        if rows:
            lines.append(f"{key} = [")
            lines += [f"  {_toml(row)}," for row in rows]
            lines.append("]")
    return lines
