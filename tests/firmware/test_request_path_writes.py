"""Pre-bound SAP and SGP (issue 16 item 2; firmware/requests.py `RequestPath`).

A SAP, or an SGP of a user variable (bank 2), that has succeeded once is answered afterwards by the
same setter bound to its axis or bank (`Motor.set`, `GlobalParameters.set`), keyed by the frame's
address, command, type and motor bytes: the value of each frame is checked as before (TMCM-6212
manual 3.2.1: 4 invalid value, 5 EEPROM locked), GP255 suppresses the reply (5.1), download mode
stores the frame (3.6.36), and the write marks the engines for a new look at their next events.
"""
from __future__ import annotations

import pytest

from opentmcl import VirtualModule
from opentmcl.protocol.frame import Reply, Request


def frame(command, type_=0, motor=0, value=0, address=1):
    return Request(address, command, type_, motor, value).encode()


def send(vm, raw, interface="serial"):
    return Reply.decode(vm.handle(raw, interface=interface))


@pytest.mark.parametrize("number, top", [(6, 255), (140, 8), (255, 1)])
def test_bound_sap_checks_each_value_last_valid_first_invalid(number, top):
    """TMCM-6212 4.1: AP6 maximum current 0...255, AP140 microstep resolution 0...8, AP255 unit mode
    0/1. After a first SAP the frame shape is bound; the last valid value is stored and read back,
    the first invalid one (and -1) answers status 4 and leaves the value."""
    vm = VirtualModule("TMCM-6212", address=1)
    assert send(vm, frame(5, number, 5, 0)).status == 100
    assert vm.is_prebound(frame(5, number, 5, 0))
    assert send(vm, frame(5, number, 5, top)).status == 100
    for bad in (top + 1, -1):
        assert send(vm, frame(5, number, 5, bad)).status == 4
    assert vm.request(6, number, 5).value == top


def test_bound_sap_of_a_read_only_parameter_never_binds():
    """TMCM-6212 4.1 AP8 "target position reached" is R only: SAP answers status 3 every time."""
    vm = VirtualModule("TMCM-6212", address=1)
    assert [send(vm, frame(5, 8, 0, 1)).status for _ in range(2)] == [3, 3]
    assert not vm.is_prebound(frame(5, 8, 0, 1))


def test_sap_of_motor_after_the_last_is_status_4():
    """TMCM-6212 3.6.5 "Motor/Bank 0...5": motor 6 answers status 4 and is not bound."""
    vm = VirtualModule("TMCM-6212", address=1)
    assert [send(vm, frame(5, 4, 6, 100)).status for _ in range(2)] == [4, 4]
    assert not vm.is_prebound(frame(5, 4, 6, 100))


def test_bound_sap_4_changes_the_running_move():
    """TMCM-6212 4.1 AP4 "maximum positioning speed": a bound SAP 4 during a move is a write the
    engine sees (the speed reached is the new maximum)."""
    vm = VirtualModule("TMCM-6212", address=1)
    assert send(vm, frame(5, 4, 0, 1000)).status == 100 and vm.is_prebound(frame(5, 4, 0, 1000))
    assert vm.request(4, 0, 0, 10_000_000).status == 100
    vm.advance(0.5)
    vm.next_event_in()
    assert send(vm, frame(5, 4, 0, 3000)).status == 100
    assert vm.scheduler._dirty
    vm.advance(2.0)
    assert vm.request(6, 3, 0).value == 3000


def test_bound_sgp_user_variable_and_gp255():
    """TMCM-6212 3.6.7 SGP bank 2 (user variables); 5.1 GP255 = 1 suppresses the reply of the bound
    SAP and SGP while GGP still answers."""
    vm = VirtualModule("TMCM-6212", address=1)
    assert send(vm, frame(9, 10, 2, 5)).status == 100 and vm.is_prebound(frame(9, 10, 2, 5))
    assert send(vm, frame(9, 10, 2, -70_000)).status == 100
    assert send(vm, frame(5, 6, 0, 100)).status == 100
    assert vm.request(9, 255, 0, 1) is None
    assert vm.handle(frame(9, 10, 2, 8)) == b"" and vm.handle(frame(5, 6, 0, 120)) == b""
    assert send(vm, frame(10, 10, 2)).value == 8 and send(vm, frame(6, 6, 0)).value == 120


def test_bound_write_in_download_mode_is_stored():
    """3.6.36 command 132: a bound SAP frame is stored (status 101), not executed."""
    vm = VirtualModule("TMCM-6212", address=1)
    assert send(vm, frame(5, 6, 0, 100)).status == 100
    assert vm.request(132).status == 100
    assert send(vm, frame(5, 6, 0, 200)).status == 101
    assert vm.request(133).status == 100
    assert vm.request(6, 6, 0).value == 100


def test_sgp_66_replies_from_the_old_address():
    """TMCM-6212 3.6.7 example "SGP 66, 0, 3" (01 09 42 00 00 00 00 03 4F): the reply to it still
    comes from module address 1; a second SGP 66 is for address 3 then."""
    vm = VirtualModule("TMCM-6212", address=1)
    assert vm.handle(bytes.fromhex("01094200000000034F")) == bytes.fromhex("0201640900000000" "70")
    assert vm.handle(bytes.fromhex("01094200000000034F")) == b""
    assert send(vm, frame(9, 66, 0, 1, address=3)).module_address == 3


def test_bound_write_with_a_wrong_checksum_is_status_1():
    """Manual 3.2.1 status 1 "Wrong checksum": nothing is written."""
    vm = VirtualModule("TMCM-6212", address=1)
    assert send(vm, frame(5, 6, 0, 100)).status == 100
    raw = frame(5, 6, 0, 50)
    assert send(vm, raw[:8] + bytes(((raw[8] + 1) & 0xFF,))).status == 1
    assert vm.request(6, 6, 0).value == 100


def test_bound_sap_on_usb_and_with_another_address():
    """A frame bound on the serial link is written the same over USB (address byte ignored, docs
    /endpoints.md); a frame for address 2 is not answered and writes nothing."""
    vm = VirtualModule("TMCM-6212", address=1)
    assert send(vm, frame(5, 6, 0, 100)).status == 100
    assert send(vm, frame(5, 6, 0, 110), interface="usb").status == 100
    assert vm.handle(frame(5, 6, 0, 120, address=2)) == b""
    assert vm.request(6, 6, 0).value == 110


@pytest.mark.parametrize("command, type_, motor, value", [(5, 4, 0, 1000), (5, 140, 2, 4), (9, 3, 2, 42)])
def test_bound_write_declares_the_effect_of_the_command_table(command, type_, motor, value, monkeypatch):
    """Issue 33 "One command table ... for each opcode it gives its effect" and docs/architecture.md
    "Time": "Whoever adds a command gives its effect in the table and nothing else". A bound SAP
    (TMCM-6212 3.6.5) or SGP to a user variable (3.6.7, bank 2) tells the scheduler the same effect
    as the same frame on the general path: the table's, not one of its own."""
    vm = VirtualModule("TMCM-6212", address=1)
    effects = []
    prepare = vm.scheduler.prepare
    monkeypatch.setattr(vm.scheduler, "prepare", lambda effect: (effects.append(int(effect)), prepare(effect)))
    raw = frame(command, type_, motor, value)
    assert send(vm, raw).status == 100 and vm.is_prebound(raw)  # the general path, then bound
    assert send(vm, raw).status == 100                          # the bound setter
    assert len(effects) == 2 and effects[0] == effects[1], effects
