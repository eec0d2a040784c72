"""The ASCII interface (PD28-1021 manual 3.4, PD86-1180 manual 4.5): command 139, GP67, echo modes,
backspace, BIN, RUN/STOP, `BA 100 -5000` replies."""
from __future__ import annotations

import pytest

from opentmcl import VirtualModule
from opentmcl.protocol.frame import Request

from .conftest import Host


@pytest.fixture(params=["PD28-1021", "PD86-1180"])
def ascii_host(request):
    host = Host(VirtualModule(request.param))
    host.ok(139)
    assert host.vm.ascii_mode
    return host


def test_manual_reply_example(ascii_host):
    """3.4.3: "after sending AGAP 0, 1 the reply would be BA 100 -5000 if the actual position ... is -5000,
    the host address is set to 2 and the module address is 1" (our modules have one axis: motor 0)."""
    vm = ascii_host.vm
    vm.axes[0].engine.set_position(-5000)
    out = vm.feed_ascii(b"AGAP 1, 0\r")
    assert out == b"AGAP 1, 0\r" + b"BA 100 -5000\r"


def test_command_line_forms(ascii_host):
    """3.4.2: "After the address character there may be spaces"; examples AMVP ABS, ..., A MST."""
    vm = ascii_host.vm
    vm.globals.set(0, 67, 0x20)                      # bit 5: no echo, only the reply
    assert vm.feed_ascii(b"A MVP ABS, 0, 5000\r") == b"BA 100 0\r"
    assert vm.feed_ascii(b"AMST 0\r") == b"BA 100 0\r"
    assert vm.feed_ascii(b"ASAP 4, 0, 123\r") == b"BA 100 0\r"
    assert vm.feed_ascii(b"AGAP 4, 0\r") == b"BA 100 123\r"


def test_echo_whole_line_mode(ascii_host):
    """3.4.4: "When bit 4 is set ... the entire line will be echoed back after the <CR>"."""
    vm = ascii_host.vm
    vm.globals.set(0, 67, 0x10)
    assert vm.feed_ascii(b"AGGP 66, 0") == b""
    assert vm.feed_ascii(b"\r") == b"AGGP 66, 0\rBA 100 1\r"


def test_backspace_editing(ascii_host):
    """3.4.4: "Characters can also be erased using the backspace character"."""
    vm = ascii_host.vm
    vm.globals.set(0, 67, 0x20)
    assert vm.feed_ascii(b"AGAP 9\x084, 0\r") == b"BA 100 " + str(vm.axes[0].get(4)).encode() + b"\r"


def test_other_addresses_and_errors(ascii_host):
    """3.4.2: the address character selects the module — B is module 2, so module 1 stays silent;
    a command ASCII mode does not know is answered with status 2; only direct-mode commands are allowed."""
    vm = ascii_host.vm
    assert vm.feed_ascii(b"BGAP 1, 0\r") == b""
    vm.globals.set(0, 67, 0x20)
    assert vm.feed_ascii(b"AFOO 1\r") == b"BA 2 0\r"
    assert vm.feed_ascii(b"ACALC ADD, 1\r") == b"BA 2 0\r"


def test_bin_returns_to_binary_mode(ascii_host):
    """3.4.1: "For leaving the ASCII mode and re-entering the binary mode enter the command BIN"; the bytes
    after it are binary frames again."""
    vm = ascii_host.vm
    vm.globals.set(0, 67, 0x20)
    frame = bytes.fromhex("01 06 01 00 00 00 00 00 08")
    assert vm.feed_ascii(b"ABIN\r" + frame) == b"BA 100 0\r"
    assert not vm.ascii_mode and vm.ascii.leftover == frame
    assert ascii_host.ok(6, 1, 0) == 0


def test_run_and_stop(ascii_host):
    """3.4: "RUN: ... start a TMCL program stored in memory. STOP: Stops a TMCL program"."""
    vm = ascii_host.vm
    vm.globals.set(0, 67, 0x20)
    assert vm.feed_ascii(b"ARUN\r") == b"BA 100 0\r"
    assert vm.application_status == 1
    assert vm.feed_ascii(b"ASTOP\r") == b"BA 100 0\r"
    assert vm.application_status == 0


def test_gp67_bit0_starts_in_ascii_mode(tmp_path):
    """3.4.4: "Bit 0 determines the startup mode: if this bit is set, the module will start up in ASCII
    mode"."""
    path = tmp_path / "ee.json"
    host = Host(VirtualModule("PD28-1021", eeprom=path))
    host.ok(9, 67, 0, 1)
    assert not host.vm.ascii_mode
    assert VirtualModule("PD28-1021", eeprom=path).ascii_mode


def test_can_heartbeat_gp82_watches_can_traffic_only(m6212):
    """TMCM-6212 5.1 GP82 "Heartbeat for CAN interface. If this time limit is up and no further command is
    received the motor will be stopped." Serial traffic does not feed the CAN heartbeat."""
    vm = m6212.vm
    m6212.ok(9, 82, 0, 300)
    m6212.ok(1, 0, 0, 1000)
    vm.advance(0.2)
    m6212.ok(6, 1, 0)                          # a serial command: CAN stays silent
    vm.advance(0.2)
    assert vm.axes[0].engine.velocity == 0
    m6212.ok(1, 0, 0, 1000)                    # serial again; the CAN heartbeat fired already
    vm.handle(bytes.fromhex("01 06 01 00 00 00 00 00 08"), interface="can")
    vm.advance(0.2)
    assert vm.axes[0].engine.velocity != 0


@pytest.mark.parametrize("host", [26, 27, 0, 255])
def test_a_host_address_without_a_character(ascii_host, host):
    """3.4.3: a reply starts with "the address character of the host"; A is 1 ... Z is 26 (3.4.2),
    so GP76 = 26 gives Z, while 27 (the first beyond), 0 or 255 have no character: the line is
    executed (and echoed) and no reply line follows (docs/assumptions.md)."""
    vm = ascii_host.vm
    vm.globals.set(0, 76, host)
    out = vm.feed_ascii(b"ASAP 4, 0, 321\r")
    assert vm.axes[0].get(4) == 321                       # executed either way
    if host == 26:
        assert out == b"ASAP 4, 0, 321\r" + b"ZA 100 0\r"
    else:
        assert out == b"ASAP 4, 0, 321\r"


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


def test_ap138_reads_the_same_in_ascii_as_in_binary():
    """PD86-1180 5 AP138 ramp mode "Automatically set when using ROR, ROL, MST and MVP"
    (docs/assumptions.md "AP138 read-back": ROR gives 2, MVP 0); 4.5: AGAP answers as GAP does."""
    host = Host(VirtualModule("PD86-1180", address=1))
    vm = host.vm
    host.ok(1, 0, 0, 100)                               # ROR 0, 100
    assert host.ok(6, 138) == 2
    host.ok(139)
    vm.globals.set(0, 67, 0x20)                          # no echo, only the reply
    assert vm.feed_ascii(b"AGAP 138, 0\r") == b"BA 100 2\r"
    assert vm.feed_ascii(b"AMVP ABS, 0, 0\r") == b"BA 100 0\r"
    assert vm.feed_ascii(b"AGAP 138, 0\r") == b"BA 100 0\r"


# A module whose address has no ASCII address character ignores every ASCII line instead of raising.
#
# PD28-1021 manual 3.4.1: "As the first character, the address character has to be sent. The address
# character is A when the module address is 1, B for modules with address 2 and so on." Global
# parameter 66 takes 0..255, so a module at 0 or 27..255 has no character: no line is addressed to it.

def _ascii_module(address: int) -> VirtualModule:
    vm = VirtualModule("PD28-1021", address=address)
    vm.request(139)  # enter ASCII mode (3.4.1)
    assert vm.ascii_mode
    return vm


def test_last_address_with_a_character_is_answered() -> None:
    """Address 26 is Z; the reply is host character (B: host address 2), module character, status,
    value (3.4.3), after the echo of the line."""
    vm = VirtualModule("PD28-1021", address=26)
    ap4 = vm.request(6, 4).value
    vm.request(139)
    assert vm.feed_ascii(b"ZGAP 4,0\r") == b"ZGAP 4,0\rBZ 100 " + str(ap4).encode() + b"\r"


@pytest.mark.parametrize("address", [0, 27, 255])
@pytest.mark.parametrize("line", [b"AGAP 4,0\r", b"ZGAP 4,0\r", b"[GAP 4,0\r", b" BIN\r"])
def test_address_without_a_character_ignores_every_line(address: int, line: bytes) -> None:
    vm = _ascii_module(address)
    assert vm.feed_ascii(line) == b""
    assert vm.ascii_mode  # not even BIN of another module's line switched it back


@pytest.mark.parametrize("name", ["PD28-1021", "PD86-1180"])
def test_a_non_ascii_byte_in_an_ascii_line_is_a_status_not_a_crash(name):
    """PD28-1021 3.4.2: a command line is ASCII text; a byte that is no ASCII character makes the
    operand unreadable: the reply carries status 4 (house rule: bad input -> a status on the wire)."""
    vm = VirtualModule(name)
    vm.request(139)
    vm.globals.set(0, 67, 0x20)  # 3.4.4 "When bit 5 is set ... there will be no echo"
    assert vm.feed_ascii(b"AGAP 1, \xff0\r") == b"BA 4 0\r"
