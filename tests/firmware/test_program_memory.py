"""Program memory and the TMCL control commands 128-135 (TMCM-6212 manual 3.6.36 Table 13,
PD86-1180 manual 4.6.39), global parameters 77, 81, 128-130 (TMCM-6212 manual 5.1)."""
from __future__ import annotations

import pytest

from opentmcl import VirtualModule
from opentmcl.protocol.frame import Reply, Request, checksum

from .test_program_support import STOP, T, Wire, module

STATUS_LOADED = 101


@pytest.fixture(params=["TMCM-6212", "PD86-1180", "PD28-1021"])
def w(request):
    return module(request.param)


def test_download_mode_stores_and_does_not_execute(w):
    """3.6.36: 132 "All following commands (except control commands) are not executed but stored
    in the TMCL memory"; they are answered with status 101 (3.2.1 "Command loaded into TMCL
    program EEPROM"); GP129 reads 1 in download mode (a GGP sent then is stored too) and 0 after 133."""
    before = w.ok(6, 4, 0)
    w.ok(132, 0, 0, 0)
    has_gp129 = (0, 129) in w.vm.profile.global_parameters   # not among the PD28-1021's numbers
    assert not has_gp129 or w.vm.globals.get(0, 129) == 1
    assert w(10, 129, 0).status == STATUS_LOADED
    r = w(5, 4, 0, before + 7)
    assert r.status == STATUS_LOADED
    assert w(1, 0, 0, 1000).status == STATUS_LOADED  # ROR is stored, the motor stays still
    w.ok(133)
    assert not has_gp129 or w.ok(10, 129, 0) == 0
    assert w.ok(6, 4, 0) == before
    assert w.ok(6, 3, 0) == 0
    assert w.vm.program.code[:3] == [(10, 129, 0, 0), (5, 4, 0, before + 7), (1, 0, 0, 1000)]


def test_read_program_memory_special_reply(w):
    """3.6.36: 134 "Return contents of the specified program memory location (special reply
    format)": host address, then the stored command, type, motor/bank and value (MSB first) in
    place of module address, status, command and value, and a checksum (docs/assumptions.md)."""
    w.download([(4, 0, 0, -5000), (27, 1, 0, 0)], start=3)
    raw = w.vm.handle(Request(1, 134, 0, 0, 3).encode())
    assert raw[:8] == bytes([2, 4, 0, 0]) + (-5000).to_bytes(4, "big", signed=True)
    assert raw[8] == checksum(raw[:8])
    raw = w.vm.handle(Request(1, 134, 0, 0, 4).encode())
    assert raw[1:4] == bytes([27, 1, 0])


def test_program_size_limit(w):
    """1 Features / profile: the program memory holds a fixed number of commands (6144 on the
    TMCM-6212, 2048 on the PD86-1180 and PD28-1021); 132 beyond it and a command stored past the
    end are answered with status 4 (invalid value)."""
    size = w.vm.profile.program_memory
    assert size == {"TMCM-6212": 6144, "PD86-1180": 2048, "PD28-1021": 2048}[w.vm.profile.name]
    assert w(132, 0, 0, size).status == 4
    w.ok(132, 0, 0, size - 1)
    assert w(28).status == STATUS_LOADED
    assert w(28).status == 4
    w.ok(133)
    assert w(134, 0, 0, size).status == 4


def test_code_protection(w):
    """5.1 GP81: "1 - protection against disassembling, 2 - protection against overwriting ...
    When switching off the protection against disassembling (changing this parameter from 1 or 3
    to 0 or 2, the program will be erased first!"."""
    w.download([(22, 0, 0, 0)])
    w.ok(9, 81, 0, 1)
    assert w(134, 0, 0, 0).status != 100
    w.ok(132, 0, 0, 0)  # overwriting still allowed
    w.ok(133)
    w.ok(9, 81, 0, 3)
    assert w(132, 0, 0, 0).status != 100
    w.ok(9, 81, 0, 2)   # 3 -> 2 switches off the read protection: the program is erased
    assert w(132, 0, 0, 0).status != 100
    assert w.vm.program.code[0] == (0, 0, 0, 0)
    w.ok(9, 81, 0, 0)
    w.download([(22, 0, 0, 0)])
    raw = w.vm.handle(Request(1, 134, 0, 0, 0).encode())
    assert raw[1] == 22


def test_erasing_a_running_program_by_gp81_stops_it(w):
    """5.1 GP81: switching off the protection against disassembling "the program will be erased
    first!". A program running at that moment has nothing left to run: it is reset (GP128 = 3,
    PC 0, command 131's state, docs/assumptions.md) and the motor it was turning keeps the last
    command, as after a 128 stop. The loop below would otherwise run on (manual 3.6.17 JA)."""
    w.load("SGP 81, 0, 1\nLoop: CALC ADD, 1\nJA Loop")
    w.run()
    w.vm.advance(10 * T)
    assert w.state == 1 and w.ok(135, 2) > 0
    w.ok(9, 81, 0, 0)
    assert w.state == 3 and w.pc == 0
    w.vm.advance(10 * T)
    assert w.state == 3 and w.ok(135, 2) == 0
    assert w.vm.program.code[0] == (0, 0, 0, 0)


def test_application_status_and_gp128_130_mirror_the_state(w):
    """3.6.36 135 types 0-3 and 5.1 GP128 (0 stop, 1 run, 2 step, 3 reset), GP130 (program counter).
    Types 0/1 pack mode << 24 | wait flag << 16 | address (layout: docs/assumptions.md)."""
    w.load("CALC LOAD, 42\nCALCX LOAD\nCALC LOAD, 7\nWAIT TICKS, 0, 100\nSTOP")
    w.run()
    w.vm.advance(10 * T)
    assert w.state == 1 and w.pc == 3
    assert w.ok(135, 1) == (1 << 24) | (1 << 16) | 3
    assert w.ok(135, 2) == 7 and w.ok(135, 3) == 42
    w.ok(132, 0, 0, 17)
    assert w.ok(135, 0) & 0xFFFF == 17   # memory pointer = download address
    w.ok(133)
    assert w.state == 0
    assert w(135, 9).status == 3


def test_stop_run_from_address_step_reset(w):
    """3.6.36: 128 stops, 129 type 0 continues from the current address, type 1 starts at the
    given one, 130 executes only the next command, 131 resets PC, stack, A, X and flags."""
    w.load("Start: CALC ADD, 1\nJA Start\nOther: CALC LOAD, 1000\nSTOP")
    w.run()
    w.vm.advance(100 * T)
    w.ok(128)
    assert w.state == 0
    a = w.a
    assert a == 50
    w.vm.advance(1.0)
    assert w.a == a                     # stopped: nothing executes
    w.ok(130)
    assert w.state == 2 and w.pc in (0, 1)
    pc_before = w.pc
    w.ok(130)
    assert w.pc != pc_before
    w.run(2)
    w.vm.advance(5 * T)
    assert w.a == 1000 and w.state == 0 and w.pc == 3
    w.ok(131)
    assert (w.state, w.pc, w.a, w.x, w.vm.flags) == (3, 0, 0, 0, 0)
    w.run()                             # after a reset the program starts at 0
    w.vm.advance(2 * T)                 # CALC ADD at T, JA at 2T
    assert w.a == 1


def test_program_survives_restart_with_file_eeprom(tmp_path):
    """docs/architecture.md "Errors": the TMCL program lives in the (file-backed) EEPROM; 5.1 GP77 "1 - Start TMCL
    application automatically after power up"."""
    path = tmp_path / "eeprom.json"
    w = Wire(VirtualModule("TMCM-6212", address=1, eeprom=path))
    w.load("Loop: CALC ADD, 1\nAGP 0, 2\nJA Loop")
    w.ok(9, 77, 0, 1)
    w.vm.close()
    again = Wire(VirtualModule("TMCM-6212", address=1, eeprom=path))
    raw = again.vm.handle(Request(1, 134, 0, 0, 1).encode())
    assert raw[1:4] == bytes([35, 0, 2])
    assert again.state == 1             # auto start
    again.vm.advance(30 * T)
    assert again.var(0) == 10


def test_no_auto_start_by_default():
    """5.1 GP77: "0 - Do not start TMCL application after power up (default)"."""
    w = module()
    w.load("Loop: CALC ADD, 1\nJA Loop")
    w.vm.power_up()
    assert w.state == 0


def test_135_accepts_only_the_types_of_its_table(w):
    """3.6.36 Table 13, 135 "get application status": "0 - return mode, wait flag, memory pointer
    1 - return mode, wait flag, program counter 2 - return accumulator 3 - return X register":
    type 3 (the last one) answers 100, 4 and 255 are status 3 "Wrong type"."""
    got = {t: w.vm.request(135, t).status for t in (0, 1, 2, 3, 4, 255)}
    assert got == {0: 100, 1: 100, 2: 100, 3: 100, 4: 3, 255: 3}


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


def test_a_calculation_at_the_last_address_runs_and_then_the_program_stops():
    """TMCM-6212 1 Features: "program memory (non volatile) for up to 6144 TMCL commands", so the
    last address is 6143; docs/assumptions.md "Program memory end": the instruction at the last
    address runs and the program then stops. A pure one (CALC ADD, 3.6.14) there is run ahead of the motors' clock
    (docs/architecture.md "Time"), and the look-ahead must stop at the end of the memory too.
    3.6.36: 135 type 2 "return accumulator"; 128 (GGP 128) application status 0 = stopped."""
    w = module()
    last = w.vm.program.size - 1
    assert last == 6143
    w.download([(19, 0, 0, 5)], start=last)
    w.run(last)
    w.vm.advance(10 * T)
    assert w.a == 5
    assert w.state == 0
    assert w.vm.interpreter.executed == 1


def test_a_stored_command_answers_status_101_with_value_0(anymod):
    """TMCM-6212 manual 3.6.36: "132 - enter download mode  All following commands (except control
    commands) are not executed but stored in the TMCL memory"; 3.2.1 Table 4 "101 Command loaded
    into TMCL program EEPROM". The manuals give no value for that reply: docs/assumptions.md
    ("Download mode") reads it as 0, whatever the stored value (1234, the largest and the smallest
    32-bit value, -1), while the stored instruction keeps its own value (3.6.36 "134 - read
    program memory", special reply: host address, command, type, motor, value MSB first)."""
    values = (1234, 2**31 - 1, -2**31, -1)
    anymod.ok(132, 0, 0, 0)
    for value in values:
        reply = anymod(5, 4, 0, value)
        assert (reply.status, reply.command, reply.value) == (101, 5, 0)
    anymod.ok(133)
    for address, value in enumerate(values):
        raw = anymod.raw(134, 0, 0, address)
        assert len(raw) == 9 and raw[1:4] == bytes((5, 4, 0))
        assert int.from_bytes(raw[4:8], "big", signed=True) == value


def _direct(w, command, type=0, motor=0, value=0) -> Reply:
    """A request from a host that did not open the download (`VirtualModule.handle(direct=True)`)."""
    raw = w.vm.handle(Request(1, command, type, motor, value).encode(), direct=True)
    return Reply.decode(raw)


@pytest.mark.parametrize("hooked", [False, True], ids=["plain", "faults watching"])
def test_direct_requests_are_executed_during_a_download(hooked):
    """3.6.36: after 132 "All following commands (except control commands) are not executed but
    stored" - for the host that opened the download. A request with `direct=True` (another host of
    a served module, docs/endpoints.md "Several hosts") is executed as in direct mode and not
    stored; that host cannot start the download again (132: status 6, "Command not available")
    nor end it (133 does nothing, as in direct mode). Also with faults watching every frame."""
    w = module(faults=[{"name": "later", "kind": "hang", "duration": 1}] if hooked else None)
    before = w.ok(6, 4, 0)
    w.ok(132, 0, 0, 0)
    assert w(5, 4, 0, before + 1).status == STATUS_LOADED
    read = _direct(w, 6, 4, 0)
    assert (read.status, read.value) == (100, before)
    assert _direct(w, 5, 4, 0, before + 2).status == 100
    assert _direct(w, 6, 4, 0).value == before + 2
    refused = _direct(w, 132, 0, 0, 7)
    assert (refused.status, refused.command) == (6, 132)
    assert _direct(w, 133).status == 100
    assert w.vm.download_mode and w.vm.download_pointer == 1
    assert w(28).status == STATUS_LOADED  # the owner's next instruction is still stored
    w.ok(133)
    assert w.vm.program.code[:3] == [(5, 4, 0, before + 1), (28, 0, 0, 0), (0, 0, 0, 0)]


def test_direct_changes_nothing_without_a_download():
    """Without a download under way, `direct=True` is a plain direct-mode request: SAP and GAP
    answer as without it, and its 132 opens a download (3.6.36) that stores the next command."""
    w = module()
    assert _direct(w, 5, 4, 0, 1234).status == 100
    assert _direct(w, 6, 4, 0).value == w.ok(6, 4, 0) == 1234
    assert _direct(w, 132, 0, 0, 0).status == 100
    assert w(28).status == STATUS_LOADED
    w.ok(133)
    assert w.vm.program.code[0] == (28, 0, 0, 0)
