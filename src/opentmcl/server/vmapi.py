"""What the endpoints read from a virtual module besides `handle`/`advance`.

The endpoints need a few global parameters of bank 0 (TMCM-6212 manual 5.1):
65 RS485 baud rate, 66 serial address, 70 CAN reply ID, 71 CAN ID,
75 telegram pause time, 83 CAN secondary address. They read them through
`VirtualModule.globals.get_raw(bank, number)` (the RAM value without access
checks, which does not count as host traffic for the heartbeat GP68/GP82);
for other module-like objects through a GGP request (manual 3.6.8).
"""
from __future__ import annotations

from collections.abc import Callable
from functools import partial

from ..protocol.frame import FRAME_LEN, Reply, Request
from ..protocol.opcodes import Op

GP_BAUD_RATE = 65
GP_SERIAL_ADDRESS = 66
GP_SERIAL_HEARTBEAT = 68
GP_CAN_REPLY_ID = 70
GP_CAN_ID = 71
GP_TELEGRAM_PAUSE = 75
GP_HOST_ADDRESS = 76
GP_CAN_HEARTBEAT = 82
GP_CAN_SECONDARY = 83
GP_SERIAL_SECONDARY = 87

BAUD_RATES = {0: 9600, 1: 14400, 2: 19200, 3: 28800, 4: 38400, 5: 57600, 6: 76800, 7: 115200,
              8: 230400, 9: 250000, 10: 500000, 11: 1000000}
"""Global parameter 65 (TMCM-6212 manual 5.1, table 16)."""

DEFAULTS = {GP_BAUD_RATE: 0, GP_SERIAL_ADDRESS: 1, GP_CAN_REPLY_ID: 2, GP_CAN_ID: 1,
            GP_TELEGRAM_PAUSE: 0, GP_CAN_SECONDARY: 0, GP_HOST_ADDRESS: 2}
"""The manual's defaults, used when a module does not know a parameter."""


def global_param(vm, number: int) -> int:
    """Value of global parameter `number` of bank 0 of `vm`."""
    table = getattr(vm, "globals", None)
    getter = getattr(table, "get_raw", None)
    if callable(getter):
        return int(getter(0, number))
    address = getattr(vm, "address", 1)
    reply = vm.handle(Request(address, Op.GGP, number, 0, 0).encode())
    if len(reply) != FRAME_LEN:
        return DEFAULTS.get(number, 0)
    decoded = Reply.decode(reply, verify=False)
    if decoded.status != 100:
        return DEFAULTS.get(number, 0)
    return decoded.value


def raw_reader(vm) -> Callable[[int], int] | None:
    """A fast `number -> value` reader of bank-0 parameters of `vm`, or None when `vm` does not
    expose `globals.get_raw` (then use `global_param`, which asks with GGP)."""
    getter = getattr(getattr(vm, "globals", None), "get_raw", None)
    if not callable(getter):
        return None
    return partial(getter, 0)


def baud_rate(vm) -> int:
    """Bits per second of the module's serial interface (GP 65)."""
    return BAUD_RATES.get(global_param(vm, GP_BAUD_RATE), 9600)


def set_global_ram(vm, number: int, value: int) -> None:
    """Set bank-0 parameter `number` in RAM only (not stored to the EEPROM file).

    Used by the server to give several modules on one CAN bus distinct CAN IDs
    (GP 71) without rewriting their EEPROM; needs `vm.globals.ram`.
    """
    table = getattr(vm, "globals", None)
    ram = getattr(table, "ram", None)
    if not isinstance(ram, dict):
        raise TypeError(f"{type(vm).__name__} does not expose its global parameters")
    ram[(0, number)] = value
