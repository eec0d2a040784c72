"""TMCL program memory and the control commands 128-135 (TMCM-6212 manual 3.6.36).

Instructions are stored as (command, type, motor, value). Download mode
(132 <start>) stores every following non-control command at the download
pointer and answers status 101; 133 leaves it and writes the program to the
EEPROM in one go. GP81 code protection: 1/3 forbid reading back (134),
2/3 forbid overwriting (132).
"""
from __future__ import annotations

from typing import TYPE_CHECKING

from ..protocol.frame import to_int32
from ..protocol.replies import MemoryReply
from ..protocol.status import Status
from .status import TmclStatus

if TYPE_CHECKING:
    from .commands import Result, StatusReply
    from .vm import VirtualModule

STOPPED, RUNNING, STEPPING, RESET = 0, 1, 2, 3
_OK = int(Status.OK)
WRITE_PROTECTED, READ_PROTECTED = (2, 3), (1, 3)
"""GP81 code protection: 2 and 3 forbid overwriting (132), 1 and 3 reading back (134)."""
EMPTY = (0, 0, 0, 0)


class ProgramMemory:
    def __init__(self, vm: VirtualModule) -> None:
        self.vm = vm
        self.size = vm.profile.program_memory
        self.code: list[tuple[int, int, int, int]] = [EMPTY] * self.size
        for addr, (command, type, motor, value) in enumerate(vm.eeprom.program[: self.size]):
            self.code[addr] = (command, type, motor, value)
        self.length = len(vm.eeprom.program)

    @property
    def protection(self) -> int:
        return self.vm.globals.get_raw(0, 81)

    def check(self, address: int, protected: tuple[int, ...] = ()) -> None:
        """Status 4 unless `address` lies in the program memory and GP81 (code protection) is
        none of `protected`."""
        if protected and self.protection in protected or not 0 <= address < self.size:
            raise TmclStatus(4)

    def store(self, address: int, ins: tuple[int, int, int, int]) -> None:
        self.code[address] = ins
        self.length = max(self.length, address + 1)

    def save(self) -> None:
        self.vm.eeprom.set_program([list(ins) for ins in self.code[: self.length]])

    def erase(self) -> None:
        self.code = [EMPTY] * self.size
        self.length = 0
        self.save()


def store_instruction(vm: VirtualModule, command: int, type: int, motor: int, value: int) -> StatusReply:
    mem = vm.program
    if vm.download_pointer >= mem.size:
        raise TmclStatus(4)
    mem.store(vm.download_pointer, (command, type & 0xFF, motor & 0xFF, to_int32(value)))
    vm.download_pointer += 1
    return int(Status.LOADED), 0


# --- the control commands 128-135 (3.6.36), each a handler of the command table ----------------
def stop_application(vm: VirtualModule, type: int, motor: int, value: int, program: bool) -> Result:
    """128: stop the running program."""
    vm.interpreter.stop()
    return _OK, 0


def run_application(vm: VirtualModule, type: int, motor: int, value: int, program: bool) -> Result:
    """129: type 0 from the current address, type 1 from the address in the value."""
    if type == 1:
        vm.program.check(value)
        vm.interpreter.run(value)
    elif type == 0:
        vm.interpreter.run(None)
    else:
        raise TmclStatus(3)
    return _OK, 0


def step_application(vm: VirtualModule, type: int, motor: int, value: int, program: bool) -> Result:
    """130: execute one instruction."""
    vm.interpreter.step()
    return _OK, 0


def reset_application(vm: VirtualModule, type: int, motor: int, value: int, program: bool) -> Result:
    """131: stop and set the program counter to 0."""
    vm.interpreter.reset()
    return _OK, 0


def enter_download_mode(vm: VirtualModule, type: int, motor: int, value: int, program: bool) -> Result:
    """132: store the following commands from the address in the value (not with GP81 = 2 or 3)."""
    vm.program.check(value, WRITE_PROTECTED)
    vm.interpreter.stop()
    vm.download_mode = True
    vm.download_pointer = value
    vm.eeprom.deferred = True
    return _OK, 0


def exit_download_mode(vm: VirtualModule, type: int, motor: int, value: int, program: bool) -> Result:
    """133: leave download mode and write the program to the EEPROM in one go."""
    if vm.download_mode:
        vm.download_mode = False
        vm.eeprom.deferred = False
        vm.program.save()
    return _OK, 0


def read_program_memory(vm: VirtualModule, type: int, motor: int, value: int, program: bool) -> Result:
    """134: the instruction at the address in the value (not with GP81 = 1 or 3)."""
    vm.program.check(value, READ_PROTECTED)
    return read_reply(vm, vm.program.code[value])


def get_application_status(vm: VirtualModule, type: int, motor: int, value: int, program: bool) -> Result:
    """135: the program's state, or with type 1 its program counter."""
    return _OK, vm.interpreter.status(type)


def read_reply(vm: VirtualModule, ins: tuple[int, int, int, int]) -> bytes:
    """Special reply of 134: host address, then the stored instruction's command,
    type, motor and value in place of module address, status, command and value."""
    return MemoryReply(vm.host_address, *ins).encode()
