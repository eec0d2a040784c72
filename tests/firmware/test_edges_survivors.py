"""Edges found unpinned by the seeded mutation sample of the firmware layer (docs/mutation.md,
`python bench/mutation.py --layer firmware --sample 150 --seed 12`): user variable 0 in the
extended calculations, the statuses of a failing CALCVV / CSUB, stepping with an armed timer, DI
dropping a pending interrupt, GIO 255 on the analog bank, the erased program after a restart and
the assigned address after a reset."""
from __future__ import annotations

import pytest

from opentmcl import VirtualModule
from opentmcl.firmware.eeprom import EepromError
from opentmcl.firmware.interpreter import INSTRUCTION_TICKS
from opentmcl.motion import CLOCK_HZ

from .conftest import Host
from .test_program_support import T, Wire, module

STOP = (28, 0, 0, 0)


def _run_raw(name: str, *instructions: tuple[int, int, int, int], seconds: float = 20 * T) -> Wire:
    """Download `instructions` as they are (no assembler checks), run them, advance `seconds`."""
    w = module(name)
    w.download(instructions)
    w.run()
    w.vm.advance(seconds)
    return w


def test_calcv_takes_user_variable_0_and_the_last_one():
    """PD28-1021 manual Table 5: "CALCV 45 <operation>, <value> Arithmetical operation between user
    variable and direct value": variable 0 is the first user variable (TMCM-6212 3.6.9 bank 2
    "0...255"), so CALCV ADD on it adds, and on the last one (255, the largest the motor byte holds)
    too."""
    w = module("PD28-1021")
    last = len(w.vm.user_vars) - 1
    w.ok(9, 0, 2, 10)
    w.ok(9, last, 2, 20)
    assert last == 255
    w.download([(45, 0, 0, 5), (45, 0, last, 7), STOP])
    w.run()
    w.vm.advance(20 * T)
    assert (w.var(0), w.var(last)) == (15, 27)
    assert w.vm.interpreter.last_error is None


def test_calcvv_with_an_operation_beyond_swap_is_status_3():
    """PD28-1021 manual Table 5: "CALCVV <operation>, <user variable 1>, <user variable 2>" with the
    operations of CALC (0 ADD ... 9 LOAD, TMCM-6212 3.6.14) and SWAP (10, "CALCVV SWAP"): operation
    11 is none of them - TMCM-6212 3.2.1 Table 4 "3 Wrong type" - and variable 1 keeps its value."""
    w = _run_raw("PD28-1021", (9, 1, 2, 6), (40, 11, 1, 2), STOP)
    assert w.vm.interpreter.last_error == (1, 40, 3)
    assert w.var(1) == 6


def test_csub_beyond_program_memory_is_status_4_and_the_last_address_is_called():
    """TMCM-6212 3.6.18 CSUB "<subroutine address>": an address outside the program memory is an
    invalid value (3.2.1 Table 4 "4 Invalid value"; the call is ignored), while the last address
    of the memory is called (the PC moves there and runs into the empty memory cell:
    status 2, invalid command)."""
    size = VirtualModule("TMCM-6212").program.size
    w = _run_raw("TMCM-6212", (23, 0, 0, size), STOP, seconds=10 * T)
    assert w.vm.interpreter.last_error == (0, 23, 4)
    assert w.pc == 1
    w = _run_raw("TMCM-6212", (23, 0, 0, size - 1), seconds=3 * T)
    assert w.vm.interpreter.last_error == (size - 1, 0, 2)


def test_step_with_an_armed_timer_executes_the_next_command():
    """TMCM-6212 3.7 "130 - step application: execute only the next TMCL command": with timer 0
    running (SGP 0, 3, 100 - a period of 100 ms, 3.5.6.4) but no interrupt enabled, one step moves
    the PC by one and the timer does not disturb it."""
    w = module()
    w.download([(9, 0, 2, 1), (9, 0, 2, 2), STOP])
    w.ok(9, 0, 3, 100)
    w.vm.advance(0.25)
    assert w(130).status == 100
    assert (w.pc, w.var(0)) == (1, 1)


def test_di_drops_the_pending_occurrence_of_its_interrupt():
    """TMCM-6212 3.6.31 "DI <interrupt number>" disables an interrupt; docs/assumptions.md
    (Interrupts): "DI n drops n's pending occurrence": interrupt 21 occurring during the handler of
    15 is pending (3.5.6.2 "There is no interrupt nesting"); the handler's DI 21 drops it, so the
    EI 21 after it does not bring it back and handler 21 never runs."""
    src = ("VECT 15, Stall\nVECT 21, Dev\nEI 15\nEI 21\nEI 255\nIdle: JA Idle\n"
           "Stall: GGP 10, 2\n CALC ADD, 1\n AGP 10, 2\n WAIT TICKS, 0, 1\n DI 21\n EI 21\n RETI\n"
           "Dev: GGP 10, 2\n CALC ADD, 10\n AGP 10, 2\n RETI\n")
    w = module()
    w.load(src)
    w.run()
    w.vm.advance(20 * T)
    assert w.vm.interrupts.trigger(15)
    w.vm.advance(0.005)                       # inside handler 15 (its WAIT)
    assert w.vm.interrupts.active == 15
    assert w.vm.interrupts.trigger(21)        # latched, pending until RETI
    w.vm.advance(0.1)
    assert w.var(10) == 1 and w.vm.interrupts.active is None


def test_gio_255_reads_the_digital_bank_but_not_the_analog_one(m6212):
    """TMCM-6212 3.6.13: "Digital lines will read as 0 or 1, while the ADC channels deliver their 16
    bit result"; docs/assumptions.md: "`GIO 255, 0` returns IN0..IN3 as bits 0..3" and "`GIO 255, 1`
    (analog) is not defined: status 3"."""
    m6212.vm.io.drive_input(0, 2, 1)
    assert m6212.ok(15, 255, 0) == 0b0100
    assert m6212(15, 255, 1).status == 3


def test_a_program_erased_by_gp81_stays_erased_after_power_up(tmp_path):
    """TMCM-6212 5.1 GP81 "TMCL code protection" (switching the protection against disassembling
    off erases the program) and GP77 "auto start mode ... 1 - start TMCL application after power
    up": after the erase the EEPROM holds no program, so the next power-up starts nothing."""
    ee = tmp_path / "ee.json"
    w = Wire(VirtualModule("TMCM-6212", address=1, eeprom=ee))
    w.download([(9, 0, 2, 7), STOP])
    w.ok(9, 77, 0, 1)
    w.ok(9, 81, 0, 1)
    w.ok(9, 81, 0, 0)                         # protection off: the program is erased
    again = Wire(VirtualModule("TMCM-6212", address=1, eeprom=ee))
    again.vm.advance(0.1)
    assert again.state == 0 and again.var(0) == 0


def test_the_assigned_address_is_kept_across_a_restart():
    """`VirtualModule.assign_address`: "GP66 in RAM, kept across resets" (TMCM-6212 5.1 GP66 "Serial
    address"): after 137 (restore factory defaults, then a restart) the module still answers at
    the address it was given, not at the default 1."""
    vm = VirtualModule("TMCM-6212")
    vm.assign_address(9)
    assert vm.request(137, 0, 0, 1234) is None   # no reply: the module restarts
    assert vm.address == 9 and Wire(vm, address=9).ok(10, 66, 0) == 9


def test_wait_ticks_ends_exactly_one_tick_after_it_began():
    """TMCM-6212 3.6.20 WAIT: "the TMCL program counter is set held at the address of this WAIT
    command until the condition is met or the timeout has expired", "one tick is 10 milliseconds":
    WAIT TICKS, 0, 1 still waits (135 wait flag, bit 16) 1/16 MHz before the 10 ms are up and no
    longer waits when they are (the WAIT, the first instruction, begins after one instruction time,
    100 us - docs/assumptions.md)."""
    w = module()
    w.download([(27, 0, 0, 1), (9, 0, 2, 1), STOP])
    w.run()
    w.vm.advance(0.001)
    begun = INSTRUCTION_TICKS
    assert w.ok(135, 0) >> 16 & 1
    w.vm.advance_to(begun + CLOCK_HZ // 100 - 1)
    assert w.ok(135, 0) >> 16 & 1
    w.vm.advance_to(begun + CLOCK_HZ // 100)
    assert not w.ok(135, 0) >> 16 & 1


def test_request_defaults_type_motor_and_value_to_0():
    """`VirtualModule.request(command, type=0, motor=0, value=0)`: GAP with only the command asks
    type 0 - TMCM-6212 4.1 AP0 "Target (next) position" - of motor 0, not AP1 actual position."""
    vm = VirtualModule("TMCM-6212", address=1)
    assert vm.request(4, 0, 0, 1000).status == 100      # MVP ABS 1000: the target moves at once
    assert vm.request(6).value == 1000
    assert vm.request(6, 1).value == 0


def test_internal_units_bound_only_velocity_and_acceleration():
    """TMCM-6212 4.1 AP255 "Units of velocity and acceleration/deceleration settings: 0 - the internal
    units of the TMC5130 are used directly": only those parameters change their range; AP6 "Maximum
    current 0...255" keeps its own (255 accepted, 256 status 4 "Invalid value")."""
    host = Host(VirtualModule("TMCM-6212", address=1))
    host.ok(5, 255, 0, 0)
    assert (host(5, 6, 0, 255).status, host(5, 6, 0, 256).status) == (100, 4)


def test_an_eeprom_file_of_one_module_is_refused_by_another(tmp_path):
    """docs/assumptions.md "EEPROM images are checked when opened": the file a TMCM-6212 wrote (SGP 77,
    bank 0 64..127 "automatically stored in the EEPROM", TMCM-6212 5.1) names its module, so a
    PD86-1180 does not power up from it."""
    ee = tmp_path / "ee.json"
    Host(VirtualModule("TMCM-6212", address=1, eeprom=ee)).ok(9, 77, 0, 1)
    with pytest.raises(EepromError, match="belongs to a TMCM-6212"):
        VirtualModule("PD86-1180", eeprom=ee)
