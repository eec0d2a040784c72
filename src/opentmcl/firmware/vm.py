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
import struct
from typing import Any

from ..modules.profile import ModuleProfile, load_profile
from ..motion import CLOCK_HZ
from ..protocol.frame import FRAME_LEN, Reply, encode_frame
from ..protocol.status import Status
from .ascii import AsciiInterface
from .axis import Axis
from .commands import NO_SUPPRESS, StatusReply, execute
from .dispatch import Entry, Setter, entry, reply_bytes, setter
from .eeprom import Eeprom
from .globals import GlobalParameters
from .interpreter import Bound, Interpreter
from .interrupts import Interrupts
from .io import IOBanks
from .program import RUNNING, STEPPING, ProgramMemory, program_control, store_instruction
from .reference import ReferenceSearch
from .status import TmclStatus
from .world import ScenarioSource, World

TICKS_PER_MS = CLOCK_HZ // 1000
_REQUEST = struct.Struct(">BBBBiB")
_REPLY = struct.Struct(">BBBBi")
_ADDRESS, _HOST, _SECONDARY, _SUPPRESS = (0, 66), (0, 76), (0, 87), (0, 255)
EEPROM_MAGIC, MAGIC_VALUE = (0, 64), 0xE4
_SERIAL_HB, _CAN_HB = (0, 68), (0, 82)
_RUNNING = (RUNNING, STEPPING)
_FAR = 1 << 63  # a tick no advance reaches
_INF = float("inf")
_HEARTBEATS = (("serial", _SERIAL_HB), ("can", _CAN_HB))
_OK, _WRONG_CHECKSUM = int(Status.OK), int(Status.WRONG_CHECKSUM)
_FAST_COMMANDS = frozenset({6, 10, 15})  # GAP, GGP, GIO: pre-bound handlers (dispatch.py)
_HEARTBEAT_OF = {"serial": "serial", "rs485": "serial", "rs232": "serial", "usb": "serial",
                 "can": "can"}  # the heartbeat a link's requests restart: GP68 / GP82
_FAST_INTERFACES = tuple(_HEARTBEAT_OF)  # every link may use the pre-bound handlers
_WRITE_COMMANDS = frozenset({5, 9})  # SAP, SGP: pre-bound setters (dispatch.py)
_MAX_BOUND = 4096  # pre-bound frames kept at most (each differs in address, type, motor or value)


def _check_address(profile: ModuleProfile, address: int) -> None:
    """A module address given to the constructor or `assign_address`: a value GP66 accepts."""
    gp66 = profile.global_parameters.get(_ADDRESS)
    if gp66 is None:
        raise ValueError(f"{profile.name} has no serial address parameter GP66 to set")
    if not (type(address) is int and gp66.accepts(address)):
        raise ValueError(f"module address must be an integer in the range of GP66, got {address!r}")


class VirtualModule:
    """A TMCL module in software: TMCM-6212, PD28-1021 (TMCM-1021) or PD86-1180 (TMCM-1180)."""

    def __init__(self, name: str = "TMCM-6212", address: int | None = None,
                 eeprom: str | os.PathLike[str] | None = None, scenario: ScenarioSource = None) -> None:
        self.profile: ModuleProfile = load_profile(name)
        if address is not None:
            _check_address(self.profile, address)
        self.opcodes = self.profile.opcodes
        self.eeprom = Eeprom(eeprom, module=self.profile.name)
        self._address_override = address
        self.scenario = scenario
        self.now = 0
        self._events: list[bytes] = []
        self._requests: dict[bytes, Entry] = {}
        self._writes: dict[bytes, Setter] = {}
        self._entries: dict[bytes, Entry | None] = {}
        self._download_mode = False
        self.world = World(self, scenario)
        self.power_up()

    # --- power-up / reset ---------------------------------------------------
    def power_up(self) -> None:
        """State after switching on: factory defaults overlaid by the EEPROM."""
        prof, ee = self.profile, self.eeprom
        magic = ee.get_global(0, EEPROM_MAGIC[1])
        if EEPROM_MAGIC in prof.global_parameters and magic is not None and magic != MAGIC_VALUE:
            ee.clear()  # PD86-1180 6.1 GP64: another value than $E4 re-initialises to factory defaults
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
        restore_coords = self.globals.get_raw(0, 84) == 1  # GP84 = 1: "copied back on startup"
        for a in range(prof.axes if restore_coords else 0):
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
        self.ascii = AsciiInterface(self)
        # GP67 bit 0: start up in ASCII mode (PD28-1021 manual 3.4.4)
        self.ascii_mode = self.profile.ascii_mode and bool(self.globals.get_raw(0, 67) & 1)
        self.download_mode = False
        self.download_pointer = 0
        self.program_counter = 0
        self.application_status = 0
        self.event_mask = 0          # command 138 motors armed for the next / every MVP
        self.event_permanent = 0
        self._armed = 0              # motors whose arrival will be reported
        self._last_command = {"serial": self.now, "can": self.now}
        self._heartbeat_fired = False
        self._engine_next: int | None = None
        self._axis_next: list[int | None] = [None] * len(self.axes)
        self._reset_request_path()
        for ax in self.axes:
            ax.world = self.world
        self.world.power_up()
        self.interpreter.power_up()

    def _reset_request_path(self) -> None:
        """New axes, globals and I/O banks: the pre-bound handlers are stale, the engines unsynced."""
        self.forget_requests()
        self._engines = [ax.engine for ax in self.axes]
        self._engines_dirty = True
        self._synced_at = -1
        self._carry_until = -1

    # --- addressing -------------------------------------------------------------
    def assign_address(self, address: int) -> None:
        """Serve at `address` from now on, as the constructor's `address` argument does (GP66 in RAM,
        kept across resets; the EEPROM is not written)."""
        _check_address(self.profile, address)
        self._address_override = address
        self.globals.ram[_ADDRESS] = address
        self.forget_requests()

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
    def handle(self, frame: bytes, *, interface: str = "serial") -> bytes:
        """Process one 9-byte request; return the reply bytes (b"" when no reply is due).

        `interface` is the link the frame came over: "serial" (or "rs232", "rs485": the module
        answers only its address GP66 / secondary address GP87), "usb" (the address byte is
        ignored, the reply carries the module's own address) or "can". CAN requests restart the
        CAN heartbeat GP82, the others the serial heartbeat GP68 (docs/endpoints.md).

        A read that has a pre-bound handler skips the general path (dispatch.py): the table is
        keyed by the whole frame, so one lookup checks length, address, command, type, motor
        and checksum at once. Every other frame takes the general path (`_handle_general`)."""
        try:
            fast = self._requests.get(frame)
        except TypeError:  # a mutable buffer: the general path reads it
            fast = None
        heartbeat = _HEARTBEAT_OF.get(interface)
        if fast is not None and heartbeat is not None:
            now = self.now
            self._last_command[heartbeat] = now  # touch(): restart the heartbeat
            self._heartbeat_fired = False
            if self._synced_at != now:
                self._sync_engines()
            return fast()
        return self._handle_general(frame, interface)

    def _handle_general(self, frame: bytes, interface: str) -> bytes:
        if len(frame) != FRAME_LEN:
            return b""
        target, command, type_, motor, value, check = _REQUEST.unpack(frame)
        ram = self.globals.ram
        address = ram.get(_ADDRESS, 0)  # replies come from the address the request went to, even after SGP 66
        if target != address and (target != ram.get(_SECONDARY, 0) or not target) and interface != "usb":
            return b""
        if sum(frame[:8]) & 0xFF != check:
            return self._reply(_WRONG_CHECKSUM, command, 0, address)
        self._carry_until = -1  # a command: the next `advance` starts afresh
        if self._writes and interface in _FAST_INTERFACES:
            write = self._writes.get(bytes(frame[:4]))
            if write is not None:
                return self._write(write, command, value, address, interface)
        self.touch("can" if interface == "can" else "serial")
        out = execute(self, command, type_, motor, value, program=False)
        if out is None:  # no reply (command 137)
            return b""
        if out.__class__ is bytes:  # special reply format (136 type 0, 134)
            return out
        status, result = out
        if status == _OK:
            if command not in NO_SUPPRESS and self.globals.ram.get(_SUPPRESS) == 1:
                return b""
            if interface in _FAST_INTERFACES and not self._download_mode and (
                    interface != "usb" or self.accepts_address(target)):
                # a USB frame is bound only if the serial link would take it too: the table is shared
                self._bind(frame, command, type_, motor)
        return self._reply(status, command, result, address)

    def _bind(self, frame: bytes, command: int, type_: int, motor: int) -> None:
        """Keep the pre-bound handler of a read (keyed by the frame) or of a SAP/SGP (keyed by its
        first four bytes) that has just succeeded on the general path."""
        if command in _FAST_COMMANDS:
            shape = bytes(frame[:4])  # frames differing in the value field share one handler
            fast = self._entries.get(shape) or self._entries.setdefault(shape, entry(self, command, type_, motor))
            if fast is not None:
                if len(self._requests) >= _MAX_BOUND:  # a host varying the ignored value field
                    self._requests = {}
                self._requests[bytes(frame)] = fast
        elif command in _WRITE_COMMANDS:
            write = setter(self, command, type_, motor)
            if write is not None:
                self._writes[bytes(frame[:4])] = write

    def _write(self, write: Setter, command: int, value: int, address: int, interface: str) -> bytes:
        """A pre-bound SAP/SGP: what `execute` does for it, without the lookups."""
        self.touch(_HEARTBEAT_OF[interface])
        self.sync()  # a write may change an engine's next event
        try:
            write(value)
        except TmclStatus as exc:
            return self._reply(exc.status, command, 0, address)
        if self.globals.ram.get(_SUPPRESS) == 1:  # kept although an SGP 255 drops the tables
            return b""
        return self._reply(_OK, command, 0, address)

    def is_prebound(self, frame: bytes) -> bool:
        """Whether `frame` is answered by a pre-bound handler (tests, benchmarks)."""
        return bytes(frame) in self._requests or bytes(frame[:4]) in self._writes

    def __getstate__(self) -> dict[str, Any]:
        """A copy (copy.deepcopy, pickle) binds its own handlers, reads and stores: these are bound
        to this module's axes, banks and engines (`forget_requests`)."""
        state = self.__dict__.copy()
        state.update(_requests={}, _entries={}, _writes={}, _program_ops={})
        return state

    def forget_requests(self) -> None:
        """Drop the pre-bound handlers (an address, the host address or the module's state
        changed) and the program's reads and stores (`Interpreter._bound`); they are bound again
        when next used."""
        self._requests = {}
        self._entries = {}
        self._writes = {}
        self._program_ops: dict[tuple[int, int, int], Bound | None] = {}

    @property
    def download_mode(self) -> bool:
        """Command 132 is storing instructions (3.6.36): no pre-bound handler answers then."""
        return self._download_mode

    @download_mode.setter
    def download_mode(self, on: bool) -> None:
        if on:
            self.forget_requests()
        self._download_mode = on

    def request(self, command: int, type: int = 0, motor: int = 0, value: int = 0) -> Reply | None:
        """Convenience for tests and tools: encode, handle, decode."""
        raw = self.handle(encode_frame(self.address, command, type, motor, value))
        return Reply(*_REPLY.unpack_from(raw)) if len(raw) == FRAME_LEN else None

    def _reply(self, status: int, command: int, value: int, address: int | None = None) -> bytes:
        return reply_bytes(self.host_address, self.address if address is None else address, status, command, value)

    def touch(self, interface: str = "serial") -> None:
        """A command arrived: restart that interface's heartbeat (GP68 serial / GP82 CAN)."""
        self._last_command[interface] = self.now
        self._heartbeat_fired = False

    def feed_ascii(self, data: bytes) -> bytes:
        """ASCII mode (command 139 or GP67 bit 0): received bytes in, echo and reply lines out."""
        return self.ascii.feed(data)

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
        if not seconds >= 0 or seconds == _INF:  # also NaN
            raise ValueError(f"seconds must be a finite number >= 0, got {seconds!r}")
        self.advance_to(self.now + round(seconds * CLOCK_HZ))

    def advance_to(self, until: int) -> None:
        """Advance to absolute tick `until`, stopping at every event on the way.

        Engines are advanced lazily: each only at its own events, before a
        command touches them (`sync`) and at the end. A lagging engine's flags
        (position reached, mode) cannot change before its next event.

        The next event of everything but the program (`_limit_event`) is cached during
        the call and looked up again only after a write that can move it (docs/architecture.md
        "Time"). A call starts afresh unless only pre-bound reads came since the last one
        ended and its limit lies beyond `until` (`_carry_until`)."""
        self.horizon = until  # the interpreter may run pure instructions ahead up to here
        if self.now <= until < self._carry_until and not self._engines_dirty \
                and not (self._carry_hb and self._heartbeat_by(until)):
            self.now = until  # carried: no event up to `until` (`_carry_limit`)
            self.sync_for_read()
            return
        self._carry_until = -1
        try:
            while self.now < until:
                self._event_at(self._next_event(until))
            self._carry_until = self._carry_limit()
        finally:
            self._limit_ok = False  # host commands come next
        self.sync_for_read()  # every event up to `until` is done: the engines' next events stand

    def _event_at(self, tick: int) -> None:
        """Everything due at the event `tick` (> now): engines, world, heartbeats, the program."""
        self.now = tick
        if tick == self._engine_next:
            self._engine_step(tick)
        if self.world.service():
            self._limit_ok = False
        self._after_step()
        self.interpreter.service()

    _carry_until = -1
    """A later `advance_to` may skip its event loop up to (not including) this tick (`_carry_limit`).
    What can move the limit ends the carry: every command and the world's Python API through `sync`
    (`_engines_dirty`), the world's inputs (`World.set_input`), and any frame the general path takes."""
    _carry_hb = False  # a heartbeat is on: a pre-bound read restarts it, so its deadline is looked up

    def _carry_limit(self) -> int:
        """Up to which tick the limit found by this `advance_to` holds for the next ones, if only
        pre-bound reads come in between: the limit itself when no write came since it was looked
        up (`_limit_ok`; a world that acts at every tick, `World.quiet`, clears it at each), and the
        loop would do nothing at the ticks before it that are no event. Not so with a program
        running (it runs at its own ticks) or a timer that rolls over before (`Interrupts._run_timers`)."""
        if not self._limit_ok or self._engines_dirty or self.application_status in _RUNNING:
            return -1
        limit = self._limit
        first = self.interrupts._first_due
        carry = _FAR if limit is None else limit
        if first is not None and first < carry:
            carry = first
        ram = self.globals.ram
        self._carry_hb = bool(ram.get(_SERIAL_HB) or ram.get(_CAN_HB))
        return carry

    def _heartbeat_by(self, until: int) -> bool:
        """Does a heartbeat expire by `until` (a carried `advance_to` stops there)?"""
        hb = self._heartbeat_deadline()
        return hb is not None and hb <= until

    def _engine_step(self, now: int) -> None:
        """Advance the engines whose event is due now; report arrivals (command 138)."""
        times = self._axis_next
        for i, t in enumerate(times):
            if t == now:
                engine = self.axes[i].engine
                engine.advance(now)
                times[i] = engine.next_event()
                if self._armed >> i & 1:
                    self._report_arrival(i)
        self._engine_next = min((t for t in times if t is not None), default=None)

    def _report_arrival(self, i: int) -> None:
        if self.axes[i].engine.position_reached:
            self._armed &= ~(1 << i)
            self._events.append(Reply(self.host_address, self.address, Status.POSITION_REACHED_EVENT,
                                      138, 1 << i).encode())

    def sync(self) -> None:
        """Bring every axis engine to `now` (before reading or commanding it); their next
        events are looked up again afterwards, since a command may change them."""
        if self._synced_at != self.now:
            self._sync_engines()
        self._engines_dirty = True

    def sync_for_read(self, engines: list[Any] | None = None) -> None:
        """Bring every axis engine (or those of `engines`, the ones a program's read looks at) to
        `now` for a pure read (GAP, GGP, GIO, GCO): advancing an engine within its segment leaves
        its next event, so the engines stay clean. Engines left behind follow at the next sync."""
        if self._synced_at == self.now:
            return
        if engines is None or engines is self._engines:
            self._sync_engines()
            return
        now = self.now
        for engine in engines:
            if engine.now < now:
                engine.advance(now)

    def engine_now(self, axis: int) -> Any:
        """The engine of `axis` brought to `now`, for a flag read outside a command (WAIT POS, the
        target-reached interrupt): a lagging engine's flags hold at its own tick, and a motion
        started from standstill leaves AP8 set at that very tick."""
        engine = self.axes[axis].engine
        if self._synced_at != self.now and engine.now < self.now:
            self.sync_for_read([engine])
        return engine

    def _sync_engines(self) -> None:
        now = self.now
        for engine in self._engines:
            if engine.now < now:
                engine.advance(now)
        self._synced_at = now

    def _engine_event(self) -> int | None:
        if self._engines_dirty:
            self._axis_next = [ax.engine.next_event() for ax in self.axes]
            if self._armed:  # a command may have reached its target at once (MVP to where it is)
                for i in range(len(self.axes)):
                    if self._armed >> i & 1:
                        self._report_arrival(i)
            self._engine_next = min((t for t in self._axis_next if t is not None), default=None)
            self._engines_dirty = False
        return self._engine_next

    _limit: int | None = None
    _limit_other: int | None = None  # the part of `_limit` that is not the timers'
    _limit_ok = False   # `_limit` is valid (only inside `advance_to`)
    event_cache = True  # False: look every event up afresh (the reference the tests compare with)

    def _next_event(self, until: int) -> int:
        now = self.now
        nxt = until
        t = self._limit_event()
        if t is not None and now < t < nxt:
            nxt = t
        t = self.interpreter.own_event()
        if t is not None and now < t < nxt:
            nxt = t
        return nxt

    def _limit_event(self) -> int | None:
        """Next event of the engines, heartbeats, timers and world (all but the program's own
        schedule), > now or None. Cached while `_limit_ok`; a write that can move it clears the
        flag (commands via `_engines_dirty`, world checks, a program instruction that is not pure,
        a read or RETI) and reaching it makes it stale (engine events, timers, heartbeats: the
        event is the limit itself); when only a timer's event was reached and nothing was written,
        only the timers are looked up again (`_limit_other`: the rest, unchanged)."""
        now = self.now
        t = self._limit
        held = self._limit_ok and not self._engines_dirty  # no write since the last look-up
        ints = self.interrupts
        if held:
            if t is None or t > now:
                return t
            other = self._limit_other
            if other is None or other > now:  # only a timer's event was reached: the rest stands
                t = ints.next_timer_event(now, refresh=False)
                best = other if t is None or now >= t or (other is not None and other <= t) else t
                self._limit = best
                return best
        return self._look_limit_up(now, held)

    def _look_limit_up(self, now: int, held: bool) -> int | None:
        """`_limit_event` afresh; `held`: nothing was written since the last look-up."""
        ints = self.interrupts
        best = None
        t = self._engine_event()
        if t is not None and now < t:
            best = t
        hb = self._heartbeat_deadline()
        if hb is not None and now < hb and (best is None or hb < best):
            best = hb
        if not held:  # else reached: an event tick, polled by the interpreter with no write since
            ints.poll(now)  # latch what a command just did (levels) and re-phase rewritten timers
        dirty = self._engines_dirty  # the world's look-up syncs lagging engines: no plan changes
        t = self.world.next_event(same_axes=held)
        self._engines_dirty = dirty
        if t is not None and now < t and (best is None or t < best):
            best = t
        self._limit_other = best
        t = ints.next_timer_event(now, refresh=False)
        if t is not None and now < t and (best is None or t < best):
            best = t
        self._limit = best
        self._limit_ok = self.event_cache
        return best

    def next_event_in(self) -> float | None:
        """Seconds until the next internal event (engine, heartbeat, program, world), or None."""
        self._limit_ok = False  # between `advance` calls: no cache (host commands came)
        try:
            nxt = self._next_event(self.now + 2**62)
        finally:
            self._limit_ok = False
        return None if nxt == self.now + 2**62 else (nxt - self.now) / CLOCK_HZ

    def _heartbeat_deadline(self) -> int | None:
        """Earliest expiry of the serial (GP68) and CAN (GP82) heartbeats, in ticks."""
        if self._heartbeat_fired:
            return None
        ram = self.globals.ram
        if not (ram.get(_SERIAL_HB) or ram.get(_CAN_HB)):  # both off: the usual case
            return None
        best = None
        for iface, key in _HEARTBEATS:
            ms = ram.get(key, 0)
            if ms:
                t = self._last_command[iface] + ms * TICKS_PER_MS
                if best is None or t < best:
                    best = t
        return best

    def _after_step(self) -> None:
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

    def program_control(self, command: int, type: int, value: int) -> StatusReply | bytes:
        return program_control(self, command, type, value)

    def store_instruction(self, command: int, type: int, motor: int, value: int) -> StatusReply:
        return store_instruction(self, command, type, motor, value)

    def erase_program(self) -> None:
        """GP81 protection off erases the program; a running program is reset first (131), as
        it has nothing left to run (docs/assumptions.md)."""
        self.interpreter.reset()
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


__all__ = ["VirtualModule"]
