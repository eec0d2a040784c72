"""One rule for the status of an opcode, checked on every opcode 0..255 of every module.

TMCM-6212 3.2.1 Table 4 (same table in PD86-1180 4.2 and PD28-1021 3.2): "2 Invalid command",
"6 Command not available". Reading (docs/assumptions.md, "Status 2 and 6"): a number that is not
in the module's own command set is an invalid command for that module (2), whether or not
another module knows it; 6 is a command the module has that cannot run in the present context -
a control command (128 and up, direct mode only, 3.6.36) met by a running program.
"""
from __future__ import annotations

import pytest

from opentmcl import VirtualModule
from opentmcl.modules.profile import load_profile
from opentmcl.protocol.frame import Request

MODULES = ["TMCM-6212", "PD86-1180", "PD28-1021"]


def _reply(vm: VirtualModule, command: int, type_: int = 0) -> bytes:
    return vm.handle(Request(1, command, type_, 0, 0).encode())


@pytest.mark.parametrize("name", MODULES)
def test_every_opcode_0_to_255_follows_one_rule(name):
    """Table 4 "2 Invalid command" for every number 0..255 the module's command table lacks,
    including commands of the other two manuals (TMCM-6212 has no STAP 7, RSAP 8 or 139; the
    PD86-1180 none of the PD28-1021's extended set 40..57 and 80). The commands it has are
    executed in direct mode and answer neither 2 nor 6 (136 is asked for its binary form, type 1,
    whose reply has a status byte; 137 without 1234 answers 4)."""
    opcodes = load_profile(name).opcodes
    statuses = {}
    for op in range(256):
        vm = VirtualModule(name, address=1)   # 132 enters download mode: one module per opcode
        statuses[op] = _reply(vm, op, 1 if op == 136 else 0)[2]
    assert {op: s for op, s in statuses.items() if op not in opcodes} == dict.fromkeys(set(range(256)) - opcodes, 2)
    assert not {op: s for op, s in statuses.items() if op in opcodes and s in (2, 6)}


@pytest.mark.parametrize(("name", "lacking"), [("TMCM-6212", 7), ("TMCM-6212", 139), ("PD86-1180", 40),
                                               ("PD86-1180", 80), ("PD28-1021", 47)])
def test_in_a_program_lacking_opcode_is_2_control_command_is_6(name, lacking):
    """The same rule in a program: an instruction the module lacks is skipped with status 2; a
    control command (3.6.36: for direct mode; 138 every module has) with "6 Command not
    available"."""
    vm = VirtualModule(name, address=1)
    for addr, ins in enumerate([(lacking, 0, 0, 0), (28, 0, 0, 0), (138, 0, 0, 1), (28, 0, 0, 0)]):
        vm.program.store(addr, ins)
    vm.request(129)
    vm.advance(0.01)
    assert vm.interpreter.last_error == (0, lacking, 2)
    vm.request(129, 1, 0, 2)
    vm.advance(0.01)
    assert vm.interpreter.last_error == (2, 138, 6)


def test_an_unknown_command_is_status_2_with_value_0():
    """TMCM-6212 3.2.1 Table 4 "2 Invalid command": a command number the module does not have (99)
    is answered with status 2 and, as every error reply (docs/assumptions.md), value 0."""
    vm = VirtualModule("TMCM-6212", address=1)
    reply = vm.request(99, 0, 0, 1234)
    assert (reply.status, reply.command, reply.value) == (2, 99, 0)
