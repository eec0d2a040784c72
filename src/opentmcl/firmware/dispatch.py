"""Pre-bound handlers of the hot read requests (docs/architecture.md, "Request path").

GAP, GGP and GIO of a valid (type, motor/bank) answer status 100 with a value and change nothing
that an engine's next event depends on (TMCM-6212 manual 3.6.6, 3.6.10, 3.6.13). For each such
request the module keeps one handler, keyed by the frame's first four bytes (address, command,
type, motor/bank): it reads the value and packs the reply (manual 3.2: reply address, module
address, status, command, value MSB first, checksum) without the general path's lookups.

`entry()` answers None for every request it does not cover (a wrong type, a motor the module
lacks, world-driven parameters, GAP 207 which clears flags, the GGPs whose values come from
elsewhere, GIO 255); those keep taking the general path (`commands.execute`). The world's axis
numbers are read when a handler is bound: code that changes them must call `vm.forget_requests()`.
"""
from __future__ import annotations

import struct
from collections.abc import Callable
from functools import partial
from operator import attrgetter
from typing import TYPE_CHECKING, cast

from ..protocol.frame import to_int32

if TYPE_CHECKING:
    from .vm import VirtualModule

Entry = Callable[[], bytes]
Setter = Callable[[int], None]
Read = Callable[[], int]
SAP, GAP, SGP, GGP, GIO, AGP = 5, 6, 9, 10, 15, 35
OK = 100
USER_BANK = 2
# GGP values that are not plain RAM: 73 lock, 128 status, 129 download mode, 130 PC, 132 tick, 133 random
_GLOBAL_SPECIAL = frozenset({73, 128, 129, 130, 132, 133})
_ENGINE_READS = {0: "target_position", 1: "position", 8: "position_reached",
                 135: "actual_acceleration", 138: "ramp_mode"}
_TAIL = struct.Struct(">4siB")


def reply_bytes(host: int, module: int, status: int, command: int, value: int) -> bytes:
    """The 9-byte reply (manual 3.2); the checksum is summed arithmetically: the four value
    bytes of a 32-bit `value` are congruent to value + value>>8 + value>>16 + value>>24 mod 256."""
    if not -0x8000_0000 <= value <= 0x7FFF_FFFF:
        value = to_int32(value)
    head = bytes((host & 0xFF, module & 0xFF, status, command))
    return _TAIL.pack(head, value, (sum(head) + value + (value >> 8) + (value >> 16) + (value >> 24)) & 0xFF)


def _packed(head: bytes, read: Read) -> Entry:
    """A handler answering `read()` behind the fixed first four reply bytes."""
    head_sum, pack = sum(head), _TAIL.pack

    def entry() -> bytes:
        v = read()
        if not -0x8000_0000 <= v <= 0x7FFF_FFFF:
            v = to_int32(v)
        return pack(head, v, (head_sum + v + (v >> 8) + (v >> 16) + (v >> 24)) & 0xFF)
    return entry


def _axis_read(vm: VirtualModule, number: int, motor: int) -> Read | None:
    if not 0 <= motor < len(vm.axes):
        return None  # status 4 (commands._axis)
    ax = vm.axes[motor]
    if number not in ax.readable or number in ax.world.axis_numbers or number == 207:
        return None  # status 3, the world's readings, AP207 (read clears it)
    e = ax.engine
    if number in (2, 3):  # velocities: the unit follows AP255 at every read (axis.py)
        name = "target_velocity" if number == 2 else "velocity"
        read_velocity = attrgetter(name)
        return lambda: ax.from_engine(number, read_velocity(e))
    attribute = _ENGINE_READS.get(number)
    if attribute is not None and (number < 135 or hasattr(e, attribute)):
        return partial(attrgetter(attribute), e)
    return cast("Read", partial(ax.ram.get, number, ax.params[number].default))


def _global_read(vm: VirtualModule, number: int, bank: int) -> Read | None:
    if bank == USER_BANK:
        if not 0 <= number < len(vm.user_vars):
            return None
        return partial(vm.user_vars.__getitem__, number)
    key = (bank, number)
    p = vm.globals.params.get(key)
    if p is None or not p.readable or (bank == 0 and number in _GLOBAL_SPECIAL):
        return None
    return partial(vm.globals.ram.__getitem__, key)


def _io_read(vm: VirtualModule, port: int, bank: int) -> Read | None:
    key = (bank, port)
    if port == 255 or key not in vm.io.ports:
        return None
    return partial(vm.io.read, key)


_READERS = {GAP: _axis_read, GGP: _global_read, GIO: _io_read}


def entry(vm: VirtualModule, command: int, type_: int, motor: int) -> Entry | None:
    """The pre-bound handler of one read request, or None when it takes the general path."""
    make = _READERS.get(command)
    if make is None or command not in vm.opcodes:
        return None
    read = make(vm, type_, motor)
    if read is None:
        return None
    head = bytes((vm.host_address & 0xFF, vm.address & 0xFF, OK, command))
    return _packed(head, read)


def program_read(vm: VirtualModule, command: int, type_: int, motor: int) -> Read | None:
    """A program's GAP, GGP or GIO (TMCM-6212 manual 3.5.5: the value goes to the accumulator)
    read without `commands.execute`'s look-ups: the same read a host's pre-bound handler makes,
    None where `execute` must answer. The caller syncs the engines first (`sync_for_read`)."""
    make = _READERS.get(command)
    if make is None or command not in vm.opcodes:
        return None
    return make(vm, type_, motor)


def program_store(vm: VirtualModule, type_: int, bank: int) -> Setter | None:
    """A program's AGP to a user variable (bank 2, manual 3.6.35: the accumulator is copied there)
    without `commands.execute`'s look-ups; None where `execute` must answer (another bank, an
    index the module lacks)."""
    if AGP not in vm.opcodes or bank != USER_BANK or bank not in vm.profile.global_banks \
            or not 0 <= type_ < len(vm.user_vars):
        return None
    return partial(vm.user_vars.__setitem__, type_)


def setter(vm: VirtualModule, command: int, type_: int, motor: int) -> Setter | None:
    """The pre-bound write of a SAP or SGP: the same setter `execute` reaches (`Axis.set`,
    `GlobalParameters.set`, which check the value and raise the status), bound to its axis or bank."""
    if command not in vm.opcodes:
        return None
    if command == SAP and 0 <= motor < len(vm.axes):
        return partial(vm.axes[motor].set, type_)
    if command == SGP and motor == USER_BANK:  # other banks: each SGP drops the tables anyway
        return partial(vm.globals.set, motor, type_)
    return None
