"""Move durations, the module's against the twin's (docs/capture.md "Reports").

A move is a motion request that succeeded (`twin.move_end`, the twins' rule too): MVP (ABS, REL,
COORD; and SAP 0) ends when the axis reports its target
reached (AP8 = 1, or the command-138 event), ROR/ROL/MST (and SAP 2) when the speed the host reads
(AP3) is the one asked for, RFS START when RFS STATUS reads 0. The module's end lies between the
last read that says "not yet" and the first that says "done", each within its window
(capture/timing.py); the move started inside the window of its request. So the module's duration
is an interval. The twins give theirs exactly (capture/twin.py). A move agrees when the intervals
meet, widened by the time tolerance at each end. Moves the host never saw end are not measured.
"""
from __future__ import annotations

from dataclasses import dataclass

from ..protocol.opcodes import Op, format_instruction
from .timing import Slot
from .twin import TwinRun, move_end


@dataclass
class Move:
    """One move: when it started (t, the request), the axis, what ends it, and both durations."""

    n: int
    t: float
    axis: int
    request: str
    kind: str            # position | speed | search
    target: int
    real: tuple[float, float]
    twin: tuple[float, float] | None
    ok: bool
    start_speed: int | None = None
    """The speed the host read last before the move (AP3), if it did."""

    @property
    def real_mid(self) -> float:
        return (self.real[0] + self.real[1]) / 2

    @property
    def twin_mid(self) -> float | None:
        return None if self.twin is None else (self.twin[0] + self.twin[1]) / 2

    @property
    def percent(self) -> float | None:
        """(module - twin) / twin in percent, from the middles of both intervals."""
        twin = self.twin_mid
        return None if not twin else (self.real_mid - twin) / twin * 100

    def as_dict(self) -> dict:
        return {"t": round(self.t, 6), "axis": self.axis, "request": self.request, "kind": self.kind,
                "target": self.target, "module_s": [round(x, 6) for x in self.real],
                "twin_s": None if self.twin is None else [round(x, 6) for x in self.twin],
                "percent": None if self.percent is None else round(self.percent, 2), "ok": self.ok}


def _verdict(kind: str, target: int, slot: Slot) -> bool | None:
    """Does this read (or event) say the move is done (True), not yet (False), or nothing (None)?"""
    rec, reply = slot.rec, slot.reply
    if reply is None or reply.get("status") != 100:
        return None
    value = reply["value"]
    if kind == "position" and rec["command"] == Op.GAP and rec["type"] == 8:
        return value == 1
    if kind == "speed" and rec["command"] == Op.GAP and rec["type"] == 3:
        return value == target
    if kind == "search" and rec["command"] == Op.RFS and rec["type"] == 2:
        return value == 0
    return None


def _axis_motion(rec: dict, address: int) -> bool:
    return rec["kind"] == "request" and rec["address"] == address and move_end(rec) is not None


def find_moves(slots: list[Slot], events: list[tuple[float, dict]], runs: list[TwinRun], address: int,
               tau: float) -> list[Move]:
    """The measured moves of the capture at `address`; `events` are (start on the wire, record)."""
    moves = []
    for i, start in enumerate(slots):
        rec = start.rec
        if not _axis_motion(rec, address) or start.reply is None or start.reply.get("status") != 100:
            continue
        kind, target = move_end(rec)  # type: ignore[misc]
        motor = rec["motor"]
        last_no, first_yes = _reads_after(slots, i, kind, target, address)
        if kind == "position":
            first_yes = _arrival_event(events, start.e, motor, last_no, first_yes)
        if first_yes is None:
            continue
        real = (max(0.0, last_no - start.s), max(0.0, first_yes - start.e))
        twin = _twin_duration(runs, rec["n"])
        ok = twin is not None and twin[0] <= real[1] + 2 * tau and twin[1] >= real[0] - 2 * tau
        text = format_instruction(rec["command"], rec["type"], motor, rec["value"]) or str(rec["command"])
        moves.append(Move(rec["n"], float(rec["t"]), motor, text, kind, target, real, twin, ok,
                          _speed_before(slots, i, motor, address)))
    return moves


def _reads_after(slots: list[Slot], i: int, kind: str, target: int, address: int) -> tuple[float, float | None]:
    """(the window end of the last read after the motion request `slots[i]` that says "not yet"
    (else that of the request), the window start of the first that says "done" or None), up to
    the next motion of the axis."""
    start = slots[i]
    motor = start.rec["motor"]
    last_no = start.e
    for later in slots[i + 1:]:
        lrec = later.rec
        if lrec["kind"] != "request" or lrec["address"] != address or lrec["motor"] != motor:
            continue
        if _axis_motion(lrec, address):
            break   # the next motion of this axis: this one was not seen to end
        verdict = _verdict(kind, target, later)
        if verdict is False:
            last_no = later.e
        elif verdict is True:
            return last_no, later.s
    return last_no, None


def _arrival_event(events: list[tuple[float, dict]], since: float, motor: int, last_no: float,
                   first_yes: float | None) -> float | None:
    """The end of a move to a position: a command-138 event of the axis after `since` that came
    before the first read that said "done" (no earlier than the last that said "not yet")."""
    for t_ev, ev in events:
        if t_ev >= since and ev.get("value", 0) >> motor & 1 and (first_yes is None or t_ev < first_yes):
            return max(t_ev, last_no)
    return first_yes


def _twin_duration(runs: list[TwinRun], n: int) -> tuple[float, float] | None:
    """The shortest and longest time the twins' axes took to finish request `n`, if they did."""
    durations = [run.done[n] - run.results[n].t for run in runs if n in run.done and n in run.results]
    return (min(durations), max(durations)) if durations else None


def _speed_before(slots: list[Slot], i: int, motor: int, address: int) -> int | None:
    for slot in reversed(slots[:i]):
        rec, reply = slot.rec, slot.reply
        if rec["kind"] == "request" and rec["address"] == address and rec["command"] == Op.GAP \
                and rec["type"] == 3 and rec["motor"] == motor and reply is not None and reply.get("status") == 100:
            return int(reply["value"])
    return None


def acceleration_estimates(moves: list[Move]) -> dict[int, dict[str, tuple[float, float]]]:
    """axis -> {"acceleration"|"deceleration": (module, twin)} in pps^2, from the speed moves whose
    speed the host read before: |change of speed| / ramp time, the mean over those moves."""
    out: dict[int, dict[str, list[tuple[float, float]]]] = {}
    for m in moves:
        twin = m.twin_mid
        if m.kind != "speed" or twin is None or m.real_mid <= 0 or twin <= 0 \
                or m.start_speed is None or m.target == m.start_speed:
            continue
        change = abs(m.target - m.start_speed)
        kind = "acceleration" if abs(m.target) > abs(m.start_speed) and m.target * m.start_speed >= 0 \
            else "deceleration"
        out.setdefault(m.axis, {}).setdefault(kind, []).append((change / m.real_mid, change / twin))
    return {axis: {kind: (sum(a for a, _ in v) / len(v), sum(b for _, b in v) / len(v))
                   for kind, v in kinds.items()} for axis, kinds in out.items()}


def events_of(cap_frames: list[dict], starts: dict[int, float], address: int) -> list[tuple[float, dict]]:
    """The command-138 events of `address`: (start on the wire, record)."""
    return [(starts.get(r["n"], float(r["t"])), r) for r in cap_frames
            if r["kind"] == "event" and r.get("address") == address and r.get("command") == Op.REQUEST_TARGET_REACHED_EVENT]
