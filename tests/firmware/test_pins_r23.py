"""Firmware edges left unpinned by the seeded mutation draw of round 23 (issue 12,
`python bench/mutation.py --layer firmware --sample 300 --seed 12`, group A)."""
from __future__ import annotations

import pytest

from opentmcl import VirtualModule
from opentmcl.firmware import requests as dispatch
from opentmcl.firmware.eeprom import Eeprom, EepromError
from opentmcl.lang.assembler import assemble
from opentmcl.modules import load_profile
from opentmcl.protocol.frame import Reply, Request

from .conftest import Host
from .test_program_support import Wire

_HEAD = '{"format":"opentmcl-eeprom","version":1,"module":"TMCM-6212"'


def _frame(command, type=0, motor=0, value=0, address=1) -> bytes:
    return Request(address, command, type, motor, value).encode()


# --- ROR / ROL: the velocity is a target speed AP2 (commands._rotate) ---------------------------

def test_ror_and_rol_take_the_range_of_the_target_speed_ap2(tmp_path):
    """TMCM-6212 3.6.1 ROR / 3.6.2 ROL "Internal function: ... the velocity value is transferred
    to axis parameter #2 (target velocity)": the range checked is AP2's. A profile that narrows
    AP2 to -1000 ... 1000 (docs/profiles.md, an existing number merged) and leaves AP3 (actual
    speed) at +-7999774 takes ROR / ROL 1000 and refuses 1001 with status 4 (invalid value)."""
    path = tmp_path / "slow.toml"
    path.write_text('extends = "TMCM-6212"\n[module]\nname = "SLOW-6212"\n'
                    "[[axis_parameter]]\nnumber = 2\nmin = -1000\nmax = 1000\n")
    h = Host(VirtualModule(str(path), address=1))
    assert h(1, 0, 0, 1000).status == 100
    assert h.ok(6, 2, 0) == 1000
    assert h(1, 0, 0, 1001).status == 4
    assert h(2, 0, 1, 1000).status == 100
    assert h.ok(6, 2, 1) == -1000
    assert h(2, 0, 1, 1001).status == 4
    assert h.ok(6, 2, 1) == -1000  # the refused ROL changed nothing


# --- dispatch.entry: None for every request it does not cover -----------------------------------

def test_entry_of_a_motor_the_module_lacks_is_none():
    """dispatch.py module docstring: "`entry()` answers None for every request it does not cover
    (a wrong type, a motor the module lacks, ...)". The TMCM-6212 has motors 0...5 (manual 3.6.6
    GAP "0...5"): GAP of motor 5 has a handler answering what the general path answers, motor 6
    none."""
    vm = VirtualModule("TMCM-6212", address=1)
    assert len(vm.axes) == 6
    fast = dispatch.handler(vm, 6, 4, 5)
    assert fast is not None
    assert fast() == vm.handle(_frame(6, 4, 5))
    assert dispatch.handler(vm, 6, 4, 6) is None
    assert Reply.decode(vm.handle(_frame(6, 4, 6))).status == 4


def test_entry_of_a_command_without_a_handler_is_none(tmp_path):
    """dispatch.py: handlers exist for "GAP, GGP and GIO of a valid (type, motor/bank)", and
    "`entry()` answers None for every request it does not cover": MVP and SAP have none, and a
    module whose command set lacks GIO (docs/profiles.md `opcodes` replaces the list; status 2,
    TMCM-6212 3.2.1) has no GIO handler, while GAP keeps one."""
    vm = VirtualModule("TMCM-6212", address=1)
    assert dispatch.handler(vm, 4, 0, 0) is None
    assert dispatch.handler(vm, 5, 4, 0) is None
    assert dispatch.handler(vm, 15, 0, 0) is not None
    opcodes = sorted(set(load_profile("TMCM-6212").opcodes) - {15})
    path = tmp_path / "nogio.toml"
    path.write_text('extends = "TMCM-6212"\n[module]\nname = "NOGIO-6212"\n'
                    f"opcodes = {opcodes}\n")
    nogio = VirtualModule(str(path), address=1)
    assert Reply.decode(nogio.handle(_frame(15, 0, 0))).status == 2
    assert dispatch.handler(nogio, 15, 0, 0) is None
    assert dispatch.handler(nogio, 6, 4, 0) is not None


# --- a pre-bound GGP of an unsigned 32-bit value -------------------------------------------------

@pytest.mark.parametrize(("period", "wire"), [
    (0x7FFF_FFFF, 0x7FFF_FFFF), (0x8000_0000, -0x8000_0000), (0xFFFF_FFFF, -1)])
def test_a_prebound_ggp_of_an_unsigned_timer_period_answers_its_32_bits(period, wire):
    """TMCM-6212 5.4 bank 3 "Timer 0 period ... 0 .. 4294967295 [ms]"; 3.2 the reply value is
    four bytes, MSB first, with the checksum over the first eight bytes. The second GGP of the
    same frame is answered by its pre-bound handler (dispatch.py); both replies carry the same
    32 bits: 2^31 - 1 as it is, 2^31 and 2^32 - 1 as -2^31 and -1 in signed form."""
    vm = VirtualModule("TMCM-6212", address=1)
    h = Host(vm)
    assert h(9, 0, 3, wire).status == 100
    frame = _frame(10, 0, 3)
    first = vm.handle(frame)
    assert vm.is_prebound(frame)
    second = vm.handle(frame)
    assert second == first
    assert second[4:8] == (period & 0xFFFF_FFFF).to_bytes(4, "big")
    assert second[8] == sum(second[:8]) & 0xFF
    assert Reply.decode(second).value == wire


# --- EEPROM images --------------------------------------------------------------------------------

@pytest.mark.parametrize("section", [
    '"global":{"0":{"77":"x"}}', '"global":{"0":{"77":2147483648}}', '"global":{"0":5}',
    '"global":[1]'])
def test_a_damaged_global_section_is_refused(tmp_path, section):
    """docs/assumptions.md "EEPROM images are checked when opened: every section must have the
    shape the module writes (32-bit integers ...) ...; otherwise `EepromError` and the file keeps
    its bytes" (eeprom.py `_whole`: {"bank": {"number": int}} for the global section)."""
    path = tmp_path / "ee.json"
    content = _HEAD + "," + section + "}"
    path.write_text(content)
    with pytest.raises(EepromError, match="damaged"):
        Eeprom(path, "TMCM-6212")
    assert path.read_text() == content


def test_the_last_32_bit_value_of_a_global_section_is_read(tmp_path):
    """The edge of the check above: 2^31 - 1 is a 32-bit integer and reads back as stored."""
    path = tmp_path / "ee.json"
    path.write_text(_HEAD + ',"global":{"0":{"77":2147483647}}}')
    assert Eeprom(path, "TMCM-6212").get_global(0, 77) == 2147483647


def test_an_image_without_a_program_section_loads(tmp_path):
    """eeprom.py `_whole`: "Every section has the shape `flush` writes" - a section that is not
    there has none to break (docs/assumptions.md). An image holding only a stored user variable
    (TMCM-6212 3.6.9 STGP; 5.1 GP85 "0 - user variables are restored (default)") opens: the
    variable is back and there is no program."""
    path = tmp_path / "ee.json"
    path.write_text(_HEAD + ',"user":{"3":7}}')
    vm = VirtualModule("TMCM-6212", address=1, eeprom=path)
    assert Host(vm).ok(10, 3, 2) == 7
    assert vm.program.length == 0


# --- the serial heartbeat stopping the motors at a pure instruction's tick ------------------------

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


# --- the constructor's default module --------------------------------------------------------------

def test_a_module_built_without_a_name_is_a_tmcm_6212():
    """`VirtualModule(name="TMCM-6212", ...)` (firmware/vm.py): without a name the module is a
    TMCM-6212 - six motors (manual 3.6.6 GAP motor "0...5") at its factory address 1 (5.1 GP66)."""
    vm = VirtualModule()
    assert vm.profile.name == "TMCM-6212"
    h = Host(vm)
    assert h.ok(10, 66, 0) == 1
    assert h(6, 1, 5).status == 100
    assert h(6, 1, 6).status == 4
