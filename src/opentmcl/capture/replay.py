"""Replay a capture against a virtual module in virtual time and compare every reply (docs/capture.md).

    report = opentmcl.replay("run.jsonl", module="PD86-1180")
    assert report.ok, report.text()

The captured host requests for one module address are sent to four fresh `VirtualModule`s, the
twins, each started from the module's state at capture start (the capture's snapshot, another
one given, or values inferred from the first reads). The module acted on each request somewhere
between the end of the request on the wire and the start of its reply (capture/timing.py); the
twins act at the ends that bracket what it can have done (capture/twin.py). A reply agrees
when its status and command agree with a twin's, and its value lies in the twins' range of that
value over the interval in which the module could have sampled it, widened by the tolerances.
Tolerances only widen: the twins' runs do not depend on them. Divergences are grouped under their
root causes (capture/causes.py); moves are timed on both sides (capture/moves.py).
"""
from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from ..modules.state import UNREPRODUCIBLE, moving_class
from ..protocol.frame import FRAME_LEN
from ..protocol.opcodes import format_instruction
from ..protocol.status import Status, message
from .causes import Cause, Check, Divergence, group
from .format import Capture, read_capture
from .moves import Move, acceleration_estimates, events_of, find_moves
from .snapshot import Snapshot, SnapshotError, apply_snapshot, snapshot_from_file, snapshot_of
from .timing import CLOCK_LAG, Slot, module_starts, slots
from .twin import GAP, Twin, TwinRun, windowed

if TYPE_CHECKING:
    from ..firmware.vm import VirtualModule
    from ..motion.scenario import Scenario

POLICIES = ("hi", "lo", "early", "late")
"""The twins (capture/twin.py): the highest and lowest positions, the earliest and latest actions."""
DEFAULT_LATENCY = 0.05
"""Seconds a command-138 event may take from the module's arrival to the wire (tolerance `latency`)."""
TOLERANCE_KEYS = ("time", "position", "velocity", "load", "timer", "latency")
AREAS = ("identity", "parameters", "status codes", "move durations", "ramp shape", "programs")
"""The areas scored in the report (an agreement score each)."""
_PROGRAM_COMMANDS = frozenset(range(128, 136))
_PROGRAM_GLOBALS = (128, 129, 130)   # GGP 128 status, 129 download mode, 130 program counter (bank 0)
_IDENTITY = 136


class ReplayError(ValueError):
    """Replay cannot start: bad capture, module, initial state or tolerance (one line)."""


@dataclass
class Tolerance:
    """`time`: seconds added at both ends of every sampling interval; `position`, `velocity`,
    `load`, `timer`: absolute value differences (timer None = not compared: a capture does not
    start at power-up); `latency`: seconds a command-138 event may take to reach the wire."""

    time: float = 0.0
    position: float = 0
    velocity: float = 0
    load: float = 0
    timer: float | None = None
    latency: float = DEFAULT_LATENCY

    @classmethod
    def parse(cls, specs) -> Tolerance:
        """From "KEY=VALUE" strings (also comma-separated), e.g. ["position=20", "time=0.2,load=50"]."""
        out = cls()
        for spec in specs or ():
            for item in str(spec).split(","):
                key, sep, text = item.strip().partition("=")
                if not sep or key not in TOLERANCE_KEYS:
                    raise ReplayError(f"bad tolerance {item!r}; use KEY=VALUE with KEY one of {', '.join(TOLERANCE_KEYS)}")
                try:
                    value = float(text)
                except ValueError:
                    raise ReplayError(f"bad tolerance value in {item!r}") from None
                if not 0 <= value < math.inf:
                    raise ReplayError(f"tolerance {key} must be a finite number >= 0, got {text}")
                setattr(out, key, value)
        return out

    def of(self, klass: str | None) -> float | None:
        """The absolute tolerance of a value class (0 for flags and settings, None: not compared)."""
        if klass in ("position", "velocity", "load", "timer"):
            return getattr(self, klass)
        return 0


@dataclass
class ReplayReport:
    capture: str
    module: str
    address: int
    compared: int = 0
    skipped: int = 0
    events: int = 0
    divergences: list[Divergence] = field(default_factory=list)
    causes: list[Cause] = field(default_factory=list)
    areas: dict[str, list[int]] = field(default_factory=lambda: {a: [0, 0] for a in AREAS})
    """area -> [checks that agree, checks]."""
    moves: list[Move] = field(default_factory=list)
    accelerations: dict[int, dict[str, tuple[float, float]]] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)
    """How the replay started (snapshot, inferred values) and what it could not reproduce."""
    link: dict = field(default_factory=dict)
    tolerance: Tolerance = field(default_factory=Tolerance)
    traces: dict[int, dict[str, Any]] = field(default_factory=dict)
    """axis -> {"module": {"position": [(t, x)], "speed": [(t, v)]}, "twin": [(t, x, v)]}: the plots."""

    @property
    def ok(self) -> bool:
        return not self.divergences

    @property
    def parameters(self) -> list[str]:
        """Names of the parameters that diverged, in order, without repeats."""
        return list(dict.fromkeys(d.parameter for d in self.divergences if d.parameter))

    def score(self, area: str) -> float | None:
        """Share of the checks of `area` that agree (None: nothing checked there)."""
        ok, total = self.areas[area]
        return ok / total if total else None

    def summary(self) -> str:
        verdict = "all replies agree" if self.ok else \
            f"{len(self.divergences)} divergences from {len(self.causes)} root causes"
        return (f"{self.capture}: {self.compared} replies and {self.events} events compared against "
                f"{self.module} at address {self.address}, {self.skipped} records skipped: {verdict}")

    def text(self) -> str:
        """Root causes first, each with its repeats and knock-ons indented; notes; area scores; summary."""
        lines = [f"note: {n}" for n in self.notes]
        for i, cause in enumerate(self.causes, 1):
            if cause.note:
                lines.append(f"cause {i}: {cause.note}")
            lines.append(str(cause.root))
            lines += [f"    {d}  (again)" for d in cause.repeats]
            lines += [f"    {d}  (knock-on)" for d in cause.knock_on]
        scores = [f"{a} {ok}/{total}" for a, (ok, total) in self.areas.items() if total]
        if scores:
            lines.append("agreement: " + ", ".join(scores))
        lines.append(self.summary())
        return "\n".join(lines)


def _req_text(rec: dict) -> str:
    if rec["command"] == _IDENTITY:
        return f"136 {rec['type']} ({'firmware string' if rec['type'] == 0 else 'binary version'})"
    text = format_instruction(rec["command"], rec["type"], rec["motor"], rec["value"])
    return text or f"command {rec['command']} type {rec['type']} motor {rec['motor']} value {rec['value']}"


def _status_value(status: int, value) -> str:
    return f"{status} ({message(status)}) value {value}"


def _value(raw: bytes) -> int:
    return int.from_bytes(raw[4:8], "big", signed=True)


class _Comparer:
    """Compares every captured reply with the twins' runs (see the module doc)."""

    def __init__(self, cap: Capture, profile, address: int, tol: Tolerance, report: ReplayReport) -> None:
        self.cap, self.profile, self.address, self.tol, self.report = cap, profile, address, tol, report
        self.checks: list[Check] = []
        answered = [r["request"] for r in cap.frames if r["kind"] in ("reply", "version", "memory") and "request" in r]
        # A capture cut at its size cap: requests after the last captured reply lost theirs to the cap
        self.last_answered = max(answered, default=0) if cap.truncated is not None else None

    def name(self, rec: dict) -> str | None:
        from .decode import parameter_name

        return parameter_name(self.profile, rec["command"], rec["type"], rec["motor"])

    def area(self, rec: dict, running: bool, status_check: bool) -> str:
        """identity (136), programs (128..135, GGP 128..130), status codes (writes, refused
        requests), ramp shape (moving axis values, RFS STATUS), else parameters."""
        command = rec["command"]
        if command == _IDENTITY:
            return "identity"
        if command in _PROGRAM_COMMANDS or (command == 10 and rec["motor"] == 0 and rec["type"] in _PROGRAM_GLOBALS):
            return "programs"
        if status_check:
            return "status codes"
        if command == GAP and moving_class(self.name(rec)) is not None or command == 13 and rec["type"] == 2:
            return "ramp shape"
        return "parameters"

    def axis_of(self, rec: dict) -> int | None:
        axis_commands = (1, 2, 3, 4, 5, 6, 7, 8, 13, 30, 31)
        if rec["command"] in axis_commands and rec["motor"] < self.profile.axes:
            return rec["motor"]
        return None

    def engine(self, rec: dict) -> bool:
        if rec["command"] not in (5, 6):
            return False
        p = self.profile.axis_parameters.get(rec["type"])
        return p is not None and bool(p.engine)

    def check(self, rec: dict, area: str, ok: bool, d: Divergence | None = None, rest: bool = False,
              running: bool = False) -> None:
        self.report.areas[area][0] += ok
        self.report.areas[area][1] += 1
        axis = self.axis_of(rec)
        if d is not None:
            d.area, d.axis, d.n = area, axis, rec["n"]
            self.report.divergences.append(d)
        write = (rec["command"], rec["type"], rec["motor"]) if rec["command"] in (5, 9, 14) else None
        self.checks.append(Check(float(rec["t"]), area, ok, axis, d, rest, self.engine(rec),
                                 program=area == "programs", write=write))

    def slot(self, slot: Slot, runs: list[TwinRun]) -> None:
        rec, captured = slot.rec, slot.reply
        if rec["kind"] != "request":
            return
        n = rec["n"]
        if any(n in run.skipped for run in runs):
            self.report.skipped += 1
            return
        results = [run.results[n] for run in runs if n in run.results]
        if not results:
            return
        if captured is None and self.last_answered is not None and n > self.last_answered:
            self.report.skipped += 1   # its reply came after the capture stopped
            return
        self.report.compared += 1
        name = self.name(rec)
        if name in UNREPRODUCIBLE:
            return
        raws = [r.raw for r in results]
        running = any(r.running for r in results)
        text = _req_text(rec)

        def diverge(area: str, what: str, cap_text: str, twin_text: str) -> None:
            self.check(rec, area, False, Divergence(float(rec["t"]), text, name, what, cap_text, twin_text),
                       running=running)

        if captured is None:
            if any(raws):
                diverge(self.area(rec, running, True), "reply", "none", next(r for r in raws if r).hex(" "))
            return
        if not any(raws):
            diverge(self.area(rec, running, True), "reply", captured["raw"], "none")
            return
        if captured["kind"] in ("version", "memory") or rec["command"] == 134:
            ok = captured["bytes"] in raws
            area = self.area(rec, running, False)
            if ok:
                self.check(rec, area, True, running=running)
            elif captured["kind"] == "version":
                twins = " / ".join(dict.fromkeys(repr(r[1:].decode("latin-1")) for r in raws if r))
                diverge(area, "firmware string", repr(captured.get("version")), twins)
            else:
                diverge(area, "reply", captured["raw"], " / ".join(dict.fromkeys(r.hex(" ") for r in raws if r)))
            return
        full = [r for r in raws if len(r) == FRAME_LEN]
        c_status, c_value = captured["status"], captured["value"]
        same = [r for r in full if r[2] == c_status and r[3] == captured["command"]]
        write = not windowed(rec, self.profile) and rec["command"] != _IDENTITY
        if not same:
            r = full[0] if full else raws[0]
            twin = _status_value(r[2], _value(r)) if len(r) == FRAME_LEN else r.hex(" ")
            diverge(self.area(rec, running, True), "status", _status_value(c_status, c_value), twin)
            return
        if same[0][:2] != captured["bytes"][:2]:
            diverge(self.area(rec, running, True), "reply address", captured["raw"][:5], same[0][:2].hex(" "))
            return
        if write:   # a write, a motion or control command: its status and the value it returns
            values = list(dict.fromkeys(_value(r) for r in same))
            area = self.area(rec, running, True)
            if c_value in values:
                self.check(rec, area, True, running=running)
            else:
                diverge(area, "value", str(c_value), " / ".join(map(str, values)))
            return
        self.compare_value(rec, name, results, c_status, c_value, running, diverge)

    def compare_value(self, rec, name, results, c_status, c_value, running, diverge) -> None:
        """A read: the captured value against the twins' range over its interval."""
        area = self.area(rec, running, False)
        if c_status != Status.OK:
            self.check(rec, "status codes", True, running=running)
            return
        klass = moving_class(name)
        tol = self.tol.of(klass)
        if tol is None:
            return
        lows = [r.lo for r in results if r.lo is not None]
        highs = [r.hi for r in results if r.hi is not None]
        if not lows:
            return
        lo, hi = min(lows), max(highs)
        rest = False
        if rec["command"] == GAP and rec["type"] == 1:
            rest = lo == hi
        if lo - tol <= c_value <= hi + tol:
            self.check(rec, area, True, rest=rest, running=running)
            return
        twin = str(lo) if lo == hi else f"{lo}..{hi}"
        if tol:
            twin += f" (+/-{tol:g})"
        diverge(area, "value", str(c_value), twin)

    def events(self, starts: dict[int, float], runs: list[TwinRun]) -> None:
        expected = events_of(self.cap.frames, starts, self.address)
        lists = [[(t, raw) for t, raw in run.events] for run in runs]
        self.report.events += len(expected)
        for i, (start, ev) in enumerate(expected):
            rec = {**ev, "command": 138, "type": 0, "motor": 0, "n": ev["n"]}
            got = [lst[i] for lst in lists if i < len(lst)]

            def event_div(what: str, cap_text: str, twin_text: str, rec=rec, ev=ev) -> None:
                self.check(rec, "move durations", False,
                           Divergence(float(ev["t"]), "event (command 138)", None, what, cap_text, twin_text))

            if not got:
                event_div("event", f"motor mask {ev['value']}", "no event")
                continue
            masks = {_value(raw) for _, raw in got}
            if ev["value"] not in masks or any(raw[2] != ev["status"] for _, raw in got):
                event_div("event", f"motor mask {ev['value']}", f"motor mask {sorted(masks)[0]}")
                continue
            lo, hi = min(t for t, _ in got), max(t for t, _ in got)
            earliest = start - self.tol.latency - self.tol.time
            if hi < earliest or lo > start + self.tol.time:
                event_div("event time", f"{start:.6f} s on the wire", f"{lo:.6f}..{hi:.6f} s")
            else:
                self.check(rec, "move durations", True)
        extra = max((len(lst) for lst in lists), default=0)
        for i in range(len(expected), extra):
            lst = next(lst for lst in lists if len(lst) > i)
            t, raw = lst[i]
            if self.cap.truncated is not None and t >= self.cap.truncated:
                continue   # after the capture stopped at its size cap
            if all(len(other) > i for other in lists):
                rec = {"command": 138, "type": 0, "motor": 0, "n": None, "t": t}
                self.check(rec, "move durations", False, Divergence(t, "event (command 138)", None, "event",
                                                                   "no event", f"motor mask {_value(raw)}"))

    def moves(self, moves: list[Move]) -> None:
        for m in moves:
            rec = {"command": 4, "type": 0, "motor": m.axis, "n": m.n, "t": m.t}
            if m.ok:
                self.check(rec, "move durations", True)
                continue
            twin = "no end" if m.twin is None else f"{m.twin[0]:.3f}..{m.twin[1]:.3f} s"
            self.check(rec, "move durations", False,
                       Divergence(m.t, m.request, None, "duration", f"{m.real[0]:.3f}..{m.real[1]:.3f} s", twin))


def first_address(cap: Capture) -> int | None:
    """The address of the first request that got a reply, else of the first request."""
    answered = {r.get("request") for r in cap.frames if r["kind"] != "request"}
    for rec in cap.frames:
        if rec["kind"] == "request" and rec["n"] in answered:
            return rec["address"]
    for rec in cap.frames:
        if rec["kind"] == "request":
            return rec["address"]
    return None


def _sim_profile_file(target, address: int | None) -> str | None:
    """The profile file of a `sim://` capture target (at `address`, else the first), if any."""
    import urllib.parse

    from ..host.errors import TmclConnectionError
    from ..host.transports.inprocess import _parse_modules
    from ..modules.profile_file import looks_like_path

    if not isinstance(target, str) or not target.startswith("sim://"):
        return None
    url = urllib.parse.urlsplit(target)
    spec = url.netloc + url.path if ".toml" in url.path.lower() else (url.netloc or url.path.lstrip("/"))
    try:
        specs = _parse_modules(spec, 1)
    except TmclConnectionError:  # a target the proxy could not have opened: keep the identity
        return None
    for name, at in specs:
        if looks_like_path(name) and (address is None or at == address):
            return name
    return None


def _tolerance(tolerance: Tolerance | dict | list | None) -> Tolerance:
    """A Tolerance from itself, a {key: value} dict or "KEY=VALUE" strings (default: None)."""
    if isinstance(tolerance, dict):
        return Tolerance.parse([f"{k}={v}" for k, v in tolerance.items()])
    if isinstance(tolerance, Tolerance):
        return tolerance
    return Tolerance.parse(tolerance)


def _binary_version(cap: Capture) -> int | None:
    """The value of the first successful reply to 136 type 1 (the binary version), if any."""
    requests = {r["n"]: r for r in cap.frames if r["kind"] == "request"}
    for rec in cap.frames:
        req = requests.get(rec.get("request")) if rec["kind"] == "reply" else None
        if req is not None and req["command"] == _IDENTITY and req["type"] == 1 and rec.get("status") == 100:
            return int(rec["value"])
    return None


def _captured_module(cap: Capture, address: int | None, notes: list[str]) -> str:
    """The module the capture identified, the profile file of its `sim://` target, else the
    built-in profile of the same module number (firmware string or 136 type 1), as `profile probe`."""
    from ..host.probe import closest_builtin
    from ..modules.profile import module_names

    snap = snapshot_of(cap, address)
    module = cap.module_name() or (snap.module if snap is not None else None)
    if module is None or module not in module_names():  # e.g. proxy --to sim:///path/my.toml
        module = _sim_profile_file(cap.header.get("target"), address) or module
    if module is not None and (module in module_names() or module.lower().endswith(".toml")):
        return module
    versions = [i.get("firmware_version") for i in cap.identities if isinstance(i.get("firmware_version"), str)]
    versions += [r["version"] for r in cap.frames if r["kind"] == "version" and isinstance(r.get("version"), str)]
    if snap is not None and snap.firmware_version:
        versions.append(snap.firmware_version)
    binary = _binary_version(cap)
    base = closest_builtin(versions[0] if versions else None, binary)
    if base is None:
        raise ReplayError(f"{cap.path}: the capture does not identify its module; name one (--module)")
    seen = repr(versions[0]) if versions else f"binary version {binary:#x}"
    notes.append(f"firmware {seen} matches no built-in profile: replaying against {base.name}, the same "
                 "module number (give --module to choose)")
    return base.name


def _virtual_module(module: str | os.PathLike, address: int, eeprom: str | os.PathLike | None,
                    scenario: Scenario | str | os.PathLike | None) -> VirtualModule:
    """A fresh virtual module for the replay; ReplayError (one line) if it cannot be built."""
    from ..firmware.eeprom import EepromError
    from ..firmware.vm import VirtualModule

    if isinstance(scenario, (str, os.PathLike)):
        from ..motion.scenario import load_scenario

        scenario = load_scenario(scenario)
    try:
        return VirtualModule(os.fspath(module), address=address, eeprom=eeprom, scenario=scenario)
    except KeyError as exc:
        raise ReplayError(str(exc.args[0]) if exc.args else f"unknown module {module!r}") from None
    except (EepromError, ValueError) as exc:
        raise ReplayError(str(exc)) from None


_INFERRED = {(GAP, 0): "target_position", (GAP, 1): "actual_position", (GAP, 209): "encoder_position"}


def inferred_state(cap_slots: list[Slot], profile, address: int) -> tuple[Snapshot, list[str]]:
    """Without a snapshot: the positions (AP0, AP1, AP209) an axis reported before anything moved
    or set it, taken as its state at capture start; the notes say which."""
    snap = Snapshot(address, source="inferred")
    touched: set[int] = set()
    notes = []
    for slot in cap_slots:
        rec, reply = slot.rec, slot.reply
        if rec["kind"] != "request" or rec["address"] != address:
            continue
        motor = rec["motor"]
        if rec["command"] in (1, 2, 3, 4, 5, 13) or rec["command"] >= 128:
            touched.add(motor if rec["command"] < 128 else -1)
            continue
        if -1 in touched or motor in touched or motor >= profile.axes:
            continue
        key = (rec["command"], rec["type"])
        if key in _INFERRED and reply is not None and reply.get("status") == 100 \
                and rec["type"] not in snap.axis.get(motor, {}):
            snap.axis.setdefault(motor, {})[rec["type"]] = int(reply["value"])
            if reply["value"]:
                notes.append(f"axis {motor} {_INFERRED[key]} = {reply['value']} (inferred from its first "
                             f"read at t={float(rec['t']):.3f} s)")
    return snap, notes


def _initial_state(cap: Capture, cap_slots: list[Slot], profile, address: int,
                   initial_state, notes: list[str]) -> Snapshot:
    if isinstance(initial_state, Snapshot):
        notes.append(f"initial state: {initial_state.source or 'given'} ({initial_state.count()} values)")
        return initial_state
    if initial_state is not None:
        try:
            snap = snapshot_from_file(initial_state, address)
        except SnapshotError as exc:
            raise ReplayError(str(exc)) from None
        notes.append(f"initial state: {os.fspath(initial_state)} ({snap.count()} values)")
        return snap
    found = snapshot_of(cap, address)
    if found is not None:
        part = "" if found.complete else ", cut off before its end"
        notes.append(f"initial state: the capture's snapshot at t={found.t:.3f} s ({found.count()} values{part})")
        return found
    snap, inferred = inferred_state(cap_slots, profile, address)
    notes.append("no snapshot in the capture: the twin starts from power-up"
                 + (" with values inferred from the first reads" if inferred else ""))
    notes.extend(inferred)
    return snap


IDLE = 10.0
"""Seconds a twin may stand before the capture: longer than the longest power-down delay of the
profiles (TMCM-6212 AP214: 4.17 s), after which a standing motor gets its standby current."""


def _readings(snap: Snapshot, vm) -> tuple[int, int]:
    """(read-only axis values of the snapshot the twin reads alike, those it reads otherwise)."""
    same = other = 0
    for motor, values in snap.axis.items():
        for number, value in values.items():
            p = vm.profile.axis_parameters.get(number)
            if p is None or p.writable or motor >= vm.profile.axes or moving_class(p.name) not in ("load", "flag"):
                continue
            reply = vm.request(GAP, number, motor, 0)
            if reply is not None and reply.status == 100:
                same, other = (same + 1, other) if reply.value == value else (same, other + 1)
    return same, other


def _idle(make_vm, snap: Snapshot, start: float, scope: str, notes: list[str]) -> float:
    """How long the twins stand before the capture: 0, or IDLE when the snapshot's read-only
    readings (load, flags: a motor at standby current, AP180) agree better with a twin that has
    stood that long. A capture seldom starts right after power-up; the snapshot says which."""
    if not any(snap.axis.values()):
        return 0.0
    scores = []
    for idle in (0.0, IDLE):
        vm = make_vm()
        try:
            vm.advance(idle + start)
            apply_snapshot(vm, snap, scope=scope)
            scores.append(_readings(snap, vm))
        finally:
            vm.close()
    if scores[1][1] < scores[0][1]:
        notes.append(f"the twins stood {IDLE:g} s before the capture: the snapshot's readings (standby "
                     f"current, flags) agree with that in {scores[1][0]} of {sum(scores[1])} values")
        return IDLE
    return 0.0


def _real_traces(cap_slots: list[Slot], address: int, axes: set[int]) -> dict[int, dict[str, list]]:
    """The module's positions and speeds as the host read them (middle of each window)."""
    out: dict[int, dict[str, list]] = {m: {"position": [], "speed": []} for m in axes}
    for slot in cap_slots:
        rec, reply = slot.rec, slot.reply
        if rec["kind"] != "request" or rec["address"] != address or rec["command"] != GAP or reply is None \
                or reply.get("status") != 100 or rec["motor"] not in out or rec["type"] not in (1, 3):
            continue
        key = "position" if rec["type"] == 1 else "speed"
        out[rec["motor"]][key].append(((slot.e + slot.s) / 2, int(reply["value"])))
    return out


def replay(capture: str | os.PathLike | Capture, module: str | os.PathLike | None = None, *,
           address: int | None = None, eeprom: str | os.PathLike | None = None, scenario=None,
           tolerance: Tolerance | dict | list | None = None, initial_state=None,
           state_scope: str = "all", clock_lag: float = CLOCK_LAG) -> ReplayReport:
    """Replay `capture` (a path or a read `Capture`) against fresh virtual twins of `module` (a name
    or a profile file; default: the module the capture identified, else the built-in profile of
    the same module number). `initial_state`: a `Snapshot` or a file (a capture with a snapshot, a
    probed profile with [snapshot]); default: the capture's snapshot, else values inferred from
    the first reads. `state_scope` "state" starts the twins only where the module was (positions),
    not from its settings (`opentmcl conform`). `clock_lag`: seconds the module's clock may trail
    the host's (capture/timing.py; it shapes the twins' runs, so it is no tolerance). Returns a
    `ReplayReport`.
    Raises ReplayError (bad module, address, initial state or tolerance) or CaptureError (bad file)."""
    cap = capture if isinstance(capture, Capture) else read_capture(capture)
    tol = _tolerance(tolerance)
    notes: list[str] = list(cap.warnings)
    if module is None:
        module = _captured_module(cap, address, notes)
    if address is None:
        address = first_address(cap)
        if address is None:
            raise ReplayError(f"{cap.path}: no host request in the capture")
    if not 0 <= clock_lag < 1:
        raise ReplayError(f"clock lag must be 0 <= seconds < 1, got {clock_lag!r}")
    cap_slots = slots(cap, clock_lag)
    motion_axes = {s.rec["motor"] for s in cap_slots if s.rec["kind"] == "request" and s.rec["address"] == address
                   and s.rec["command"] in (1, 2, 3, 4, 13)}
    vms = [_virtual_module(module, address, eeprom, scenario) for _ in POLICIES]
    report = ReplayReport(cap.path, vms[0].profile.name, address, link=cap.link, tolerance=tol)
    try:
        snap = _initial_state(cap, cap_slots, vms[0].profile, address, initial_state, notes)
        # the state applies from its own instant in this capture, else from the start; never after a request
        start = min([snap.t if initial_state is None else 0.0, *(s.e for s in cap_slots[:1])])
        idle = _idle(lambda: _virtual_module(module, address, eeprom, scenario), snap, start, state_scope, notes)
        runs = []
        for vm, policy in zip(vms, POLICIES, strict=True):
            twin = Twin(vm, policy, tol.time, motion_axes, idle)
            twin.start(start)
            applied = apply_snapshot(vm, snap, scope=state_scope)
            if policy == POLICIES[0]:
                notes.extend(applied)
            runs.append(twin.go(cap_slots))
    finally:
        for vm in vms:
            vm.close()
    widened = sum(1 for s in cap_slots if s.widened)
    if widened:
        notes.append(f"{widened} round trips were shorter than the link's wire time: their window is the whole "
                     "round trip (a pty or USB port that ignores the baud rate?)")
    report.notes = notes
    comparer = _Comparer(cap, vms[0].profile, address, tol, report)
    for slot in cap_slots:
        comparer.slot(slot, runs)
    if report.compared == 0:  # nothing checked is no evidence: not "all replies agree"
        seen = sorted({r["address"] for r in cap.frames if r["kind"] == "request" and "address" in r})
        raise ReplayError(f"{cap.path}: no request to address {address} in the capture "
                          f"(requests go to {', '.join(map(str, seen)) or 'no address'})")
    starts = module_starts(cap)
    comparer.events(starts, runs)
    report.moves = find_moves(cap_slots, events_of(cap.frames, starts, address), runs, address, tol.time)
    comparer.moves(report.moves)
    report.accelerations = acceleration_estimates(report.moves)
    report.divergences.sort(key=lambda d: d.t)
    report.causes = group(comparer.checks)
    _diagnose(report)
    real = _real_traces(cap_slots, address, motion_axes)
    report.traces = {m: {"module": real[m], "twin": runs[0].trace.get(m, [])} for m in sorted(motion_axes)}
    return report


def _diagnose(report: ReplayReport) -> None:
    """A note on motion causes: the accelerations measured on both sides and the move durations."""
    for cause in report.causes:
        axis = cause.root.axis
        if cause.area not in ("ramp shape", "move durations") or axis is None:
            continue
        parts = []
        for kind, (real, twin) in sorted(report.accelerations.get(axis, {}).items()):
            if twin and abs(real - twin) / twin > 0.05:
                parts.append(f"{kind} about {real:.0f} pps^2 on the module, {twin:.0f} on the twin")
        durations = [m.percent for m in report.moves if m.axis == axis and m.percent is not None and not m.ok]
        if durations:
            parts.append(f"moves {sum(durations) / len(durations):+.0f}% on average")
        cause.note = "; ".join(parts)


def assert_replays(capture, module=None, **kwargs) -> ReplayReport:
    """For a user's own tests: replay and fail with every divergence listed."""
    report = replay(capture, module, **kwargs)
    if not report.ok:
        raise AssertionError(report.text())
    return report
