"""The one rule for the module addresses of a bus, shared by `opentmcl serve`, ``sim://`` and
``opentmcl://`` URLs: every address is 1..255 (global parameter 66, TMCM-6212 manual 5.1) and no
two modules on one bus share one, since a request to a shared address would be answered twice
(manual 3.1: the address byte selects the module)."""
from __future__ import annotations

ADDRESSES = range(1, 256)


def address_error(addresses: list[int]) -> str | None:
    """Why `addresses` cannot share one bus, in one line, or None when they can."""
    for address in addresses:
        if address not in ADDRESSES:
            return f"module address must be 1..255 (manual 5.1, parameter 66), got {address}"
    if len(set(addresses)) != len(addresses):
        return f"module addresses must be distinct on one bus, got {list(addresses)}"
    return None
