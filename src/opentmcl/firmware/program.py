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
    from .commands import StatusReply
    from .vm import VirtualModule

STOPPED, RUNNING, STEPPING, RESET = 0, 1, 2, 3
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


def program_control(vm: VirtualModule, command: int, type: int, value: int) -> StatusReply | bytes:
    """Commands 128-135."""
    mem = vm.program
    if command == 128:
        vm.interpreter.stop()
    elif command == 129:
        if type == 1:
            if not 0 <= value < mem.size:
                raise TmclStatus(4)
            vm.interpreter.run(value)
        elif type == 0:
            vm.interpreter.run(None)
        else:
            raise TmclStatus(3)
    elif command == 130:
        vm.interpreter.step()
    elif command == 131:
        vm.interpreter.reset()
    elif command == 132:
        if mem.protection in (2, 3):
            raise TmclStatus(4)
        if not 0 <= value < mem.size:
            raise TmclStatus(4)
        vm.interpreter.stop()
        vm.download_mode = True
        vm.download_pointer = value
        vm.eeprom.deferred = True
    elif command == 133:
        if vm.download_mode:
            vm.download_mode = False
            vm.eeprom.deferred = False
            mem.save()
    elif command == 134:
        if mem.protection in (1, 3):
            raise TmclStatus(4)
        if not 0 <= value < mem.size:
            raise TmclStatus(4)
        return read_reply(vm, mem.code[value])
    elif command == 135:
        return int(Status.OK), vm.interpreter.status(type)
    return int(Status.OK), 0


def read_reply(vm: VirtualModule, ins: tuple[int, int, int, int]) -> bytes:
    """Special reply of 134: host address, then the stored instruction's command,
    type, motor and value in place of module address, status, command and value."""
    return MemoryReply(vm.host_address, *ins).encode()
