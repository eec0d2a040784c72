"""One twin's run through a capture, in virtual time (docs/capture.md "Replay").

The module acted on each request somewhere inside its window (capture/timing.py), and which
instant matters: an MST 2 ms later stops an axis 100 steps further on. Four twins bracket it. The
"hi" twin acts on each request at the instant that leaves its axis further on later (an MST as late
as it can, a start as early as it can; the sign is that of the axis speed before the request minus
the speed the request asks for), the "lo" twin at the other end of the window: they bound the
positions. The "early" twin acts on every request at the start of its window and the "late" twin at
the end: they bound the speeds while a ramp follows a request. A read is answered
at the start of its window, and the twin's value is followed over the whole sampling interval
[window start - time tolerance, window end + time tolerance]: at its ends, at every event of the
twin in between (a ramp phase change, an arrival, a switch edge: between two events a position is
quadratic and a speed linear in time) and at a turning point, so the range is the true range of
the value over the interval. Requests act in capture order (the timeline: capture/schedule.py).
"""
from __future__ import annotations

from dataclasses import dataclass, field

from ..modules.state import READ_CLEARS
from ..motion import CLOCK_HZ
from ..protocol.frame import FRAME_LEN
from ..protocol.opcodes import MOTION_COMMANDS, Op
from .decode import parameter_name
from .timing import Slot

READS_OF = {Op.SAP: Op.GAP, Op.RSAP: Op.GAP, Op.SGP: Op.GGP, Op.SIO: Op.GIO}
"""A setting written and the command that reads it back (same type and motor or bank)."""
MOTION = MOTION_COMMANDS | {Op.SAP, Op.RSAP}
"""Requests whose instant of action may change where an axis goes (`Twin.effect`)."""
NO_MOTION = frozenset({Op.SGP, Op.SIO, Op.REQUEST_TARGET_REACHED_EVENT, Op.STAP, Op.STGP, Op.READ_PROGRAM_MEMORY,
                       Op.GET_FIRMWARE_VERSION, Op.GAP, Op.GGP, Op.GIO, Op.GCO, Op.GET_APPLICATION_STATUS})
"""Requests that do not change where an axis goes (SGP: unless a program runs)."""
WINDOWED = frozenset({Op.GAP, Op.GGP, Op.GIO, Op.GCO, Op.GET_APPLICATION_STATUS})
"""Reads whose answer is followed over the sampling interval (`windowed`; RFS STATUS too)."""
_GAP, _GGP, _RFS = int(Op.GAP), int(Op.GGP), int(Op.RFS)  # plain ints for the twin's reads
APPLICATION_STATUS = 128
"""GGP 128: 1 while a TMCL program runs."""
MAX_STEPS = 400
"""Most twin events stepped through between two points of the timeline; beyond, the twin jumps."""
MAX_TRACE = 20000
"""Most (time, position, speed) points kept per axis for the plots."""


def windowed(rec: dict, profile) -> bool:
    """A read whose answer is followed over its sampling interval (GAP, GGP, GIO, GCO, 135, RFS
    STATUS), except a value its reading changes (AP207)."""
    command = rec.get("command")
    if command == Op.RFS:
        return rec.get("type") == 2
    if command not in WINDOWED:
        return False
    return parameter_name(profile, command, rec["type"], rec["motor"]) not in READ_CLEARS


def _sign(x: int) -> int:
    return (x > 0) - (x < 0)


@dataclass
class Result:
    """What the twin answered to one request, and the range of the value over its interval."""

    raw: bytes
    t: float
    lo: int | None = None
    hi: int | None = None
    running: bool = False
    """A TMCL program was running when the request acted."""

    def include(self, value: int) -> None:
        self.lo = value if self.lo is None or value < self.lo else self.lo
        self.hi = value if self.hi is None or value > self.hi else self.hi


@dataclass
class _Window:
    n: int
    command: int
    type: int
    motor: int
    position: bool
    result: Result
    open: bool = True
    last: tuple[float, int, int] | None = None   # (t, value, speed) for a position: the turning point


@dataclass
class _Watch:
    n: int
    motor: int
    kind: str     # position | speed | search
    value: int = 0


def move_end(rec: dict) -> tuple[str, int] | None:
    """What ends the move a request starts, and the value that tells it (docs/capture.md "Reports"):
    "position" for MVP ABS, REL or COORD and SAP 0 (TMCM-6212 3.6.4, 4.1: AP8 "target position
    reached"; the value is the request's), "speed" for ROR, ROL (the signed speed asked), MST (0) and
    SAP 2 (AP3 reaching it), "search" for RFS START (RFS STATUS 0, 3.6.11); None for anything else."""
    command, type_, value = rec["command"], rec["type"], rec["value"]
    if command == Op.MVP and type_ in (0, 1, 2) or command == Op.SAP and type_ == 0:
        return "position", value
    if command == Op.ROR or command == Op.ROL:
        return "speed", value if command == Op.ROR else -value
    if command == Op.MST:
        return "speed", 0
    if command == Op.SAP and type_ == 2:
        return "speed", value
    if command == Op.RFS and type_ == 0:
        return "search", 0
    return None


@dataclass
class TwinRun:
    """A twin's answers (`results` by request number), events, and motion timing."""

    policy: str
    results: dict[int, Result] = field(default_factory=dict)
    skipped: set[int] = field(default_factory=set)
    events: list[tuple[float, bytes]] = field(default_factory=list)
    done: dict[int, float] = field(default_factory=dict)
    """request n of a motion command -> when the twin's axis got there (arrival, speed, search end)."""
    trace: dict[int, list[tuple[float, int, int]]] = field(default_factory=dict)


class Twin:
    """One `VirtualModule` played through a capture: it acts, samples and watches motions;
    `Schedule` (capture/schedule.py) says when (see the module doc)."""

    def __init__(self, vm, policy: str, tau: float, trace_axes: set[int], idle: float = 0.0) -> None:
        from ..firmware.table import execute  # the firmware loads when a replay runs, not on import

        self.execute = execute
        self.vm, self.policy, self.tau, self.idle = vm, policy, tau, idle
        self.run = TwinRun(policy)
        self.windows: dict[int, _Window] = {}
        self.watches: dict[int, _Watch] = {}
        self.trace_axes = sorted(m for m in trace_axes if m < vm.profile.axes)
        self.last_action = 0

    # -- reading the twin (pure reads) -------------------------------------------------------
    def read(self, command: int, type_: int, motor: int) -> int | None:
        if self.vm.download_mode:
            return None
        out = self.execute(self.vm, command, type_, motor, 0, program=False)
        if isinstance(out, tuple) and out[0] == 100:
            return int(out[1])
        return None

    def now(self) -> float:
        """Capture time."""
        return self.vm.now / CLOCK_HZ - self.idle

    # -- time ----------------------------------------------------------------------------------
    def advance(self, tick: int) -> None:
        """Step to `tick` event by event, sampling the open windows and watching motions."""
        steps = 0
        while self.vm.now < tick:
            nxt = tick
            if steps < MAX_STEPS:
                dt = self.vm.next_event_in()
                if dt is not None:
                    nxt = min(tick, self.vm.now + max(1, round(dt * CLOCK_HZ)))
            self.vm.advance_to(nxt)
            steps += 1
            self.after_step()

    def after_step(self) -> None:
        t = self.now()
        for raw in self.vm.drain_events():
            self.run.events.append((t, raw))
        for w in self.windows.values():
            if w.open:
                self.sample(w)
        if self.watches:
            self.check_watches()
        self.trace()

    def sample(self, w: _Window) -> None:
        value = self.read(w.command, w.type, w.motor)
        if value is None:
            return
        w.result.include(value)
        if w.position:
            speed = self.read(_GAP, 3, w.motor)
            if speed is None:
                return
            t = self.now()
            if w.last is not None and _sign(w.last[2]) * _sign(speed) < 0:
                # the speed crossed zero between two samples: the position turned there
                t0, x0, v0 = w.last
                t_turn = t0 + (t - t0) * v0 / (v0 - speed)
                w.result.include(round(x0 + v0 * (t_turn - t0) / 2))
            w.last = (t, value, speed)

    def trace(self) -> None:
        t = self.now()
        for motor in self.trace_axes:
            points = self.run.trace.setdefault(motor, [])
            if len(points) >= MAX_TRACE:
                continue
            x, v = self.read(_GAP, 1, motor), self.read(_GAP, 3, motor)
            if x is not None and v is not None and (not points or points[-1][0] != t):
                points.append((t, x, v))

    # -- motions and their end -----------------------------------------------------------------
    def check_watches(self) -> None:
        for n, w in list(self.watches.items()):
            if w.kind == "position":
                done = self.read(_GAP, 8, w.motor) == 1
            elif w.kind == "speed":
                done = self.read(_GAP, 3, w.motor) == w.value
            else:
                done = self.read(_RFS, 2, w.motor) == 0
            if done:
                self.run.done[n] = self.now()
                del self.watches[n]

    def watch(self, rec: dict) -> None:
        """After a motion request that succeeded: watch for its end (superseding the axis's last)."""
        motor = rec["motor"]
        end = move_end(rec)
        if end is None or motor >= self.vm.profile.axes:
            return
        kind, target = end
        for n in [n for n, w in self.watches.items() if w.motor == motor]:
            del self.watches[n]
        self.watches[rec["n"]] = _Watch(rec["n"], motor, kind, target)
        self.check_watches()

    # -- the sign of an action's timing ----------------------------------------------------------
    def effect(self, rec: dict) -> int | None:
        """The sign of d(later position)/d(delay) for the request's axis: +1 or -1 for a motion
        command, 0 for a request that does not change where any axis goes (a setting of an axis
        at rest, a global parameter, an output), None when it is not known (a program started, a
        reference search, a ramp setting changed while the axis moves)."""
        command, type_, motor = rec["command"], rec["type"], rec["motor"]
        if command in NO_MOTION:
            return None if command == Op.SGP and self.read(_GGP, APPLICATION_STATUS, 0) == 1 else 0
        if command not in MOTION or motor >= self.vm.profile.axes:
            return None
        v0 = self.read(_GAP, 3, motor)
        x0 = self.read(_GAP, 1, motor)
        if v0 is None or x0 is None:
            return None
        if command in (Op.SAP, Op.RSAP) and type_ not in (0, 1, 2, 4):
            p = self.vm.profile.axis_parameters.get(type_)
            return None if v0 and p is not None and p.engine else 0   # a ramp setting while moving
        if command == Op.RSAP:
            return None if v0 else 0
        if command == Op.SAP and type_ == 1:
            return -_sign(v0)   # a position overwritten later keeps the distance run until then
        v1 = self.asked_speed(rec, v0, x0)
        return None if v1 is None else _sign(v0 - v1)

    def asked_speed(self, rec: dict, v0: int, x0: int) -> int | None:
        """The speed a motion request sends its axis to (signed; a move to a position at its
        maximum speed AP4), from speed `v0` at position `x0`; None when not known (RFS START, MVP COORD)."""
        command, type_, value = rec["command"], rec["type"], rec["value"]
        if command == Op.MST or (command == Op.RFS and type_ == 1):
            return 0
        if command in (Op.ROR, Op.ROL):
            return value if command == Op.ROR else -value
        if command == Op.SAP and type_ == 2:
            return value
        if command == Op.SAP and type_ == 4:
            return _sign(v0) * value
        if command == Op.MVP and type_ in (0, 1) or command == Op.SAP and type_ == 0:
            target = value if type_ == 0 or command == Op.SAP else x0 + value
            vmax = self.read(_GAP, 4, rec["motor"]) or 0
            return _sign(target - x0) * vmax
        return None

    def late(self, sign: int | None) -> bool:
        """Does this twin act at the end of the request's window? The "early" and "late" twins
        always at their end; the others by the sign of its effect on the axis's later positions;
        when the effect is not known, the "lo" twin acts late and the "hi" twin early, so that each
        end of the window is played by one of them; a request that changes where no axis goes acts
        at the start in both."""
        if self.policy in ("early", "late"):
            return self.policy == "late" and sign != 0
        if sign is None:
            return self.policy == "lo"
        return sign > 0 if self.policy == "hi" else sign < 0

    # -- acting ---------------------------------------------------------------------------------
    def act(self, slot: Slot) -> None:
        rec = slot.rec
        if rec["kind"] == "ascii":
            if getattr(self.vm, "ascii_mode", False):
                self.vm.feed_ascii(rec["bytes"])
            return
        if not self.vm.accepts_address(rec["address"]):
            self.run.skipped.add(rec["n"])   # another module's request (the twin follows GP66/GP87)
            return
        running = self.read(_GGP, APPLICATION_STATUS, 0) == 1
        raw = self.vm.handle(rec["bytes"]) if len(rec["bytes"]) == FRAME_LEN else b""
        result = self.run.results.setdefault(rec["n"], Result(raw, self.now()))
        result.raw, result.t, result.running = raw, self.now(), running
        for ev in self.vm.drain_events():
            self.run.events.append((self.now(), ev))
        if len(raw) == FRAME_LEN and raw[2] == 100 and windowed(rec, self.vm.profile):
            result.include(int.from_bytes(raw[4:8], "big", signed=True))
        if len(raw) == FRAME_LEN and raw[2] == 100:
            self.watch(rec)
        self.trace()

    @staticmethod
    def writes(rec: dict, read: dict) -> bool:
        """Does `rec` write what `read` reads (SAP/RSAP and GAP, SGP and GGP, SIO and GIO of the
        same type and motor or bank; 137 everything)? Only such a write bounds the read's sampling
        interval: a motion command changes moving values anyway, and a twin out of phase with the
        module by a window would cut the interval where the module still sampled."""
        if rec["kind"] != "request":
            return False
        if rec["command"] == Op.RESTORE_FACTORY_SETTINGS:
            return True
        return READS_OF.get(rec["command"]) == read["command"] and rec["type"] == read["type"] \
            and rec["motor"] == read["motor"]

    def open(self, slot: Slot) -> None:
        rec = slot.rec
        n = rec["n"]
        result = self.run.results.setdefault(n, Result(b"", self.now()))
        position = rec["command"] == Op.GAP and rec["type"] in (1, 209)
        w = self.windows[n] = _Window(n, rec["command"], rec["type"], rec["motor"], position, result)
        if self.vm.accepts_address(rec["address"]):
            self.sample(w)

    def close(self, slot: Slot) -> None:
        closing = self.windows.pop(slot.rec["n"], None)
        if closing is not None and self.vm.accepts_address(slot.rec["address"]):
            self.sample(closing)

    def start(self, t: float) -> None:
        """Stand idle until capture time `t` (the twin's clock starts `idle` seconds before 0)."""
        self.advance(self.tick_of(t))

    def tick_of(self, t: float) -> int:
        """The twin's tick of capture time `t` (the twin may have stood `idle` seconds before)."""
        return max(0, round((t + self.idle) * CLOCK_HZ))

