"""Edges of the virtual module's Python API and of CSUB, found unpinned by mutation testing
(docs/mutation.md)."""
from __future__ import annotations

import pytest

from opentmcl import VirtualModule
from opentmcl.firmware import flags

from .test_program_support import T, run_program


@pytest.mark.parametrize("address", [1, 255])
def test_assign_address_takes_both_ends_of_gp66(address):
    """TMCM-6212 5.1 GP66 "Serial address" 1...255: `assign_address` serves at any of them."""
    vm = VirtualModule("TMCM-6212")
    vm.assign_address(address)
    assert vm.address == address and vm.request(10, 66, 0).value == address


@pytest.mark.parametrize("address", [0, 256, "1", 2.0])
def test_assign_address_refuses_what_gp66_cannot_hold(address):
    vm = VirtualModule("TMCM-6212", address=3)
    with pytest.raises(ValueError, match="range of GP66"):
        vm.assign_address(address)
    assert vm.address == 3


def test_request_gives_none_when_the_reply_is_suppressed():
    """3.6.7 GP255: "The reply in direct mode will be suppressed when this parameter is set to 1":
    the convenience `request` has no reply to decode and returns None."""
    vm = VirtualModule("TMCM-6212", address=1)
    assert vm.request(9, 255, 0, 1) is None
    assert vm.request(6, 1, 0).status == 100  # GAP is never suppressed (docs/assumptions.md)


def test_stored_global_reads_the_eeprom_not_the_ram(tmp_path):
    """TMCM-6212 5.1: bank-0 parameters 64..127 are "automatically stored in the EEPROM"; the tick
    timer GP132 is not: `stored_global` shows what the EEPROM holds."""
    vm = VirtualModule("TMCM-6212", address=1, eeprom=tmp_path / "ee.json")
    vm.request(9, 75, 0, 15)
    vm.request(9, 132, 0, 5)
    assert (vm.stored_global(0, 75), vm.stored_global(0, 132)) == (15, None)


def test_flag_names_for_the_debugger():
    """TMCM-6212 3.6.16 JC names ZE, EQ, GT, LT and the error flags ETO, EAL, EDV, EPO, ESD (3.6.29
    CLE); `describe` spells each set flag with the manual's name, "-" for none."""
    everything = flags.ZERO | flags.EQUAL | flags.GREATER | flags.LOWER | flags.ERROR_MASK
    assert flags.describe(everything) == "ZE EQ GT LT ETO EAL EDV EPO ESD"
    assert flags.describe(0) == "-"


def test_csub_may_call_address_0():
    """TMCM-6212 3.6.18 CSUB "Call subroutine": address 0 is a program address like any other; the
    subroutine at 0 runs twice (once as the program, once when called) and RSUB returns."""
    src = """
    Sub:
        GGP 5, 2
        CALC ADD, 1
        AGP 5, 2
        COMP 2
        JC EQ, Back
        CSUB Sub
        STOP
    Back:
        RSUB
    """
    w = run_program(src, 40 * T)
    assert (w.var(5), w.state) == (2, 0)


@pytest.mark.parametrize("name", ["PD28-1021", "PD86-1180"])
def test_a_non_ascii_byte_in_an_ascii_line_is_a_status_not_a_crash(name):
    """PD28-1021 3.4.2: a command line is ASCII text; a byte that is no ASCII character makes the
    operand unreadable: the reply carries status 4 (house rule: bad input -> a status on the wire)."""
    vm = VirtualModule(name)
    vm.request(139)
    vm.globals.set(0, 67, 0x20)  # 3.4.4 "When bit 5 is set ... there will be no echo"
    assert vm.feed_ascii(b"AGAP 1, \xff0\r") == b"BA 4 0\r"


def test_an_address_for_a_profile_without_gp66_is_a_clear_error(tmp_path):
    """A profile file may `[remove]` GP66 (docs/profiles.md); then no module address can be set
    (TMCM-6212 5.1: the address lives in GP66): a ValueError naming GP66, not a KeyError."""
    path = tmp_path / "no66.toml"
    path.write_text('extends = "TMCM-6212"\n[module]\nname = "NO-66"\n'
                    '[remove]\nglobal_parameter = [[0, 66]]\n')
    VirtualModule(str(path))                                  # without an address: fine
    with pytest.raises(ValueError, match="no serial address parameter GP66"):
        VirtualModule(str(path), address=3)
    with pytest.raises(ValueError, match="no serial address parameter GP66"):
        VirtualModule(str(path)).assign_address(3)
