"""Edges found unpinned by the seeded mutation sample of the firmware layer after the request-path
and run-ahead changes of issue 16 (docs/mutation.md, `python bench/mutation.py --layer firmware
--sample 150 --seed 12`, round 21)."""
from __future__ import annotations

import pytest

from opentmcl import VirtualModule
from opentmcl.firmware.eeprom import EepromError
from opentmcl.firmware.interpreter import INSTRUCTION_TICKS
from opentmcl.firmware.wait import TICK
from opentmcl.motion import CLOCK_HZ
from opentmcl.protocol.frame import Reply, Request

from .test_program_support import T, Wire, module


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


def test_rst_restarts_at_address_0_and_refuses_the_end_of_memory():
    """PD28-1021 manual Table 5: "RST 48 <jump address> Restart the program from the given
    address". Address 0, the first of the program memory, is a valid target: the loop ADD 1 /
    COMP 3 / JC EQ / RST 0 runs three times. The first address beyond the memory (2048, 1 Features
    "2048 TMCL commands") is an invalid value (3.2.1 Table 4 "4 Invalid value"; the program goes on
    after it) and the last one (2047) is taken (it runs into the empty memory cell: status 2)."""
    w = module("PD28-1021")
    size = w.vm.program.size
    assert size == 2048
    w.download([(19, 0, 0, 1), (20, 0, 0, 3), (21, 2, 0, 4), (48, 0, 0, 0), (28, 0, 0, 0)])
    w.run()
    w.vm.advance(40 * T)
    assert (w.a, w.state, w.vm.interpreter.last_error) == (3, 0, None)
    w = module("PD28-1021")
    w.download([(48, 0, 0, size), (19, 0, 0, 7), (28, 0, 0, 0)])
    w.run()
    w.vm.advance(10 * T)
    assert (w.a, w.vm.interpreter.last_error) == (7, (0, 48, 4))
    w = module("PD28-1021")
    w.download([(48, 0, 0, size - 1)])
    w.run()
    w.vm.advance(10 * T)
    assert w.vm.interpreter.last_error == (size - 1, 0, 2)


def test_wait_refsw_on_a_module_without_a_home_switch_parameter_times_out(tmp_path):
    """TMCM-6212 3.6.20 "REFSW: Wait until a reference switch has been triggered ... The timeout flag
    (ETO) will be set after a timeout limit has been reached". A profile that removes AP9 (home
    switch state, 4.1; docs/profiles.md `[remove]`) has no switch to wait for: the WAIT ends by
    its timeout of 5 ticks and sets ETO (docs/assumptions.md "Firmware mutation sample"), the same
    as on a module whose home switch stays open."""
    path = tmp_path / "nohome.toml"
    path.write_text('extends = "TMCM-6212"\n[module]\nname = "NOHOME-6212"\n'
                    "[remove]\naxis_parameter = [9]\n")
    for name in ("TMCM-6212", str(path)):
        w = module(name)
        w.download([(27, 2, 0, 5), (21, 8, 0, 3), (28, 0, 0, 0), (19, 9, 0, 9), (28, 0, 0, 0)])
        w.run()
        w.vm.advance(3 * T)
        assert w.pc == 0, name  # still waiting
        w.vm.advance(0.1)
        assert (w.a, w.state) == (9, 0), name


@pytest.mark.parametrize(("ticks", "wait"), [(-1, 0), (0, 0), (1, TICK)])
def test_wait_ticks_0_goes_on_at_once_and_1_waits_one_tick(ticks, wait):
    """TMCM-6212 3.6.20 WAIT TICKS: "one tick is 10 milliseconds"; docs/assumptions.md "WAIT":
    `WAIT TICKS, 0, n` with n <= 0 does not wait, and the next instruction follows one slot
    after the wait ends: SIO at 1 slot, WAIT at 2, the next SIO exactly at 3 slots + n ticks
    (n = 1, the first that waits: 10 ms), to the clock tick."""
    w = module()
    w.download([(14, 0, 2, 1), (27, 0, 0, ticks), (14, 0, 2, 0), (28, 0, 0, 0)])
    w.run()
    due = w.vm.now + 3 * INSTRUCTION_TICKS + wait
    w.vm.advance_to(due - 1)
    assert w.out(0) == 1
    w.vm.advance_to(due)
    assert w.out(0) == 0


def test_the_eeprom_lock_holds_after_a_power_cycle(tmp_path):
    """PD86-1180 6.1 GP73 "Configuration EEPROM lock flag ... Write: 1234 to lock the EEPROM,
    4321 to unlock it. Read: 1=EEPROM locked", access RWE: the lock is kept in the EEPROM, so a
    module powered up again on the same EEPROM is still locked - 4.6.7 STAP "will not have any
    effect when the configuration EEPROM is locked ... the error code 5" - until 4321 unlocks it."""
    path = tmp_path / "ee.json"
    Wire(VirtualModule("PD86-1180", address=1, eeprom=path)).ok(9, 73, 0, 1234)
    again = Wire(VirtualModule("PD86-1180", address=1, eeprom=path))
    assert again.ok(10, 73, 0) == 1
    assert again(7, 4, 0).status == 5
    again.ok(9, 73, 0, 4321)
    third = Wire(VirtualModule("PD86-1180", address=1, eeprom=path))
    assert third.ok(10, 73, 0) == 0
    assert third(7, 4, 0).status == 100


def test_reti_right_after_power_up_is_ignored():
    """TMCM-6212 3.6.33 RETI ends an interrupt handling routine; docs/assumptions.md "Interrupts":
    "RETI outside a handler is ignored". A program started with 129 type 0 ("from current
    address", 3.6.36) just after power-up, whose first instruction is RETI, goes on to the next."""
    w = module()
    w.download([(38, 0, 0, 0), (19, 9, 0, 4), (28, 0, 0, 0)])
    w.run()
    w.vm.advance(10 * T)
    assert (w.a, w.state, w.vm.interpreter.last_error) == (4, 0, None)


def test_vect_takes_the_last_address_and_refuses_the_first_beyond():
    """TMCM-6212 3.6.32 "VECT <interrupt number>, <label>": the label is an address of the program
    memory (1 Features: 6144 commands, 0...6143). 6143 is set; 6144 is an invalid value (3.2.1
    Table 4 "4 Invalid value"), and the program goes on after it."""
    w = module()
    size = w.vm.program.size
    w.download([(37, 0, 0, size - 1), (37, 1, 0, size), (28, 0, 0, 0)])
    w.run()
    w.vm.advance(10 * T)
    assert w.vm.interrupts.vectors[0] == size - 1
    assert w.vm.interpreter.last_error == (1, 37, 4)
    assert (w.pc, w.state) == (2, 0)


def test_a_module_without_gp66_answers_at_the_address_it_reports(tmp_path):
    """TMCM-6212 5.1 GP66 "Serial address" is the address the module answers (3.1: the first byte of
    a request addresses the module). A profile that removes GP66 (docs/profiles.md `[remove]`) has
    no address setting: it reports address 0 and answers frames to 0 only, from 0 - not from
    GP66's default of 1."""
    path = tmp_path / "no66.toml"
    path.write_text('extends = "TMCM-6212"\n[module]\nname = "NO66-6212"\n'
                    "[remove]\nglobal_parameter = [[0, 66]]\n")
    vm = VirtualModule(str(path))
    assert vm.address == 0
    assert vm.handle(Request(1, 6, 1, 0, 0).encode()) == b""
    reply = Reply.decode(vm.handle(Request(0, 6, 1, 0, 0).encode()))
    assert (reply.module_address, reply.status) == (0, 100)


def test_error_replies_carry_value_0_on_both_paths():
    """TMCM-6212 3.2 Table 3: a reply is reply address, module address, status, command, value;
    docs/assumptions.md "Firmware mutation sample": an error reply's value is 0. A frame with a
    wrong checksum (3.2.1 Table 4 "1 Wrong checksum") to a module at address 5 gets status 1 from
    module 5 with value 0; a SAP that the pre-bound path refuses (4.1 AP4 0...7999774: 7999775 is
    status 4) answers byte for byte what the general path answers to the same frame."""
    vm = VirtualModule("TMCM-6212", address=5)
    good = Request(5, 6, 1, 0, 0).encode()
    bad = Reply.decode(vm.handle(good[:8] + bytes(((good[8] + 1) & 0xFF,))))
    assert (bad.module_address, bad.status, bad.command, bad.value) == (5, 1, 6, 0)
    refused = Request(5, 5, 4, 0, 7999775).encode()
    general = VirtualModule("TMCM-6212", address=5).handle(refused)
    assert vm.handle(Request(5, 5, 4, 0, 7999774).encode())[2] == 100
    assert vm.is_prebound(refused)
    assert vm.handle(refused) == general
    assert Reply.decode(general).status == 4 and Reply.decode(general).value == 0


def test_the_secondary_address_is_accepted_and_no_other():
    """TMCM-6212 5.1 GP87 "Serial secondary address: Second module (target) address for RS485.
    Setting this parameter to 0 switches off the secondary address", 0...255: with GP87 = 3 the
    module at address 1 takes frames to 1 and to 3, not to 4 or 2; with GP87 = 0 only 1."""
    vm = VirtualModule("TMCM-6212", address=1)
    assert [vm.accepts_address(a) for a in (0, 1, 2, 3, 4)] == [False, True, False, False, False]
    assert vm.request(9, 87, 0, 3).status == 100
    assert [vm.accepts_address(a) for a in (0, 1, 2, 3, 4, 255)] == [False, True, False, True, False, False]
    got = {a: len(vm.handle(Request(a, 6, 1, 0, 0).encode())) for a in (1, 2, 3, 4)}
    assert got == {1: 9, 2: 0, 3: 9, 4: 0}


@pytest.mark.parametrize("bank", [0, 1])
def test_sio_255_on_a_bank_without_outputs_is_wrong_type(bank):
    """TMCM-6212 3.6.12 SIO "<bank number> (2)": the outputs are bank 2 only, so `SIO 255, <bank>`
    (all outputs at once) on the input banks 0 and 1 has no output to set - 3.2.1 Table 4 "3 Wrong
    type", as GIO 255 on the analog bank (docs/assumptions.md) - while `SIO 255, 2, 0` is taken."""
    w = module()
    assert w(14, 255, bank, 0).status == 3
    assert w(14, 255, 2, 0).status == 100


def test_1180_pullups_take_0_to_7():
    """PD86-1180 4.6.14 "COMMAND FOR SWITCHING THE PULL-UP RESISTORS": "SIO 0, 0,<bitmask> 0… 7":
    0 (all off) and 7 (all on) are taken, -1 and 8 are status 4 (3.2.1 "4 Invalid value")."""
    w = module("PD86-1180")
    w.ok(14, 0, 0, 7)
    w.ok(14, 0, 0, 0)
    assert w.vm.io.pullups == 0
    assert (w(14, 0, 0, -1).status, w(14, 0, 0, 8).status) == (4, 4)
    assert w.vm.io.pullups == 0


def test_request_defaults_the_value_to_0():
    """`VirtualModule.request(command, type=0, motor=0, value=0)`: SIO 0, 2 with the value left out
    sets OUT_0 (TMCM-6212 3.6.12 SIO "<port number> (0...4), <bank number> (2), 0/1") to 0."""
    vm = VirtualModule("TMCM-6212", address=1)
    assert vm.request(14, 0, 2, 1).status == 100
    assert vm.request(15, 0, 2).value == 1
    assert vm.request(14, 0, 2).status == 100
    assert vm.request(15, 0, 2).value == 0


def test_sio_replies_the_value_the_manual_prints():
    """TMCM-6212 3.6.12 SIO "Reply in Direct Mode: Status 100 - OK, Value 0 (don't care)": the
    manual prints 0 as the reply value of SIO, so SIO 0, 2, 1 answers 0 (and GIO 0, 2
    reads the output back as 1)."""
    vm = VirtualModule("TMCM-6212", address=1)
    reply = vm.request(14, 0, 2, 1)
    assert (reply.status, reply.command, reply.value) == (100, 14, 0)
    assert vm.request(15, 0, 2).value == 1


def test_an_ascii_line_leaves_no_binary_bytes_over():
    """PD28-1021 manual 3.4.1: only the bytes after a BIN line are binary frames again
    (`AsciiInterface.leftover`, which the bus hands to the binary framer). A feed that stays in
    ASCII mode leaves nothing over, also after an earlier feed with BIN left a frame over."""
    vm = VirtualModule("PD28-1021", address=1)
    assert vm.request(139).status == 100
    assert vm.feed_ascii(b"AGAP 1, 0\r").endswith(b"BA 100 0\r")
    assert vm.ascii.leftover == b""
    frame = Request(1, 6, 1, 0, 0).encode()
    vm.feed_ascii(b"ABIN\r" + frame)
    assert vm.ascii.leftover == frame
    assert vm.request(139).status == 100
    vm.feed_ascii(b"AGAP 1, 0\r")
    assert vm.ascii.leftover == b""


def test_an_unknown_command_is_status_2_with_value_0():
    """TMCM-6212 3.2.1 Table 4 "2 Invalid command": a command number the module does not have (99)
    is answered with status 2 and, as every error reply (docs/assumptions.md), value 0."""
    vm = VirtualModule("TMCM-6212", address=1)
    reply = vm.request(99, 0, 0, 1234)
    assert (reply.status, reply.command, reply.value) == (2, 99, 0)


def test_ja_beyond_program_memory_is_ignored_with_status_4():
    """TMCM-6212 3.6.17 "JA <jump address>", 1 Features: 6144 commands, so 6144 is beyond the memory:
    docs/assumptions.md "Program memory end": a JA one beyond the end is ignored (3.2.1 Table 4
    "4 Invalid value" in the program's last error) and the program goes on; JA 6143 is taken."""
    w = module()
    size = w.vm.program.size
    w.download([(22, 0, 0, size), (19, 9, 0, 3), (28, 0, 0, 0)])
    w.run()
    w.vm.advance(10 * T)
    assert (w.a, w.vm.interpreter.last_error) == (3, (0, 22, 4))
    w = module()
    w.download([(22, 0, 0, size - 1)])
    w.run()
    w.vm.advance(10 * T)
    assert w.vm.interpreter.last_error == (size - 1, 0, 2)


_HEAD = '{"format":"opentmcl-eeprom","version":1,"module":"TMCM-6212"'


@pytest.mark.parametrize("content", [
    _HEAD + ',"coord":{"1":{"2":"x"}}}',
    _HEAD + ',"coord":[1]}',
    '{"format":"other","version":1,"module":"TMCM-6212"}',
    '{"version":1,"module":"TMCM-6212"}',
    '[1, 2]',
])
def test_a_damaged_coordinate_section_or_a_foreign_file_is_refused(tmp_path, content):
    """docs/architecture.md "Errors" (never a corrupted EEPROM file): coordinates are stored as
    32-bit integers per motor (TMCM-6212 3.6.22 SCO "-2^31 ... 2^31 - 1"), so a coordinate section
    with a text value or of the wrong shape is damaged; a JSON file that is not an OpenTMCL EEPROM
    image (another format, none, not an object) is refused too - both as EepromError, the file
    keeping its bytes."""
    path = tmp_path / "ee.json"
    path.write_text(content)
    with pytest.raises(EepromError, match="EEPROM file"):
        VirtualModule("TMCM-6212", eeprom=path)
    assert path.read_text() == content


def test_a_stored_program_keeps_32_bit_values(tmp_path):
    """TMCM-6212 3.1 Table 2: an instruction is command, type, motor/bank (a byte each) and a
    32-bit value; an EEPROM image whose program holds MVP ABS values beyond a byte (256, 51200)
    and the lowest 32-bit value loads with the values as stored (only the three byte fields are
    limited to 0...255)."""
    path = tmp_path / "ee.json"
    path.write_text(_HEAD + ',"program":[[4,0,0,51200],[4,0,0,-2147483648],[4,0,0,256]]}')
    vm = VirtualModule("TMCM-6212", address=1, eeprom=path)
    assert vm.program.code[:3] == [(4, 0, 0, 51200), (4, 0, 0, -2147483648), (4, 0, 0, 256)]


def test_next_event_in_counts_seconds():
    """`VirtualModule.next_event_in()`: seconds to the next internal event. A program started with
    129 has its first instruction one slot later (docs/assumptions.md "Instruction rate": 1600
    ticks of the 16 MHz clock, 100 µs); a stopped program and standing motors have none."""
    w = module()
    assert w.vm.next_event_in() is None
    w.download([(27, 0, 0, 50), (28, 0, 0, 0)])
    w.run()
    assert w.vm.next_event_in() == INSTRUCTION_TICKS / CLOCK_HZ == 1e-4
    w.vm.advance(T)
    assert w.vm.next_event_in() == pytest.approx(0.5)
