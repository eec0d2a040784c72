"""A heartbeat that is already up when a program sets it stops the motors at the next event, also
when pure instructions follow (the run-ahead must not skip that event), and leaves no event behind.

TMCM-6212 manual 5.1 (Bank 0), global parameter 68: "Serial heartbeat for RS485 interface and USB interface. If
this time limit is up and no further command is received by the module the motor will be stopped."
The module checks its heartbeats at every event tick (docs/architecture.md "Time"); a program's
instruction is one event per slot of INSTRUCTION_TICKS (manual 3.6: about 10000 instructions per
second). Here the host talks on CAN only, so the serial heartbeat has been up since power-up the
moment the program writes GP68 = 5 ms: the motors stop at the program's next instruction slot.
"""
from __future__ import annotations

import pytest

from opentmcl.firmware.interpreter import INSTRUCTION_TICKS
from opentmcl.firmware.vm import VirtualModule
from opentmcl.lang.assembler import assemble
from opentmcl.protocol.frame import Request

from .test_program_support import Wire

SGP, GGP, CALC, WAIT, STOP, ROR, GAP = 9, 10, 19, 27, 28, 1, 6
PURE_TAILS = {
    "CALC ADD": (CALC, 0, 0, 1),   # pure before issue 16 too
    "GGP 66, 0": (GGP, 66, 0, 0),  # runs ahead since issue 16 (a GGP of plain RAM)
    "GGP 7, 3": (GGP, 7, 3, 0),    # a GGP the module refuses (status 3, program goes on)
}


def _send(vm: VirtualModule, command: int, type_: int = 0, motor: int = 0, value: int = 0) -> bytes:
    return vm.handle(Request(1, command, type_, motor, value).encode(), interface="can")


def _rotating() -> VirtualModule:
    vm = VirtualModule("TMCM-6212")
    _send(vm, ROR, 0, 0, 51200)
    vm.advance(0.5)  # at full speed; no serial command since power-up
    return vm


@pytest.mark.parametrize("tail", sorted(PURE_TAILS))
def test_heartbeat_up_at_sgp68_stops_at_next_instruction(tail: str) -> None:
    vm = _rotating()
    _send(vm, 132)  # download mode (3.6.36)
    _send(vm, SGP, 68, 0, 5)
    for _ in range(10):
        _send(vm, *PURE_TAILS[tail])
    _send(vm, WAIT, 0, 0, 100)
    _send(vm, STOP)
    _send(vm, 133)
    _send(vm, 129, 1, 0, 0)  # run from address 0
    start = vm.now
    vm.advance(0.1)
    # the reference: the same motion without a program, read at the slot after SGP 68's
    ref = _rotating()
    ref.advance_to(start + 2 * INSTRUCTION_TICKS)
    expected = ref.request(GAP, 1, 0).value
    assert vm.request(GAP, 3, 0).value == 0  # stopped
    assert vm.request(GAP, 1, 0).value == expected


def test_heartbeat_set_in_time_still_runs_ahead() -> None:
    """The last valid case: GP68 set while the heartbeat is not yet up (a serial command just
    came): the motor keeps turning through the pure instructions."""
    vm = _rotating()
    _send(vm, 132)
    _send(vm, SGP, 68, 0, 500)
    for _ in range(10):
        _send(vm, CALC, 0, 0, 1)
    _send(vm, STOP)
    _send(vm, 133)
    vm.handle(Request(1, 129, 1, 0, 0).encode(), interface="serial")  # restarts the serial heartbeat
    vm.advance(0.01)
    assert vm.request(GAP, 3, 0).value > 0  # still turning


def test_can_heartbeat_gp82_up_at_sgp_stops_at_next_instruction() -> None:
    """The same for the CAN heartbeat GP82 (manual 5.1: "Heartbeat for CAN interface. If this time
    limit is up and no further command is received the motor will be stopped") with a host on the
    serial link only."""
    def serial(vm: VirtualModule, *fields: int) -> bytes:
        return vm.handle(Request(1, *fields).encode(), interface="serial")

    def rotating() -> VirtualModule:
        vm = VirtualModule("TMCM-6212")
        serial(vm, ROR, 0, 0, 51200)
        vm.advance(0.5)
        return vm

    vm = rotating()
    serial(vm, 132, 0, 0, 0)
    serial(vm, SGP, 82, 0, 5)
    for _ in range(10):
        serial(vm, GGP, 66, 0, 0)
    serial(vm, STOP, 0, 0, 0)
    serial(vm, 133, 0, 0, 0)
    serial(vm, 129, 1, 0, 0)
    start = vm.now
    vm.advance(0.1)
    ref = rotating()
    ref.advance_to(start + 2 * INSTRUCTION_TICKS)
    assert vm.request(GAP, 3, 0).value == 0
    assert vm.request(GAP, 1, 0).value == ref.request(GAP, 1, 0).value


def test_after_a_heartbeat_stop_and_stop_no_event_is_left():
    """TMCM-6212 5.1 GP68 "If this time limit is up and no further command is received by the
    module the motor will be stopped"; `VirtualModule.next_event_in()` "Seconds until the next
    internal event (engine, heartbeat, program, world), or None". A 1 ms heartbeat expires at the
    tick of the program's 10th instruction (one instruction per 100 us, docs/assumptions.md
    "Instruction rate"), a CALC; the 11th is STOP. Afterwards the motor stands, the program has
    stopped and the heartbeat has fired: nothing is left to happen."""
    vm = VirtualModule("TMCM-6212", address=1)
    w = Wire(vm)
    w.download(assemble("CALC ADD, 1\n" * 10 + "STOP\n", module="TMCM-6212").instructions)
    w.ok(9, 68, 0, 1)
    w.ok(4, 0, 0, 10_000_000)   # a long move: its ramp has events far ahead
    w.run()
    vm.advance(0.002)
    assert vm.next_event_in() is None
    assert (w.ok(6, 3, 0), w.state, w.a) == (0, 0, 10)
