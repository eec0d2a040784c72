"""Every captured reply against the twins' (docs/capture.md "Replay").

A reply agrees when its status and command agree with a twin's and, for a read, its value lies in
the twins' range of that value over the interval in which the module could have sampled it
(capture/twin.py), widened by the tolerance of its value class (capture/tolerance.py). A write,
motion or control command agrees when the value it returns is one a twin returned; a firmware
string or a program memory read when its bytes are a twin's. Each comparison is a `Check` in one
area of the report; the divergent ones are grouped under their root causes (capture/causes.py).
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

from ..modules.state import UNREPRODUCIBLE, moving_class
from ..protocol.frame import FRAME_LEN
from ..protocol.opcodes import AXIS_COMMANDS, PROGRAM_CONTROL, Op, format_instruction
from ..protocol.status import Status, message
from .causes import Check, Divergence
from .format import Capture
from .moves import Move, events_of
from .outcome import ReplayReport
from .timing import Slot
from .tolerance import Tolerance
from .twin import Result, TwinRun, windowed

PROGRAM_GLOBALS = (128, 129, 130)   # GGP 128 status, 129 download mode, 130 program counter (bank 0)
DURATIONS = "move durations"


def request_text(rec: dict) -> str:
    """A request as the manual writes it (136 with what it asks for)."""
    if rec["command"] == Op.GET_FIRMWARE_VERSION:
        return f"136 {rec['type']} ({'firmware string' if rec['type'] == 0 else 'binary version'})"
    text = format_instruction(rec["command"], rec["type"], rec["motor"], rec["value"])
    return text or f"command {rec['command']} type {rec['type']} motor {rec['motor']} value {rec['value']}"


def _status_value(status: int, value) -> str:
    return f"{status} ({message(status)}) value {value}"


def _value(raw: bytes) -> int:
    return int.from_bytes(raw[4:8], "big", signed=True)


def _listed(raws) -> str:
    """The twins' different replies, in hex."""
    return " / ".join(dict.fromkeys(r.hex(" ") for r in raws if r))


@dataclass
class Case:
    """One captured request under comparison: its record, parameter name and the twins' results."""

    rec: dict
    name: str | None
    results: list[Result]

    @cached_property
    def raws(self) -> list[bytes]:
        return [r.raw for r in self.results]

    @property
    def running(self) -> bool:
        """A TMCL program ran in a twin when the request acted."""
        return any(r.running for r in self.results)

    @property
    def t(self) -> float:
        return float(self.rec["t"])


def event_difference(start: float, ev: dict, got: list[tuple[float, bytes]],
                     tol: Tolerance) -> tuple[str, str, str] | None:
    """How the twins' events differ from the captured one that started on the wire at `start`:
    (what, captured, twin), or None when they agree (same motor mask and status, in time)."""
    mask = f"motor mask {ev['value']}"
    if not got:
        return "event", mask, "no event"
    masks = {_value(raw) for _, raw in got}
    if ev["value"] not in masks or any(raw[2] != ev["status"] for _, raw in got):
        return "event", mask, f"motor mask {sorted(masks)[0]}"
    lo, hi = min(t for t, _ in got), max(t for t, _ in got)
    earliest = start - tol.latency - tol.time
    if hi < earliest or lo > start + tol.time:
        return "event time", f"{start:.6f} s on the wire", f"{lo:.6f}..{hi:.6f} s"
    return None


class Comparer:
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

    # -- the areas and the record of each check ------------------------------------------------
    def area(self, rec: dict, status_check: bool) -> str:
        """identity (136), programs (128..135, GGP 128..130), status codes (writes, refused
        requests), ramp shape (moving axis values, RFS STATUS), else parameters."""
        command = rec["command"]
        if command == Op.GET_FIRMWARE_VERSION:
            return "identity"
        if command in PROGRAM_CONTROL or (command == Op.GGP and rec["motor"] == 0 and rec["type"] in PROGRAM_GLOBALS):
            return "programs"
        if status_check:
            return "status codes"
        if command == Op.GAP and moving_class(self.name(rec)) is not None or command == Op.RFS and rec["type"] == 2:
            return "ramp shape"
        return "parameters"

    def axis_of(self, rec: dict) -> int | None:
        if rec["command"] in AXIS_COMMANDS and rec["motor"] < self.profile.axes:
            return rec["motor"]
        return None

    def engine(self, rec: dict) -> bool:
        if rec["command"] not in (Op.SAP, Op.GAP):
            return False
        p = self.profile.axis_parameters.get(rec["type"])
        return p is not None and bool(p.engine)

    def check(self, rec: dict, area: str, ok: bool, d: Divergence | None = None, rest: bool = False) -> None:
        self.report.areas[area][0] += ok
        self.report.areas[area][1] += 1
        axis = self.axis_of(rec)
        if d is not None:
            d.area, d.axis, d.n = area, axis, rec["n"]
            self.report.divergences.append(d)
        write = (rec["command"], rec["type"], rec["motor"]) if rec["command"] in (Op.SAP, Op.SGP, Op.SIO) else None
        self.checks.append(Check(float(rec["t"]), area, ok, axis, d, rest, self.engine(rec),
                                 program=area == "programs", write=write))

    def diverge(self, case: Case, area: str, what: str, captured: str, twin: str) -> None:
        self.check(case.rec, area, False, Divergence(case.t, request_text(case.rec), case.name, what, captured, twin))

    # -- replies -------------------------------------------------------------------------------
    def slot(self, slot: Slot, runs: list[TwinRun]) -> None:
        """Compare the reply to the request of `slot` (other records have none)."""
        case = self._case(slot, runs)
        if case is None:
            return
        captured = slot.reply
        if captured is None or not any(case.raws):
            self._missing_reply(case, captured)
        elif captured["kind"] in ("version", "memory") or case.rec["command"] == Op.READ_PROGRAM_MEMORY:
            self._whole_reply(case, captured)
        else:
            self._frame(case, captured)

    def _case(self, slot: Slot, runs: list[TwinRun]) -> Case | None:
        """The comparison of a request, counted; None when it is skipped or not compared."""
        rec = slot.rec
        if rec["kind"] != "request":
            return None
        n = rec["n"]
        if any(n in run.skipped for run in runs):
            self.report.skipped += 1
            return None
        results = [run.results[n] for run in runs if n in run.results]
        if not results:
            return None
        if slot.reply is None and self.last_answered is not None and n > self.last_answered:
            self.report.skipped += 1   # its reply came after the capture stopped
            return None
        self.report.compared += 1
        name = self.name(rec)
        return None if name in UNREPRODUCIBLE else Case(rec, name, results)

    def _missing_reply(self, case: Case, captured: dict | None) -> None:
        """No reply on one side."""
        area = self.area(case.rec, True)
        if captured is not None:
            self.diverge(case, area, "reply", captured["raw"], "none")
        elif any(case.raws):
            self.diverge(case, area, "reply", "none", next(r for r in case.raws if r).hex(" "))

    def _whole_reply(self, case: Case, captured: dict) -> None:
        """A firmware string, a program memory read (134): the bytes as they are."""
        area = self.area(case.rec, False)
        if captured["bytes"] in case.raws:
            self.check(case.rec, area, True)
        elif captured["kind"] == "version":
            twins = " / ".join(dict.fromkeys(repr(r[1:].decode("latin-1")) for r in case.raws if r))
            self.diverge(case, area, "firmware string", repr(captured.get("version")), twins)
        else:
            self.diverge(case, area, "reply", captured["raw"], _listed(case.raws))

    def _frame(self, case: Case, captured: dict) -> None:
        """A nine-byte reply: status and command, reply address, then the value."""
        rec = case.rec
        full = [r for r in case.raws if len(r) == FRAME_LEN]
        c_status, c_value = captured["status"], captured["value"]
        same = [r for r in full if r[2] == c_status and r[3] == captured["command"]]
        if not same:
            r = full[0] if full else case.raws[0]
            twin = _status_value(r[2], _value(r)) if len(r) == FRAME_LEN else r.hex(" ")
            self.diverge(case, self.area(rec, True), "status", _status_value(c_status, c_value), twin)
        elif same[0][:2] != captured["bytes"][:2]:
            self.diverge(case, self.area(rec, True), "reply address", captured["raw"][:5], same[0][:2].hex(" "))
        elif not windowed(rec, self.profile) and rec["command"] != Op.GET_FIRMWARE_VERSION:
            self._returned_value(case, same, c_value)
        else:
            self.compare_value(case, c_status, c_value)

    def _returned_value(self, case: Case, same: list[bytes], c_value: int) -> None:
        """A write, a motion or control command: its status and the value it returns."""
        values = list(dict.fromkeys(_value(r) for r in same))
        area = self.area(case.rec, True)
        if c_value in values:
            self.check(case.rec, area, True)
        else:
            self.diverge(case, area, "value", str(c_value), " / ".join(map(str, values)))

    def compare_value(self, case: Case, c_status: int, c_value: int) -> None:
        """A read: the captured value against the twins' range over its interval."""
        rec = case.rec
        area = self.area(rec, False)
        if c_status != Status.OK:
            self.check(rec, "status codes", True)
            return
        tol = self.tol.of(moving_class(case.name))
        lows = [r.lo for r in case.results if r.lo is not None]
        highs = [r.hi for r in case.results if r.hi is not None]
        if tol is None or not lows:
            return
        lo, hi = min(lows), max(highs)
        if lo - tol <= c_value <= hi + tol:
            self.check(rec, area, True, rest=rec["command"] == Op.GAP and rec["type"] == 1 and lo == hi)
            return
        twin = str(lo) if lo == hi else f"{lo}..{hi}"
        if tol:
            twin += f" (+/-{tol:g})"
        self.diverge(case, area, "value", str(c_value), twin)

    # -- events and moves ----------------------------------------------------------------------
    def events(self, starts: dict[int, float], runs: list[TwinRun]) -> None:
        """The module's command-138 events against the twins', one by one in order."""
        expected = events_of(self.cap.frames, starts, self.address)
        lists = [list(run.events) for run in runs]
        self.report.events += len(expected)
        for i, (start, ev) in enumerate(expected):
            rec = {**ev, "command": Op.REQUEST_TARGET_REACHED_EVENT, "type": 0, "motor": 0, "n": ev["n"]}
            differs = event_difference(start, ev, [lst[i] for lst in lists if i < len(lst)], self.tol)
            if differs is None:
                self.check(rec, DURATIONS, True)
            else:
                self.check(rec, DURATIONS, False, Divergence(float(ev["t"]), "event (command 138)", None, *differs))
        self._extra_events(lists, len(expected))

    def _extra_events(self, lists: list[list[tuple[float, bytes]]], expected: int) -> None:
        """Events every twin sent beyond the module's (before the capture stopped, if cut)."""
        extra = max((len(lst) for lst in lists), default=0)
        for i in range(expected, extra):
            t, raw = next(lst for lst in lists if len(lst) > i)[i]
            if self.cap.truncated is not None and t >= self.cap.truncated:
                continue   # after the capture stopped at its size cap
            if all(len(other) > i for other in lists):
                rec = {"command": Op.REQUEST_TARGET_REACHED_EVENT, "type": 0, "motor": 0, "n": None, "t": t}
                self.check(rec, DURATIONS, False, Divergence(t, "event (command 138)", None, "event",
                                                             "no event", f"motor mask {_value(raw)}"))

    def moves(self, moves: list[Move]) -> None:
        for m in moves:
            rec = {"command": Op.MVP, "type": 0, "motor": m.axis, "n": m.n, "t": m.t}
            if m.ok:
                self.check(rec, DURATIONS, True)
                continue
            twin = "no end" if m.twin is None else f"{m.twin[0]:.3f}..{m.twin[1]:.3f} s"
            self.check(rec, DURATIONS, False,
                       Divergence(m.t, m.request, None, "duration", f"{m.real[0]:.3f}..{m.real[1]:.3f} s", twin))
