"""Review of issue 16 (found by the differential run): a module whose address has no ASCII address
character ignores every ASCII line instead of raising.

PD28-1021 manual 3.4.1: "As the first character, the address character has to be sent. The address
character is A when the module address is 1, B for modules with address 2 and so on." Global
parameter 66 takes 0..255, so a module at 0 or 27..255 has no character: no line is addressed to it.
"""
from __future__ import annotations

import pytest

from opentmcl import VirtualModule


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
