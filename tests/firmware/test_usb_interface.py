"""TMCL over USB ignores the address byte; RS-485/RS-232 filter by it (issue 10, section 4).

TMCM-6212 manual 3.1: "When a command is to be sent via RS-232, RS-485, RS-422 or USB interface,
it has to be enclosed by an address byte at the beginning and a checksum byte at the end";
5.1 GP66 is the "RS485 serial address". Trinamic's open TMCL firmware reads a USB command with
"Ignore address byte" and checks the address on RS-485/RS-232 only
(docs/sources.md "USB address byte", docs/assumptions.md)."""
from __future__ import annotations

import pytest

from opentmcl import VirtualModule
from opentmcl.protocol.frame import Reply, Request

GGP_66 = 10, 66, 0


def _ggp66(vm, target, interface):
    return vm.handle(Request(target, *GGP_66, 0).encode(), interface=interface)


@pytest.mark.parametrize("target", [0, 1, 3, 254, 255])
def test_usb_answers_any_address_byte_from_the_module_address(target):
    """On USB any address byte is accepted; the reply carries the module's own address (GP66 = 3)
    and the host address GP76 (manual 3.2 reply format)."""
    vm = VirtualModule("TMCM-6212", address=3)
    reply = Reply.decode(_ggp66(vm, target, "usb"))
    assert (reply.reply_address, reply.module_address, reply.status, reply.value) == (2, 3, 100, 3)


@pytest.mark.parametrize("interface", ["serial", "rs485", "rs232"])
def test_rs485_and_rs232_keep_filtering(interface):
    """GP66 "RS485 serial address": a frame for another address gets no reply; the module's own
    address (3) and an enabled secondary address GP87 (7) are answered."""
    vm = VirtualModule("TMCM-6212", address=3)
    assert _ggp66(vm, 2, interface) == b"" and _ggp66(vm, 4, interface) == b""
    assert Reply.decode(_ggp66(vm, 3, interface)).value == 3
    assert vm.request(9, 87, 0, 7).status == 100
    assert Reply.decode(_ggp66(vm, 7, interface)).module_address == 3


def test_handle_filters_unless_told_usb():
    """`VirtualModule.handle` without an interface filters by address, as before."""
    vm = VirtualModule("PD86-1180", address=1)
    assert vm.handle(Request(0, *GGP_66, 0).encode()) == b""
    assert Reply.decode(vm.handle(Request(0, *GGP_66, 0).encode(), interface="usb")).module_address == 1


def test_usb_wrong_checksum_is_status_1():
    """Manual 3.2 status 1 "Wrong checksum" - on USB also for a frame with a foreign address byte."""
    vm = VirtualModule("PD28-1021", address=1)
    frame = bytearray(Request(9, *GGP_66, 0).encode())
    frame[8] ^= 0xFF
    reply = Reply.decode(vm.handle(bytes(frame), interface="usb"))
    assert (reply.module_address, reply.status) == (1, 1)


@pytest.mark.parametrize("interface", ["usb", "rs485", "rs232", "serial"])
def test_serial_heartbeat_gp68_is_fed_by_usb_and_rs485(interface):
    """TMCM-6212 5.1 GP68 "Serial heartbeat for RS485 interface and USB interface. If this time
    limit is up and no further command is received by the module the motor will be stopped":
    commands on USB (any address byte) and RS-485 keep the motor running past the limit."""
    vm = VirtualModule("TMCM-6212", address=1)
    assert vm.request(9, 68, 0, 100).status == 100
    assert vm.request(1, 0, 0, 1000).status == 100          # ROR 0, 1000
    target = 0 if interface == "usb" else 1
    for _ in range(6):                                         # 6 x 60 ms > 100 ms
        vm.advance(0.06)
        assert vm.handle(Request(target, 6, 3, 0, 0).encode(), interface=interface)
    assert vm.axes[0].engine.velocity != 0
    vm.advance(0.101)                                          # silence beyond GP68
    assert vm.axes[0].engine.velocity == 0


def test_can_frames_do_not_feed_the_serial_heartbeat():
    """GP68 watches RS485 and USB; CAN traffic feeds only GP82 (5.1)."""
    vm = VirtualModule("TMCM-6212", address=1)
    vm.request(9, 68, 0, 100)
    vm.request(1, 0, 0, 1000)
    for _ in range(3):
        vm.advance(0.06)
        vm.handle(Request(1, 6, 3, 0, 0).encode(), interface="can")
    assert vm.axes[0].engine.velocity == 0
