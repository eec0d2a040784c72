"""The virtual TMCL module: wire-format requests in, replies out, motors in virtual time.

    vm = VirtualModule("TMCM-6212", address=1)
    reply = vm.handle(frame)      # 9-byte request -> reply bytes (b"" when no reply is due)
    vm.advance(0.25)              # virtual seconds

The module holds the TMCL state (parameters, registers, program, I/O, EEPROM); its `scheduler`
owns the clock, the next-event look-up and every cache (scheduler.py); every command goes through
the command table (table.py).
"""
from __future__ import annotations

import os
import struct
from functools import partial
from typing import Any, Literal, overload

from ..faults import load_plan
from ..modules.profile import ModuleProfile, load_profile
from ..protocol.frame import FRAME_LEN, Reply, encode_frame
from ..protocol.opcodes import REQUEST_TARGET_REACHED_EVENT
from ..protocol.status import Status
from .ascii import AsciiInterface
from .commands import StatusReply
from .eeprom import Eeprom
from .effects import Effect
from .faults import ModuleFaults
from .globals import GlobalParameters
from .heartbeat import OF_INTERFACE, Heartbeats
from .interpreter import Interpreter
from .interrupts import Interrupts
from .io import IOBanks
from .motor import Motor
from .program import ProgramMemory, store_instruction
from .reference import ReferenceSearch
from .requests import RequestPath, Setter, reply_bytes
from .scheduler import Scheduler
from .status import TmclStatus
from .table import TABLE, execute, suppressible
from .world import ScenarioSource, World

_REQUEST = struct.Struct(">BBBBiB")
_REPLY = struct.Struct(">BBBBi")
_ADDRESS, _HOST, _SECONDARY, _SUPPRESS = (0, 66), (0, 76), (0, 87), (0, 255)
EEPROM_MAGIC, MAGIC_VALUE = (0, 64), 0xE4
_OK, _WRONG_CHECKSUM = int(Status.OK), int(Status.WRONG_CHECKSUM)
_NO_READS: dict = {}  # the request path's table while faults watch every frame: never written


def _check_address(profile: ModuleProfile, address: int) -> None:
    """A module address given to the constructor or `assign_address`: a value GP66 accepts."""
    gp66 = profile.global_parameters.get(_ADDRESS)
    if gp66 is None:
        raise ValueError(f"{profile.name} has no serial address parameter GP66 to set")
    if not (type(address) is int and gp66.accepts(address)):
        raise ValueError(f"module address must be an integer in the range of GP66, got {address!r}")


class VirtualModule:
    """A TMCL module in software: TMCM-6212, PD28-1021 (TMCM-1021) or PD86-1180 (TMCM-1180)."""

    scheduler_class: type[Scheduler] = Scheduler
    interpreter_class: type[Interpreter] = Interpreter
    """The parts a subclass may replace (the test suite's oracle: one event per instruction)."""
    _hook: ModuleFaults | None = None   # faults that see every frame and every advance (faults.py)
    _faults: ModuleFaults | None = None

    def __init__(self, name: str = "TMCM-6212", address: int | None = None,
                 eeprom: str | os.PathLike[str] | None = None, scenario: ScenarioSource = None,
                 faults: object = None) -> None:
        self.profile: ModuleProfile = load_profile(name)
        if address is not None:
            _check_address(self.profile, address)
        self.opcodes = self.profile.opcodes
        self.eeprom = Eeprom(eeprom, module=self.profile.name)
        self._address_override = address
        self.scenario = scenario
        self.scheduler = self.scheduler_class(self)
        self.requests = RequestPath(self)
        self._reads = self.requests.reads    # the request path's table, read on every frame
        self._writes = self.requests.writes
        self.events: list[bytes] = []
        """Unsolicited replies produced while time advanced (command 138, status 128)."""
        self._download_mode = False
        self.world = World(self, scenario)
        self.power_up()
        plan = self.world.scenario.faults
        if plan or faults is not None:  # the scenario's [[fault]] tables and `faults` (docs/faults.md)
            self.faults.load(plan.merged(load_plan(faults)) if faults is not None else plan)

    # --- power-up / reset ---------------------------------------------------------------
    def power_up(self) -> None:
        """State after switching on: factory defaults overlaid by the EEPROM."""
        prof, ee = self.profile, self.eeprom
        magic = ee.get_global(0, EEPROM_MAGIC[1])
        if EEPROM_MAGIC in prof.global_parameters and magic is not None and magic != MAGIC_VALUE:
            ee.clear()  # PD86-1180 6.1 GP64: another value than $E4 re-initialises to factory defaults
        self.globals = GlobalParameters(self)
        if self._address_override is not None:
            self.globals.ram[_ADDRESS] = self._address_override
        self.axes: list[Motor] = []
        for i in range(prof.axes):
            ram = {}
            for num, p in prof.axis_parameters.items():
                stored = ee.get_axis(i, num) if p.storable else None
                ram[num] = p.default if stored is None else stored
            self.axes.append(Motor(i, prof, ram))
        restore = self.globals.get_raw(0, 85) == 0
        self.user_vars = [0] * prof.user_variables
        for n in range(prof.storable_user_variables):
            v = ee.get_user(n)
            if restore and v is not None:
                self.user_vars[n] = v
        self.coords = [[0] * (prof.coordinates + 1) for _ in range(prof.axes)]
        restore_coords = self.globals.get_raw(0, 84) == 1  # GP84 = 1: "copied back on startup"
        for a in range(prof.axes if restore_coords else 0):
            for c in range(1, prof.coordinates + 1):
                v = ee.get_coord(a, c)
                if v is not None:
                    self.coords[a][c] = v
        self.io = IOBanks(self)
        self.interrupts = Interrupts(self)
        self.program = ProgramMemory(self)
        self.interpreter = self.interpreter_class(self)
        self._searches = [ReferenceSearch(ax) for ax in self.axes]
        self.accumulator = 0
        self.x_register = 0
        self.flags = 0
        self.ascii = AsciiInterface(self)
        # GP67 bit 0: start up in ASCII mode (PD28-1021 manual 3.4.4)
        self.ascii_mode = self.profile.ascii_mode and bool(self.globals.get_raw(0, 67) & 1)
        self.download_mode = False
        self.download_pointer = 0
        self.program_counter = 0
        self.application_status = 0
        self.event_mask = 0          # command 138 motors armed for the next / every MVP
        self.event_permanent = 0
        self.armed = 0
        """Motors whose arrival will be reported (command 138)."""
        self.heartbeats = Heartbeats(self)
        self.scheduler.power_up()
        for ax in self.axes:
            ax.world = self.world
        self.world.power_up()
        self.interpreter.power_up()

    # --- addressing -------------------------------------------------------------
    def assign_address(self, address: int) -> None:
        """Serve at `address` from now on, as the constructor's `address` argument does (GP66 in RAM,
        kept across resets; the EEPROM is not written)."""
        _check_address(self.profile, address)
        self._address_override = address
        self.globals.ram[_ADDRESS] = address
        self.scheduler.invalidate(Effect.REQUESTS)

    def stored_global(self, bank: int, number: int) -> int | None:
        """The value of a global parameter in the EEPROM (None when it is not stored there)."""
        return self.eeprom.get_global(bank, number)

    @property
    def address(self) -> int:
        return self.globals.ram.get(_ADDRESS, 0)

    @property
    def host_address(self) -> int:
        return self.globals.ram.get(_HOST, 0)

    def accepts_address(self, address: int) -> bool:
        """RS485 module address GP66 or secondary address GP87 (0 = off)."""
        ram = self.globals.ram
        if address == ram.get(_ADDRESS, 0):
            return True
        secondary = ram.get(_SECONDARY, 0)
        return secondary != 0 and address == secondary

    # --- wire interface -------------------------------------------------------
    @overload
    def handle(self, frame: bytes, as_reply: Literal[False] = False, *, interface: str = "serial",
               direct: bool = False) -> bytes: ...

    @overload
    def handle(self, frame: bytes, as_reply: bool, *, interface: str = "serial",
               direct: bool = False) -> Reply | bytes: ...

    def handle(self, frame: bytes, as_reply: bool = False, *, interface: str = "serial",
               direct: bool = False) -> Reply | bytes:
        """Process one 9-byte request; return the reply bytes (b"" when no reply is due).

        `interface` is the link the frame came over: "serial" (or "rs232", "rs485": the module
        answers only its address GP66 / secondary address GP87), "usb" (the address byte is
        ignored, the reply carries the module's own address) or "can". CAN requests restart the
        CAN heartbeat GP82, the others the serial heartbeat GP68 (docs/endpoints.md).

        `direct=True`: the frame comes from a host that did not open the download under way (a
        served module's other link, docs/endpoints.md "Several hosts"): it is executed as in
        direct mode even in download mode, never stored (`table.execute`). Without a download
        under way it changes nothing.

        A read that has a pre-bound handler skips the general path (requests.py): the table is
        keyed by the whole frame, so one lookup checks length, address, command, type, motor
        and checksum at once. Every other frame takes the general path (`_handle_general`).
        `as_reply` (a host in this process, `InProcessTransport`): a pre-bound read answers with
        the `Reply` it would pack (nothing to pack or decode), every other request with bytes."""
        try:
            fast = self._reads.get(frame)
        except TypeError:  # a mutable buffer: the general path reads it
            fast = None
        if fast is not None:
            heartbeat = OF_INTERFACE.get(interface)
            if heartbeat is not None:
                return fast(heartbeat, as_reply)  # the heartbeat restarted, the engines at now
        hook = self._hook
        if hook is not None:  # faults decide first (firmware/faults.py)
            general = partial(self._handle_general, direct=True) if direct else self._handle_general
            return hook.handle(frame, interface, general)
        return self._handle_general(frame, interface, direct)

    def _handle_general(self, frame: bytes, interface: str, direct: bool = False) -> bytes:
        if len(frame) != FRAME_LEN:
            return b""
        target, command, type_, motor, value, check = _REQUEST.unpack(frame)
        ram = self.globals.ram
        address = ram.get(_ADDRESS, 0)  # replies come from the address the request went to, even after SGP 66
        if target != address and (target != ram.get(_SECONDARY, 0) or not target) and interface != "usb":
            return b""
        if sum(frame[:8]) & 0xFF != check:
            return self._reply(_WRONG_CHECKSUM, command, 0, address)
        self.scheduler.invalidate(Effect.COMMAND)  # the next `advance` starts afresh
        if self._writes and interface in OF_INTERFACE:
            write = self._writes.get(bytes(frame[:4]))
            if write is not None:
                return self._write(write, command, type_, motor, value, address, interface)
        self.touch("can" if interface == "can" else "serial")
        out = execute(self, command, type_, motor, value, program=False, direct=direct)
        if out is None:  # no reply (command 137)
            return b""
        if out.__class__ is bytes:  # special reply format (136 type 0, 134): suppressed as any other
            return b"" if self._suppressed(command) else out
        status, result = out
        if status == _OK:
            if self._suppressed(command):
                return b""
            if interface in OF_INTERFACE and not self._download_mode and (
                    interface != "usb" or self.accepts_address(target)):
                # a USB frame is bound only if the serial link would take it too: the table is shared
                self.requests.bind(frame, command, type_, motor)
        return self._reply(status, command, result, address)

    def _suppressed(self, command: int) -> bool:
        """GP255 = 1 suppresses the reply of a successful `command` (TMCM-6212 5.1, table.suppressible)."""
        return self.globals.ram.get(_SUPPRESS) == 1 and suppressible(command)

    def _write(self, write: Setter, command: int, type_: int, motor: int, value: int, address: int,
               interface: str) -> bytes:
        """A pre-bound SAP/SGP: what `execute` does for it (the table's effect), without the lookups."""
        self.touch(OF_INTERFACE[interface])
        self.scheduler.prepare(TABLE[command].effect_of(type_, motor))
        try:
            write(value)
        except TmclStatus as exc:
            return self._reply(exc.status, command, 0, address)
        if self.globals.ram.get(_SUPPRESS) == 1:  # kept although an SGP 255 drops the tables
            return b""
        return self._reply(_OK, command, 0, address)

    def __getstate__(self) -> dict[str, Any]:
        """A copy (copy.deepcopy, pickle) binds its own handlers: the request path's table is
        looked up again from the copy's own request path."""
        return {k: v for k, v in self.__dict__.items() if k not in ("_reads", "_writes")}

    def __setstate__(self, state: dict[str, Any]) -> None:
        self.__dict__.update(state)
        self._reads = self.requests.reads if self._hook is None else _NO_READS
        self._writes = self.requests.writes

    # --- faults (docs/faults.md) ----------------------------------------------------------------
    @property
    def faults(self) -> ModuleFaults:
        """The module's faults: power loss, a firmware that hangs, overtemperature, switches,
        lost steps, by name, at a time or on a request (firmware/faults.py)."""
        if self._faults is None:
            self._faults = ModuleFaults(self)
        return self._faults

    def watch(self, hook: ModuleFaults | None) -> None:
        """From now on `hook` sees every frame (`handle(frame, interface, general)`) and every
        advance (`advance_to(until)`); None: no longer. No pre-bound read answers while it does."""
        self._hook = hook
        self._reads = self.requests.reads if hook is None else _NO_READS

    def is_prebound(self, frame: bytes) -> bool:
        """Whether `frame` is answered by a pre-bound handler (tests, benchmarks)."""
        return self.requests.is_prebound(frame)

    def forget_requests(self) -> None:
        """Drop the pre-bound handlers and the program's compiled steps (they are bound again when
        next used)."""
        self.scheduler.invalidate(Effect.REQUESTS)

    @property
    def download_mode(self) -> bool:
        """Command 132 is storing instructions (3.6.36): no pre-bound handler answers then."""
        return self._download_mode

    @download_mode.setter
    def download_mode(self, on: bool) -> None:
        if on:
            self.scheduler.invalidate(Effect.REQUESTS)
        self._download_mode = on

    def request(self, command: int, type: int = 0, motor: int = 0, value: int = 0) -> Reply | None:
        """Convenience for tests and tools: encode, handle, decode."""
        raw = self.handle(encode_frame(self.address, command, type, motor, value))
        return Reply(*_REPLY.unpack_from(raw)) if len(raw) == FRAME_LEN else None

    def _reply(self, status: int, command: int, value: int, address: int | None = None) -> bytes:
        return reply_bytes(self.host_address, self.address if address is None else address, status, command, value)

    def touch(self, interface: str = "serial") -> None:
        """A command arrived: restart that interface's heartbeat (GP68 serial / GP82 CAN)."""
        self.heartbeats.touch(interface)

    def feed_ascii(self, data: bytes) -> bytes:
        """ASCII mode (command 139 or GP67 bit 0): received bytes in, echo and reply lines out."""
        return self.ascii.feed(data)

    def drain_events(self) -> list[bytes]:
        """Unsolicited replies produced while time advanced (command 138, status 128). `events` stays
        the same list (emptied here): a caller may look at it to learn whether any wait."""
        events = self.events
        out = events[:]
        events.clear()
        return out

    # --- time -----------------------------------------------------------------------------
    @property
    def now(self) -> int:
        """The module's time in 16 MHz ticks (the scheduler's clock)."""
        return self.scheduler.now

    @property
    def time(self) -> float:
        """Virtual seconds since power-up."""
        return self.scheduler.time

    def advance(self, seconds: float) -> None:
        hook = self._hook
        if hook is None:
            self.scheduler.advance(seconds)
        else:
            hook.advance_to(self.scheduler.tick_after(seconds))

    def advance_to(self, until: int) -> None:
        """Advance to absolute tick `until`, stopping at every event on the way (scheduler.py)."""
        hook = self._hook
        if hook is None:
            self.scheduler.advance_to(until)
        else:
            hook.advance_to(until)

    def next_event_in(self) -> float | None:
        """Seconds until the next internal event (engine, heartbeat, program, world, a fault's
        action), or None."""
        hook = self._hook
        return self.scheduler.next_event_in() if hook is None else hook.next_event_in()

    def sync(self) -> None:
        """Bring every axis engine to now before the module's state is changed from outside a
        command (the world's Python API): their next events are looked up again."""
        self.scheduler.prepare(Effect.ENGINES)

    def engine_now(self, axis: int) -> Any:
        """The engine of `axis` brought to now (WAIT POS, the target-reached interrupt)."""
        return self.scheduler.engine_now(axis)

    # --- command 138 ---------------------------------------------------------------------
    def arm_position_event(self, motor: int) -> None:
        """Called by MVP: report arrival if command 138 asked for this motor."""
        bit = 1 << motor
        if self.event_mask & bit:
            self.armed |= bit
            if not self.event_permanent & bit:
                self.event_mask &= ~bit

    def report_arrival(self, i: int) -> None:
        """The scheduler saw axis `i` at an event: report its arrival if it has reached its target."""
        if self.axes[i].engine.position_reached:
            self.armed &= ~(1 << i)
            self.events.append(Reply(self.host_address, self.address, Status.POSITION_REACHED_EVENT,
                                     REQUEST_TARGET_REACHED_EVENT, 1 << i).encode())

    # --- services used by the command handlers ---------------------------------------
    def reference_search(self, axis: Motor) -> ReferenceSearch:
        return self._searches[axis.index]

    def clear_error_flags(self, which: int) -> None:
        """CLE: 0 all, 1 ETO, 2 EAL, 3 EDV, 4 EPO, 5 ESD (flag bit = 1 << (which - 1))."""
        self.flags &= ~0x1F if which == 0 else ~(1 << (which - 1))  # arithmetic flags stay (flags.py)

    def store_instruction(self, command: int, type: int, motor: int, value: int) -> StatusReply:
        return store_instruction(self, command, type, motor, value)

    def erase_program(self) -> None:
        """GP81 protection off erases the program; a running program is reset first (131), as
        it has nothing left to run (docs/assumptions.md)."""
        self.interpreter.reset()
        self.program.erase()
        self.scheduler.invalidate(Effect.PROGRAM)

    def restore_factory_defaults(self) -> None:
        """Command 137: EEPROM back to factory state, then a restart."""
        self.eeprom.clear()
        self.power_up()

    def close(self) -> None:
        """Flush the EEPROM (servers call this on shutdown)."""
        self.eeprom.flush()

    def __repr__(self) -> str:
        return f"VirtualModule({self.profile.name!r}, address={self.address}, t={self.time:.6f}s)"


__all__ = ["VirtualModule"]
