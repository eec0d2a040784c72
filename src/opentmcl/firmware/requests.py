"""The request path's pre-bound handlers (docs/architecture.md "Request path").

A read that succeeded once on the general path is answered next time by one handler bound to its
axis, bank or port: the read of the command table's "read" commands (GAP, GGP, GIO: `Motor.reader`,
`GlobalParameters.reader`, `IOBanks.reader`, the same reads the general path makes) packed behind
the reply's fixed first four bytes (manual 3.2: reply address, module address, status, command;
value MSB first; checksum). Only pure reads are bound (the table's effect READ or NONE): a GAP of a
parameter the world computes, AP207 (the read clears it) and invalid requests keep taking the
general path. SAP and SGP to user variables are bound as setters: the next one with any value
calls the same setter the general path reaches.

The handlers are a cache of the scheduler's: anything that changes what they answer (an address,
the host address, GP255, a power-up; Effect.REQUESTS) drops them.
"""
from __future__ import annotations

import struct
from collections.abc import Callable
from functools import partial
from typing import TYPE_CHECKING

from ..protocol.frame import Reply, to_int32
from ..protocol.opcodes import Op
from .effects import Effect
from .status import TmclStatus
from .table import TABLE, available

if TYPE_CHECKING:
    from .vm import VirtualModule

Entry = Callable[..., "Reply | bytes"]
"""A pre-bound read: ``entry(heartbeat="serial", as_reply=False)``, its reply as bytes or
(`as_reply`) as a `Reply` (`_entry`)."""
Setter = Callable[[int], None]
Read = Callable[[], int]
SAP, GAP, SGP, GGP, AGP = int(Op.SAP), int(Op.GAP), int(Op.SGP), int(Op.GGP), int(Op.AGP)
OK = 100
USER_BANK = 2
MAX_BOUND = 4096  # pre-bound frames kept at most (each differs in address, type, motor or value)
_TAIL = struct.Struct(">4siB")
_PURE = Effect.READ
_new_tuple = tuple.__new__  # `_new_tuple(Reply, fields)`: a Reply without the NamedTuple's Python __new__


def reply_bytes(host: int, module: int, status: int, command: int, value: int) -> bytes:
    """The 9-byte reply (manual 3.2); the checksum is summed arithmetically: the four value
    bytes of a 32-bit `value` are congruent to value + value>>8 + value>>16 + value>>24 mod 256."""
    if not -0x8000_0000 <= value <= 0x7FFF_FFFF:
        value = to_int32(value)
    head = bytes((host & 0xFF, module & 0xFF, status, command))
    return _TAIL.pack(head, value, (sum(head) + value + (value >> 8) + (value >> 16) + (value >> 24)) & 0xFF)


def _entry(vm: VirtualModule, head: bytes, read: Read) -> Entry:
    """The pre-bound handler of one read. Called with the heartbeat of the request's link
    (`heartbeat.OF_INTERFACE`), it restarts that heartbeat (as `Heartbeats.touch`), brings the
    engines to now for a pure read (`Scheduler.sync_for_read`) and answers `read()` behind the
    fixed first four reply bytes; with `as_reply` as the `Reply` of the same fields (nothing
    packed), the same object again while the value stays the same (a Reply is immutable)."""
    sched, heartbeats = vm.scheduler, vm.heartbeats
    ticks = heartbeats.last
    head_sum, pack = sum(head), _TAIL.pack
    reply = _new_tuple(Reply, (*head, 0))

    def entry(heartbeat: str = "serial", as_reply: bool = False) -> Reply | bytes:
        nonlocal reply
        now = sched.now
        ticks[heartbeat] = now  # restart the heartbeat
        heartbeats.fired = False
        if sched.synced_at != now:
            sched.sync_for_read()
        v = read()
        if as_reply:
            if v != reply[4]:
                if v.__class__ is not int or not -0x8000_0000 <= v <= 0x7FFF_FFFF:
                    v = to_int32(v)  # as on the wire: a flag (bool) as 1 or 0, 32 bits
                reply = _new_tuple(Reply, reply[:4] + (v,))
            return reply
        if not -0x8000_0000 <= v <= 0x7FFF_FFFF:
            v = to_int32(v)
        return pack(head, v, (head_sum + v + (v >> 8) + (v >> 16) + (v >> 24)) & 0xFF)
    return entry


def reader(vm: VirtualModule, command: int, type_: int, motor: int) -> Read | None:
    """The bound read of GAP `type_, motor`, GGP `type_, bank` or GIO `port, bank` when it is a pure
    read the module answers (the command table's effect), else None."""
    spec = available(vm, command)
    if spec is None or spec.binds != "read" or spec.effect_of(type_, motor) & ~_PURE:
        return None
    try:
        if command == GAP:
            if not 0 <= motor < len(vm.axes):
                return None
            return vm.axes[motor].reader(type_)
        if command == GGP:
            if motor not in vm.profile.global_banks:
                return None
            return vm.globals.reader(motor, type_)
        return vm.io.reader(type_, motor)
    except TmclStatus:
        return None


def handler(vm: VirtualModule, command: int, type_: int, motor: int) -> Entry | None:
    """The pre-bound handler of one read request (its whole reply), or None when it takes the
    general path."""
    read = reader(vm, command, type_, motor)
    if read is None:
        return None
    return _entry(vm, bytes((vm.host_address & 0xFF, vm.address & 0xFF, OK, command)), read)


def store(vm: VirtualModule, type_: int, bank: int) -> Setter | None:
    """A program's AGP to a user variable (bank 2, manual 3.6.35: the accumulator is copied there);
    None where the general path must answer (another bank, an index the module lacks)."""
    if available(vm, AGP) is None or bank != USER_BANK or bank not in vm.profile.global_banks \
            or not 0 <= type_ < len(vm.user_vars):
        return None
    return partial(vm.user_vars.__setitem__, type_)


class RequestPath:
    """The pre-bound handlers of one module."""

    def __init__(self, vm: VirtualModule) -> None:
        self.vm = vm
        self.reads: dict[bytes, Entry] = {}
        """Whole 9-byte frames -> handler (one lookup checks address, command, type, motor, checksum)."""
        self.writes: dict[bytes, Setter] = {}
        """First four bytes of a SAP or SGP (bank 2) -> its setter."""
        self._shapes: dict[bytes, Entry | None] = {}  # first four bytes -> handler, shared by values
        vm.scheduler.register("pre-bound requests", Effect.REQUESTS, self.forget)

    def forget(self) -> None:
        self.reads.clear()
        self.writes.clear()
        self._shapes.clear()

    def bind(self, frame: bytes, command: int, type_: int, motor: int) -> None:
        """Keep the handler of a read (keyed by the frame) or of a SAP/SGP (keyed by its first four
        bytes) that has just succeeded on the general path."""
        binds = TABLE[command].binds
        if binds == "read":
            shape = bytes(frame[:4])  # frames differing in the value field share one handler
            fast = self._shapes.get(shape) or self._shapes.setdefault(shape, handler(self.vm, command, type_, motor))
            if fast is not None:
                if len(self.reads) >= MAX_BOUND:  # a host varying the ignored value field
                    self.reads.clear()
                self.reads[bytes(frame)] = fast
        elif binds == "write":
            write = self._setter(command, type_, motor)
            if write is not None:
                self.writes[bytes(frame[:4])] = write

    def _setter(self, command: int, type_: int, motor: int) -> Setter | None:
        """The same setter the general path reaches (`Motor.set`, `GlobalParameters.set`, which
        check the value and raise the status), bound to its axis or bank."""
        vm = self.vm
        if available(vm, command) is None:
            return None
        if command == SAP and 0 <= motor < len(vm.axes):
            return partial(vm.axes[motor].set, type_)
        if command == SGP and motor == USER_BANK:  # other banks drop the handlers anyway
            return partial(vm.globals.set, motor, type_)
        return None

    def __getstate__(self) -> dict[str, object]:
        """A copy (copy.deepcopy, pickle) binds its own handlers: these are bound to this module."""
        return {**self.__dict__, "reads": {}, "writes": {}, "_shapes": {}}

    def is_prebound(self, frame: bytes) -> bool:
        """Whether `frame` is answered by a pre-bound handler (tests, benchmarks)."""
        return bytes(frame) in self.reads or bytes(frame[:4]) in self.writes
