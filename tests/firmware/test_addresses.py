"""The module address: GP66 "Serial address" 1...255 and GP87 "Serial secondary address"
(TMCM-6212 manual 5.1; 3.1: the first byte of a request addresses the module), set by the
constructor or `VirtualModule.assign_address`, kept across a restart, stored by STGP, and a profile
that removes GP66 (docs/profiles.md `[remove]`)."""
from __future__ import annotations

import pytest

from opentmcl import VirtualModule
from opentmcl.protocol.frame import Reply, Request

from .conftest import Host
from .test_program_support import Wire


def test_the_assigned_address_is_kept_across_a_restart():
    """`VirtualModule.assign_address`: "GP66 in RAM, kept across resets" (TMCM-6212 5.1 GP66 "Serial
    address"): after 137 (restore factory defaults, then a restart) the module still answers at
    the address it was given, not at the default 1."""
    vm = VirtualModule("TMCM-6212")
    vm.assign_address(9)
    assert vm.request(137, 0, 0, 1234) is None   # no reply: the module restarts
    assert vm.address == 9 and Wire(vm, address=9).ok(10, 66, 0) == 9


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


def test_stgp_stores_the_address_given_to_the_constructor(tmp_path):
    """TMCM-6212 3.6.9 STGP: "stores a global parameter ... permanently"; VirtualModule(address=...)
    sets GP66 in RAM only (docs/assumptions.md), so STGP 66, 0 writes it: a module built from
    that EEPROM without an address answers at it."""
    ee = tmp_path / "ee.json"
    vm = VirtualModule("TMCM-6212", address=7, eeprom=ee)
    assert vm.stored_global(0, 66) is None
    Host(vm, address=7).ok(11, 66, 0)
    assert vm.stored_global(0, 66) == 7
    vm.close()
    again = VirtualModule("TMCM-6212", eeprom=ee)
    assert again.address == 7


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
