"""The conformance battery of `opentmcl conform` (docs/capture.md "Conformance runs").

It talks to a module through a `Client` while the proxy records everything, then the capture is
replayed against the twin. What it sends, phase by phase (each starts with a `mark` record):

- identity: 136 type 0 and 1;
- survey (always): GAP of every readable axis parameter of the chosen axes, GGP of every readable
  global parameter and user variable, GIO of every readable port;
- edges (`allow_writes`): for each writable setting that moves nothing, SAP/SGP of its last valid
  value and its first invalid one at both ends of its range (where a 32-bit value can carry them),
  each followed at once by the value read before. Left out: state values, unit switches (AP255
  re-expresses every velocity), auto-stored global parameters (written to EEPROM at once), the
  link's own parameters (address, baud rate, host address, CAN IDs, reply suppression), code
  protection, user variables (their range is all of 32 bits) and outputs (they may drive machinery);
- motion (`allow_motion`, per chosen axis, within `max_travel` of where the axis stands): moves of
  three lengths at two speeds and accelerations and back, ROR, a change of speed on the fly and
  MST, a short program with WAIT POS at the top of the program memory (the instructions there are
  read first with 134 and written back), and a reference search only when asked. It polls speed,
  position and position reached after every motion command until the axis is there;
- restore: every setting it changed gets the value read before.

Any error or Ctrl-C sends MST to every axis first (and stops a program it started), then restores.
"""
from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from ..host.errors import TmclError, TmclStatusError
from ..modules.state import is_state
from ..protocol.opcodes import (
    ENTER_DOWNLOAD_MODE,
    EXIT_DOWNLOAD_MODE,
    GET_FIRMWARE_VERSION,
    RUN_APPLICATION,
    STOP_APPLICATION,
    Op,
)
from .snapshot import KEEP

if TYPE_CHECKING:
    from ..modules.profile import ModuleProfile

# plain ints for the requests of a run (`Client.request` keeps plain-int requests ready)
_GAP, _SAP, _GGP, _SGP, _GIO = int(Op.GAP), int(Op.SAP), int(Op.GGP), int(Op.SGP), int(Op.GIO)
_ROR, _MST, _MVP, _RFS, _WAIT, _STOP = int(Op.ROR), int(Op.MST), int(Op.MVP), int(Op.RFS), int(Op.WAIT), int(Op.STOP)
INT32 = (-(1 << 31), (1 << 31) - 1)
SKIP_AXIS = frozenset({255})
"""AP255 (unit mode) re-expresses every velocity and acceleration in the other unit."""
PROGRAM_WORDS = 5
"""The conformance program: MVP REL, WAIT POS, MVP REL back, WAIT POS, STOP."""
POLL_INTERVAL = 0.01
"""Seconds between the starts of two polls of speed and position: 100 readings a second measure a
ramp of a tenth of a second; at 9600 baud one poll takes longer than that anyway."""
TRAVEL_GUARD = 0.9
"""A rotation is stopped once the axis is this share of `max_travel` away from where it began."""


class ConformError(ValueError):
    """The battery cannot go on (a move that does not end, an axis beyond its travel, a program
    already running): the CLI reports it in one line, exit status 2."""


@dataclass
class Options:
    axes: list[int]
    allow_writes: bool = False
    allow_motion: bool = False
    max_travel: int = 0
    max_speed: int | None = None
    max_accel: int | None = None
    reference: bool = False
    program: bool = True


@dataclass
class Battery:
    """One conformance run over `client` against `profile`; `mark(phase, axis, label)` records phases."""

    client: Any
    profile: ModuleProfile
    options: Options
    mark: Callable[[str, int | None, str], None]
    log: Callable[[str], None] = lambda text: None
    restore: list[tuple[int, int, int, int]] = field(default_factory=list)
    """(SAP|SGP, type, motor/bank, value) to write back at the end, in order."""
    program_started: bool = False
    skipped: list[str] = field(default_factory=list)

    # -- requests ----------------------------------------------------------------------------
    def send(self, command: int, type_: int = 0, motor: int = 0, value: int = 0) -> int | None:
        """The reply's value, None on an error status (a refused value is part of the battery)."""
        try:
            return self.client.reply(command, type_, motor, value).value
        except TmclStatusError:
            return None

    def read(self, number: int, motor: int) -> int | None:
        return self.send(_GAP, number, motor)

    # -- phases ------------------------------------------------------------------------------
    def run(self) -> None:
        try:
            self.identity()
            if self.options.allow_motion and self.send(_GGP, 128, 0) == 1:
                raise ConformError("a TMCL program is running on the module: stop it before a motion run "
                                   "(opentmcl send '128 0, 0, 0' --to URL)")
            self.survey()
            if self.options.allow_writes or self.options.allow_motion:
                self.edges()
            if self.options.allow_motion:
                for axis in self.options.axes:
                    self.motion(axis)
        except BaseException:
            self.emergency()
            raise
        self.restore_all()

    def identity(self) -> None:
        self.mark("identity", None, "136 firmware string and version")
        self.client.request(GET_FIRMWARE_VERSION, 0, 0, 0)
        self.send(GET_FIRMWARE_VERSION, 1)

    def survey(self) -> None:
        prof = self.profile
        for axis in self.options.axes:
            self.mark("survey", axis, "every readable axis parameter")
            for number, p in sorted(prof.axis_parameters.items()):
                if p.readable:
                    self.read(number, axis)
        self.mark("survey", None, "every readable global parameter, user variable and port")
        for (bank, number), p in sorted(prof.global_parameters.items()):
            if p.readable:
                self.send(_GGP, number, bank)
        for n in range(prof.user_variables):
            self.send(_GGP, n, 2)
        for (bank, port), io in sorted(prof.io.items()):
            if "R" in io.access:
                self.send(_GIO, port, bank)

    def _edges(self, p) -> list[int]:
        values = []
        for v in ([p.max, p.max + 1, p.min, p.min - 1] if not p.values else [max(p.values), max(p.values) + 1,
                                                                               min(p.values), min(p.values) - 1]):
            if INT32[0] <= v <= INT32[1] and v not in values:
                values.append(v)
        return values

    def edges(self) -> None:
        prof = self.profile
        for axis in self.options.axes:
            self.mark("edges", axis, "range edges of every writable axis parameter that moves nothing")
            for number, p in sorted(prof.axis_parameters.items()):
                if not (p.readable and p.writable) or is_state(p.name) or number in SKIP_AXIS:
                    continue
                before = self.read(number, axis)
                if before is None:
                    continue
                for value in self._edges(p):
                    if self.send(_SAP, number, axis, value) is not None:
                        self.send(_SAP, number, axis, before)
        self.mark("edges", None, "range edges of every writable global parameter that moves nothing")
        for (bank, number), p in sorted(prof.global_parameters.items()):
            if not (p.readable and p.writable) or is_state(p.name) or (bank, number) in KEEP \
                    or "A" in p.access or bank == 2:
                continue
            before = self.send(_GGP, number, bank)
            if before is None:
                continue
            for value in self._edges(p):
                if self.send(_SGP, number, bank, value) is not None:
                    self.send(_SGP, number, bank, before)

    # -- motion ------------------------------------------------------------------------------
    def setting(self, number: int, axis: int, value: int) -> bool:
        """SAP that is restored at the end; False when the module refuses it."""
        before = self.read(number, axis)
        if before is None or self.send(_SAP, number, axis, value) is None:
            return False
        self.restore.append((_SAP, number, axis, before))
        return True

    def motion(self, axis: int) -> None:
        opts, prof = self.options, self.profile
        self.mark("motion", axis, "moves, rotation, program")
        x0 = self.read(1, axis)
        if x0 is None:
            raise ConformError(f"axis {axis} does not report its position (GAP 1)")
        vmax = opts.max_speed or self.read(4, axis) or 0
        amax = opts.max_accel or self.read(5, axis) or 0
        if vmax <= 0 or amax <= 0:
            raise ConformError(f"axis {axis}: no speed or acceleration to move with (AP4 {vmax}, AP5 {amax})")
        travel = opts.max_travel
        for length, speed, accel in ((travel, vmax, amax), (travel // 4, vmax // 2, amax // 2),
                                     (max(1, travel // 16), vmax, amax)):
            self.mark("move", axis, f"MVP REL {length} at {speed} pps, {accel} pps^2 and back")
            self.ramp(axis, speed, accel)
            self.move(axis, x0 + length, x0, travel)
            self.move(axis, x0, x0, travel)
        self.ramp(axis, vmax, amax)
        fast = max(2, min(vmax // 2, int(math.sqrt(travel * amax / 2) / 2)))
        self.mark("rotate", axis, f"ROR {fast // 2}, change to {fast} on the fly, MST")
        self.rotate(axis, fast // 2, x0, travel)
        self.rotate(axis, fast, x0, travel)
        self.stop(axis, x0, travel)
        self.move(axis, x0, x0, travel)
        if opts.program and {ENTER_DOWNLOAD_MODE, RUN_APPLICATION} <= set(prof.opcodes):
            self.program(axis, x0, max(1, travel // 8), travel)
        if opts.reference:
            self.mark("reference", axis, "RFS START until RFS STATUS is 0")
            self.send(_RFS, 0, axis)
            self.poll(axis, lambda: self.send(_RFS, 2, axis) == 0, None, 0, 120.0)

    def ramp(self, axis: int, speed: int, accel: int) -> None:
        self.setting(4, axis, speed)
        self.setting(5, axis, accel)
        if 17 in self.profile.axis_parameters and self.profile.axis_parameters[17].writable:
            self.setting(17, axis, accel)   # max_deceleration of the six-point ramp

    def poll(self, axis: int, done: Callable[[], bool], x0: int | None, travel: int, limit: float) -> None:
        """Read speed and position until `done`; MST when the axis leaves `travel` of `x0`."""
        deadline = time.monotonic() + limit
        cycle = time.monotonic()
        while True:
            wait = cycle + POLL_INTERVAL - time.monotonic()
            if wait > 0:   # a fast link (TCP) is polled every POLL_INTERVAL, a slow one as fast as it goes
                time.sleep(wait)
            cycle = time.monotonic()
            self.read(3, axis)
            x = self.read(1, axis)
            if x0 is not None and x is not None and abs(x - x0) > travel:
                self.send(_MST, 0, axis)
                raise ConformError(f"axis {axis} left the allowed travel ({x} from {x0}); stopped it")
            if done():
                return
            if time.monotonic() > deadline:
                raise ConformError(f"axis {axis} did not get there within {limit:.0f} s")

    def _limit(self, distance: float, speed: int, accel: int) -> float:
        """Generous seconds for a move: ten times the ramp estimate plus five."""
        return 10 * (distance / max(1, speed) + 2 * speed / max(1, accel)) + 5

    def move(self, axis: int, target: int, x0: int, travel: int) -> None:
        speed, accel = self.read(4, axis) or 1, self.read(5, axis) or 1
        self.send(_MVP, 0, axis, target)
        self.poll(axis, lambda: self.read(8, axis) == 1, x0, travel, self._limit(travel, speed, accel))

    def rotate(self, axis: int, speed: int, x0: int, travel: int) -> None:
        accel = self.read(5, axis) or 1
        self.send(_ROR, 0, axis, speed)
        guard = int(travel * TRAVEL_GUARD)
        self.poll(axis, lambda: self.read(3, axis) == speed, x0, guard, self._limit(0, speed, accel))
        self.read(3, axis)   # a few readings at constant speed
        self.read(1, axis)

    def stop(self, axis: int, x0: int, travel: int) -> None:
        self.send(_MST, 0, axis)
        self.poll(axis, lambda: self.read(3, axis) == 0, x0, travel, 30.0)

    def program(self, axis: int, x0: int, length: int, travel: int) -> None:
        """MVP REL, WAIT POS, MVP REL back, WAIT POS, STOP at the top of the memory, run, written back."""
        start = self.profile.program_memory - PROGRAM_WORDS
        self.mark("program", axis, f"a program at {start}: MVP REL {length}, WAIT POS, back, WAIT POS, STOP")
        kept = []
        for index in range(start, start + PROGRAM_WORDS):
            try:
                m = self.client.read_memory(index)
            except TmclStatusError:
                self.skipped.append("program: the module refuses to read its program memory (code protection?)")
                return
            kept.append((m.command, m.type, m.motor, m.value))
        words = [(_MVP, 1, axis, length), (_WAIT, 1, axis, 0), (_MVP, 1, axis, -length), (_WAIT, 1, axis, 0),
                 (_STOP, 0, 0, 0)]
        if not self.download(start, words):
            self.skipped.append("program: the module refuses the download (code protection?)")
            return
        try:
            self.program_started = True
            self.send(RUN_APPLICATION, 1, 0, start)
            self.poll(axis, lambda: self.send(_GGP, 128, 0) == 0, x0, travel, 60.0)
            self.program_started = False
        finally:
            self.download(start, kept)

    def download(self, start: int, words: list[tuple[int, int, int, int]]) -> bool:
        try:
            self.client.request(ENTER_DOWNLOAD_MODE, 0, 0, start)
        except TmclStatusError:
            return False
        try:
            for word in words:
                self.client.request(*word)
        finally:
            self.client.request(EXIT_DOWNLOAD_MODE, 0, 0, 0)
        return True

    # -- the end -----------------------------------------------------------------------------
    def restore_all(self) -> None:
        """Every changed setting back to the value read before, last change first."""
        self.mark("restore", None, "every changed setting back")
        for command, type_, motor, value in reversed(self.restore):
            try:
                self.send(command, type_, motor, value)
            except TmclError:
                pass
        self.restore.clear()

    def emergency(self) -> None:
        """MST to every axis (and stop a program this run started), then restore what can be."""
        try:
            if self.program_started:
                self.send(STOP_APPLICATION)
            for axis in range(self.profile.axes):
                self.send(_MST, 0, axis)
        except BaseException:  # the link is gone: nothing more can be sent
            return
        try:
            self.restore_all()
        except BaseException:
            pass
