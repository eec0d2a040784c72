"""The virtual TMCL module: wire-format requests in, replies out, motors in virtual time.

    vm = VirtualModule("TMCM-6212", address=1)
    reply = vm.handle(frame)      # 9-byte request -> reply bytes (b"" when no reply is due)
    vm.advance(0.25)              # virtual seconds

Time is an integer count of 16 MHz ticks (motion/base.py); `advance` jumps
from event to event (ramp phase changes, arrivals, heartbeat expiry) and
never steps in small increments.
"""
from __future__ import annotations

import os

from ..modules.profile import ModuleProfile, load_profile
from ..motion import CLOCK_HZ
from ..protocol.frame import FRAME_LEN, Reply, checksum, to_int32
from ..protocol.status import Status
from .axis import Axis
from .commands import COMMANDS, NO_SUPPRESS, execute
from .eeprom import Eeprom
from .globals import GlobalParameters
from .interpreter import Interpreter
from .interrupts import Interrupts
from .io import IOBanks
from .program import ProgramMemory, program_control, store_instruction
from .reference import ReferenceSearch

TICKS_PER_MS = CLOCK_HZ // 1000


class VirtualModule:
    """A TMCL module in software: TMCM-6212, PD28-1021 (TMCM-1021) or PD86-1180 (TMCM-1180)."""

    def __init__(self, name: str = "TMCM-6212", address: int | None = None,
                 eeprom: str | os.PathLike | None = None, scenario=None) -> None:
        self.profile: ModuleProfile = load_profile(name)
        self.eeprom = Eeprom(eeprom, module=self.profile.name)
        self._address_override = address
        self.scenario = scenario
        self.now = 0
        self._events: list[bytes] = []
        self.power_up()

    # --- power-up / reset ---------------------------------------------------
    def power_up(self) -> None:
        """State after switching on: factory defaults overlaid by the EEPROM."""
        prof, ee = self.profile, self.eeprom
        self.globals = GlobalParameters(self)
        if self._address_override is not None:
            self.globals.ram[(0, 66)] = self._address_override
        self.axes: list[Axis] = []
        for i in range(prof.axes):
            ram = {}
            for num, p in prof.axis_parameters.items():
                stored = ee.get_axis(i, num) if p.storable else None
                ram[num] = p.default if stored is None else stored
            self.axes.append(Axis(i, prof, ram))
        restore = self.globals.get_raw(0, 85) == 0
        self.user_vars = [0] * prof.user_variables
        for n in range(prof.storable_user_variables):
            v = ee.get_user(n)
            if restore and v is not None:
                self.user_vars[n] = v
        self.coords = [[0] * (prof.coordinates + 1) for _ in range(prof.axes)]
        for a in range(prof.axes):
            for c in range(1, prof.coordinates + 1):
                v = ee.get_coord(a, c)
                if v is not None:
                    self.coords[a][c] = v
        self.io = IOBanks(self)
        self.interrupts = Interrupts(self)
        self.program = ProgramMemory(self)
        self.interpreter = Interpreter(self)
        self._searches = [ReferenceSearch(ax) for ax in self.axes]
        self.accumulator = 0
        self.x_register = 0
        self.flags = 0
        self.ascii_mode = False
        self.download_mode = False
        self.download_pointer = 0
        self.program_counter = 0
        self.application_status = 0
        self.event_mask = 0          # command 138 motors armed for the next / every MVP
        self.event_permanent = 0
        self._armed = 0              # motors whose arrival will be reported
        self._last_command = self.now
        self._heartbeat_fired = False
        self._engines_dirty = True
        self._engine_next: int | None = None
        self.interpreter.power_up()

    # --- addressing -------------------------------------------------------------
    @property
    def address(self) -> int:
        return self.globals.get_raw(0, 66)

    @property
    def host_address(self) -> int:
        return self.globals.get_raw(0, 76)

    def accepts_address(self, address: int) -> bool:
        """RS485 module address GP66 or secondary address GP87 (0 = off)."""
        secondary = self.globals.get_raw(0, 87)
        return address == self.address or (secondary != 0 and address == secondary)

    # --- wire interface -------------------------------------------------------
    def handle(self, frame: bytes) -> bytes:
        """Process one 9-byte request; return the reply bytes (b"" when no reply is due)."""
        if len(frame) != FRAME_LEN or not self.accepts_address(frame[0]):
            return b""
        command = frame[1]
        if checksum(frame[:8]) != frame[8]:
            return self._reply(Status.WRONG_CHECKSUM, command, 0)
        self.touch()
        address = self.address  # a reply comes from the address the request went to, even after SGP 66
        value = int.from_bytes(frame[4:8], "big", signed=True)
        out = execute(self, command, frame[2], frame[3], value, program=False)
        if out is None:  # no reply (command 137)
            return b""
        if isinstance(out, bytes):  # special reply format (136 type 0, 134)
            return out
        status, result = out
        if status == Status.OK and self.globals.get_raw(0, 255) == 1 and command not in NO_SUPPRESS:
            return b""
        return self._reply(status, command, result, address)

    def request(self, command: int, type: int = 0, motor: int = 0, value: int = 0) -> Reply | None:
        """Convenience for tests and tools: encode, handle, decode."""
        from ..protocol.frame import Request
        raw = self.handle(Request(self.address, command, type, motor, value).encode())
        return Reply.decode(raw, verify=False) if len(raw) == FRAME_LEN else None

    def _reply(self, status: int, command: int, value: int, address: int | None = None) -> bytes:
        module = self.address if address is None else address
        return Reply(self.host_address, module, int(status), command, to_int32(value)).encode()

    def touch(self) -> None:
        """A command arrived: restart the heartbeat (GP68 serial / GP82 CAN)."""
        self._last_command = self.now
        self._heartbeat_fired = False

    def drain_events(self) -> list[bytes]:
        """Unsolicited replies produced while time advanced (command 138, status 128)."""
        out, self._events = self._events, []
        return out

    # --- time ---------------------------------------------------------------------
    @property
    def time(self) -> float:
        """Virtual seconds since power-up."""
        return self.now / CLOCK_HZ

    def advance(self, seconds: float) -> None:
        if seconds < 0:
            raise ValueError("time cannot run backwards")
        self.advance_to(self.now + round(seconds * CLOCK_HZ))

    def advance_to(self, until: int) -> None:
        """Advance to absolute tick `until`, stopping at every event on the way.

        Engines are advanced lazily: only at their own events, before a
        command touches them (`sync`) and at the end."""
        self.horizon = until  # the interpreter may run pure instructions ahead up to here
        while self.now < until:
            nxt = self._next_event(until)
            self.now = nxt
            if nxt == self._engine_next:
                self.sync()
            self._after_step()
            self.interpreter.service()
        self.sync()

    def sync(self) -> None:
        """Bring every axis engine to `now` (before reading or commanding it)."""
        now = self.now
        for ax in self.axes:
            if ax.engine.now < now:
                ax.engine.advance(now)
        self._engines_dirty = True

    def _engine_event(self) -> int | None:
        if self._engines_dirty:
            times = [t for ax in self.axes if (t := ax.engine.next_event()) is not None]
            self._engine_next = min(times) if times else None
            self._engines_dirty = False
        return self._engine_next

    def _next_event(self, until: int) -> int:
        nxt = until
        t = self._engine_event()
        if t is not None and self.now < t < nxt:
            nxt = t
        hb = self._heartbeat_deadline()
        if hb is not None and self.now < hb < nxt:
            nxt = hb
        t = self.interpreter.next_event()
        if t is not None and self.now < t < nxt:
            nxt = t
        return nxt

    def _heartbeat_deadline(self) -> int | None:
        ms = self.globals.get_raw(0, 68)
        if not ms or self._heartbeat_fired:
            return None
        return self._last_command + ms * TICKS_PER_MS

    def _after_step(self) -> None:
        if self._armed and self.now == self._engine_next:
            for ax in self.axes:
                bit = 1 << ax.index
                if self._armed & bit and ax.engine.position_reached:
                    self._armed &= ~bit
                    self._events.append(Reply(self.host_address, self.address, Status.POSITION_REACHED_EVENT,
                                              138, bit).encode())
        hb = self._heartbeat_deadline()
        if hb is not None and self.now >= hb:
            self._heartbeat_fired = True
            self.sync()
            for ax in self.axes:  # GP68: "the motor will be stopped"
                ax.engine.hard_stop()

    def arm_position_event(self, motor: int) -> None:
        """Called by MVP: report arrival if command 138 asked for this motor."""
        bit = 1 << motor
        if self.event_mask & bit:
            self._armed |= bit
            if not self.event_permanent & bit:
                self.event_mask &= ~bit

    # --- services used by the command handlers ---------------------------------------
    def reference_search(self, axis: Axis) -> ReferenceSearch:
        return self._searches[axis.index]

    def clear_error_flags(self, which: int) -> None:
        """CLE: 0 all, 1 ETO, 2 EAL, 3 EDV, 4 EPO, 5 ESD (flag bit = 1 << (which - 1))."""
        self.flags &= ~0x1F if which == 0 else ~(1 << (which - 1))  # arithmetic flags stay (flags.py)

    def program_control(self, command: int, type: int, value: int):
        return program_control(self, command, type, value)

    def store_instruction(self, command: int, type: int, motor: int, value: int):
        return store_instruction(self, command, type, motor, value)

    def erase_program(self) -> None:
        self.program.erase()

    def restore_factory_defaults(self) -> None:
        """Command 137: EEPROM back to factory state, then a restart."""
        self.eeprom.clear()
        self.power_up()

    def close(self) -> None:
        """Flush the EEPROM (servers call this on shutdown)."""
        self.eeprom.flush()

    def __repr__(self) -> str:
        return f"VirtualModule({self.profile.name!r}, address={self.address}, t={self.time:.6f}s)"


__all__ = ["COMMANDS", "VirtualModule"]
