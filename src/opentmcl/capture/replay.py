"""Replay a capture against a virtual module in virtual time and compare every reply (docs/capture.md).

    report = opentmcl.replay("run.jsonl", module="PD86-1180")
    assert report.ok, report.text()

The captured host requests for one module address are sent to a fresh `VirtualModule` at their
captured instants (the module's clock jumps there; nothing waits). Each virtual reply is compared
with the captured one: status, command and value, and the whole frame for special replies (136,
134). Values that move with time are compared within a time window: the captured value agrees
when it lies between the smallest and the largest virtual value read at t - window, t and
t + window, widened by the absolute tolerance of its class (position, velocity, load, timer).
Event replies of command 138 are compared in order: same motor mask, not later than the captured
instant + window, not earlier than the captured instant - window.
"""
from __future__ import annotations

import math
import os
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from ..motion import CLOCK_HZ
from ..protocol.frame import FRAME_LEN
from ..protocol.opcodes import format_instruction
from ..protocol.status import Status, message
from .format import Capture, read_capture

if TYPE_CHECKING:
    from ..firmware.vm import VirtualModule
    from ..motion.scenario import Scenario

CLASSES = {
    "position": ("actual_position", "encoder_position", "absolute_encoder_value", "last_reference_position"),
    "velocity": ("actual_speed", "measured_speed", "actual_acceleration"),
    "load": ("actual_load_value", "smartenergy_actual_current"),
    "timer": ("tick_timer",),
    "flag": ("position_reached", "left_limit_switch", "right_limit_switch", "home_switch",
             "driver_error_flags", "extended_error_flags", "tmcl_program_counter", "tmcl_application_status"),
}
"""Time-dependent parameters by class; `flag`s get the window but no absolute tolerance."""
IGNORED = ("random_number",)
"""Parameters whose value cannot be reproduced (GGP 129 random number): never compared."""
DEFAULT_WINDOW = 0.1
TOLERANCE_KEYS = ("time", "position", "velocity", "load", "timer")
_READS = (6, 10, 15)  # GAP, GGP, GIO
_RFS, _RFS_STATUS, _APP_STATUS = 13, 2, 135


class ReplayError(ValueError):
    """Replay cannot start: bad capture, module or tolerance (one line)."""


@dataclass
class Tolerance:
    """`time`: seconds either side of the captured instant; the others: absolute value differences
    (None = not compared). Timers are not compared by default: a capture does not start at power-up."""

    time: float = DEFAULT_WINDOW
    position: float = 0
    velocity: float = 0
    load: float = 0
    timer: float | None = None

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


@dataclass
class Divergence:
    t: float
    request: str
    parameter: str | None
    what: str
    captured: str
    virtual: str

    def __str__(self) -> str:
        name = f" [{self.parameter}]" if self.parameter else ""
        return f"t={self.t:.6f}s  {self.request}{name}: {self.what}: captured {self.captured}, virtual {self.virtual}"


@dataclass
class ReplayReport:
    capture: str
    module: str
    address: int
    compared: int = 0
    skipped: int = 0
    events: int = 0
    divergences: list[Divergence] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return not self.divergences

    @property
    def parameters(self) -> list[str]:
        """Names of the parameters that diverged, in order, without repeats."""
        return list(dict.fromkeys(d.parameter for d in self.divergences if d.parameter))

    def summary(self) -> str:
        verdict = "all replies agree" if self.ok else f"{len(self.divergences)} divergences"
        return (f"{self.capture}: {self.compared} replies and {self.events} events compared against "
                f"{self.module} at address {self.address}, {self.skipped} records skipped: {verdict}")

    def text(self) -> str:
        return "\n".join([*map(str, self.divergences), self.summary()])


def _klass(name: str | None) -> str | None:
    for klass, names in CLASSES.items():
        if name in names:
            return klass
    return None


def _req_text(rec: dict) -> str:
    text = format_instruction(rec["command"], rec["type"], rec["motor"], rec["value"])
    return text or f"command {rec['command']} type {rec['type']} motor {rec['motor']} value {rec['value']}"


def _status_value(status: int, value) -> str:
    return f"{status} ({message(status)}) value {value}"


class _Replayer:
    def __init__(self, cap: Capture, vm, address: int, tol: Tolerance, report: ReplayReport) -> None:
        self.cap, self.vm, self.address, self.tol, self.report = cap, vm, address, tol, report
        self.replies = {r["request"]: r for r in cap.frames if r["kind"] in ("reply", "version", "memory") and "request" in r}
        # A capture cut at its size cap: requests after the last captured reply lost theirs to the cap
        self.last_answered = max(self.replies, default=0) if cap.truncated is not None else None
        self.expected_events = [r for r in cap.frames if r["kind"] == "event" and r.get("address") == address]
        self.virtual_events: list[tuple[float, bytes]] = []
        self.windows: dict[int, list] = {}

    def advance(self, t: float) -> None:
        until = max(self.vm.now, round(t * CLOCK_HZ))
        self.vm.advance_to(until)
        for raw in self.vm.drain_events():
            self.virtual_events.append((self.vm.now / CLOCK_HZ, raw))

    def run(self) -> None:
        from ..firmware.table import execute

        actions = []  # (time, order, kind, record)
        for rec in self.cap.frames:
            if rec["dir"] != "host":
                continue
            if rec["kind"] == "request":
                actions.append((rec["t"], 1, "request", rec))
                if self._windowed(rec) and self.tol.time > 0:
                    actions.append((max(0.0, rec["t"] - self.tol.time), 0, "sample", rec))
                    actions.append((rec["t"] + self.tol.time, 2, "sample", rec))
            elif rec["kind"] == "ascii":
                actions.append((rec["t"], 1, "ascii", rec))
            else:
                self.report.skipped += 1
        for ev in self.expected_events:
            actions.append((ev["t"] + self.tol.time, 3, "events", ev))
        actions.sort(key=lambda a: (a[0], a[1], a[3]["n"]))
        for t, _, kind, rec in actions:
            self.advance(t)
            if kind in ("request", "sample") and not self.vm.accepts_address(rec["address"]):
                # another module's request (the module follows SGP 66 / GP87 itself)
                self.report.skipped += kind == "request"
                continue
            if kind == "request":
                self.request(rec)
            elif kind == "sample":
                out = None if self.vm.download_mode else \
                    execute(self.vm, rec["command"], rec["type"], rec["motor"], rec["value"], program=False)
                if isinstance(out, tuple):
                    self.windows.setdefault(rec["n"], []).append(out)
                if t > rec["t"]:
                    self.judge_window(rec)
            elif kind == "ascii":
                if getattr(self.vm, "ascii_mode", False):
                    self.vm.feed_ascii(rec["bytes"])
        end = max((a[0] for a in actions), default=0.0)
        self.advance(end)
        self.compare_events()

    def _windowed(self, rec: dict) -> bool:
        if rec["command"] == 15 or rec["command"] == _APP_STATUS:
            return True
        if rec["command"] == _RFS and rec["type"] == _RFS_STATUS:
            return True
        return rec["command"] in _READS and _klass(self._name(rec)) is not None

    def _name(self, rec: dict) -> str | None:
        from .decode import parameter_name

        return parameter_name(self.vm.profile, rec["command"], rec["type"], rec["motor"])

    def request(self, rec: dict) -> None:
        raw = self.vm.handle(rec["bytes"]) if len(rec["bytes"]) == FRAME_LEN else b""
        captured = self.replies.get(rec["n"])
        if captured is None and self.last_answered is not None and rec["n"] > self.last_answered:
            self.report.skipped += 1   # its reply came after the capture stopped
            return
        self.report.compared += 1
        name = self._name(rec)
        if name in IGNORED:
            return
        if captured is None and not raw:
            return
        if captured is None:
            self.diverge(rec, name, "reply", "none", raw.hex(" "))
            return
        if not raw:
            self.diverge(rec, name, "reply", captured["raw"], "none")
            return
        if captured["kind"] in ("version", "memory") or rec["command"] == 134:
            if captured["bytes"] != raw:
                self.diverge(rec, name, "reply", captured["raw"], raw.hex(" "))
            return
        status, value = raw[2], int.from_bytes(raw[4:8], "big", signed=True)
        c_status, c_value = captured["status"], captured["value"]
        if status != c_status or raw[3] != captured["command"]:
            self.diverge(rec, name, "status", _status_value(c_status, c_value), _status_value(status, value))
            return
        if raw[:2] != captured["bytes"][:2]:
            self.diverge(rec, name, "reply address", captured["raw"][:5], raw[:2].hex(" "))
            return
        if self._windowed(rec) and status == Status.OK:
            self.windows.setdefault(rec["n"], []).append((status, value))
            rec["_captured_value"] = c_value
            if self.tol.time <= 0:
                self.judge_window(rec)
            return
        if value != c_value:
            self.diverge(rec, name, "value", str(c_value), str(value))

    def judge_window(self, rec: dict) -> None:
        if "_captured_value" not in rec:
            return  # the reply itself diverged (or was not OK): already reported
        captured = rec.pop("_captured_value")
        values = [v for s, v in self.windows.pop(rec["n"], []) if s == Status.OK]
        name = self._name(rec)
        klass = _klass(name)
        tol = getattr(self.tol, klass, 0) if klass in TOLERANCE_KEYS else 0
        if tol is None:
            return
        lo, hi = min(values) - tol, max(values) + tol
        if not lo <= captured <= hi:
            window = f"{min(values)}..{max(values)} within +/-{self.tol.time:g} s" + (f" (+/-{tol:g})" if tol else "")
            self.diverge(rec, name, "value", str(captured), window)

    def diverge(self, rec: dict, name, what: str, captured: str, virtual: str) -> None:
        self.report.divergences.append(Divergence(rec["t"], _req_text(rec), name, what, captured, virtual))

    def compare_events(self) -> None:
        window = self.tol.time
        for i, ev in enumerate(self.expected_events):
            self.report.events += 1
            if i >= len(self.virtual_events):
                self.report.divergences.append(Divergence(ev["t"], "event (command 138)", None, "event",
                                                          f"motor mask {ev['value']}", "no event"))
                continue
            t, raw = self.virtual_events[i]
            mask = int.from_bytes(raw[4:8], "big", signed=True)
            if mask != ev["value"] or raw[2] != ev["status"]:
                self.report.divergences.append(Divergence(ev["t"], "event (command 138)", None, "event",
                                                          f"motor mask {ev['value']}", f"motor mask {mask}"))
            elif not ev["t"] - window <= t <= ev["t"] + window:
                self.report.divergences.append(Divergence(ev["t"], "event (command 138)", None, "event time",
                                                          f"{ev['t']:.6f} s", f"{t:.6f} s"))
        for t, raw in self.virtual_events[len(self.expected_events):]:
            if self.cap.truncated is not None and t >= self.cap.truncated:
                continue   # after the capture stopped at its size cap
            self.report.divergences.append(Divergence(t, "event (command 138)", None, "event", "no event",
                                                      f"motor mask {int.from_bytes(raw[4:8], 'big', signed=True)}"))
        self.report.divergences.sort(key=lambda d: d.t)


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
    from ..host.transports.inprocess import parse_modules
    from ..modules.profile_file import looks_like_path

    if not isinstance(target, str) or not target.startswith("sim://"):
        return None
    url = urllib.parse.urlsplit(target)
    spec = url.netloc + url.path if ".toml" in url.path.lower() else (url.netloc or url.path.lstrip("/"))
    try:
        specs = parse_modules(spec, 1)
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


def _captured_module(cap: Capture, address: int | None) -> str:
    """The module the capture identified, or the profile file of its `sim://` target."""
    from ..modules.profile import module_names

    module = cap.module_name()
    if module is None or module not in module_names():  # e.g. proxy --to sim:///path/my.toml
        module = _sim_profile_file(cap.header.get("target"), address) or module
    if module is None:
        raise ReplayError(f"{cap.path}: the capture does not identify its module; name one (--module)")
    return module


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


def replay(capture: str | os.PathLike | Capture, module: str | os.PathLike | None = None, *,
           address: int | None = None, eeprom: str | os.PathLike | None = None, scenario=None,
           tolerance: Tolerance | dict | list | None = None) -> ReplayReport:
    """Replay `capture` (a path or a read `Capture`) against a fresh virtual `module` (a name or a
    profile file; default: the module the capture identified). Returns a `ReplayReport`.
    Raises ReplayError (bad module, address or tolerance) or CaptureError (bad file)."""
    cap = capture if isinstance(capture, Capture) else read_capture(capture)
    tol = _tolerance(tolerance)
    if module is None:
        module = _captured_module(cap, address)
    if address is None:
        address = first_address(cap)
        if address is None:
            raise ReplayError(f"{cap.path}: no host request in the capture")
    vm = _virtual_module(module, address, eeprom, scenario)
    report = ReplayReport(cap.path, vm.profile.name, address)
    try:
        _Replayer(cap, vm, address, tol, report).run()
    finally:
        vm.close()
    if report.compared == 0:  # nothing checked is no evidence: not "all replies agree"
        seen = sorted({r["address"] for r in cap.frames if r["kind"] == "request" and "address" in r})
        raise ReplayError(f"{cap.path}: no request to address {address} in the capture "
                          f"(requests go to {', '.join(map(str, seen)) or 'no address'})")
    return report


def assert_replays(capture, module=None, **kwargs) -> ReplayReport:
    """For a user's own tests: replay and fail with every divergence listed."""
    report = replay(capture, module, **kwargs)
    if not report.ok:
        raise AssertionError(report.text())
    return report
