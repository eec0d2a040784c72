"""Register-exact model of the TMC4210 single-axis motion controller (TMC4210 datasheet).

    from opentmcl.chips.tmc4210 import TMC4210
    chip = TMC4210(f_clk=16_000_000)
    back = chip.spi(0x1A000123)
    chip.advance(0.01)

See docs/tmc4210.md.
"""
from typing import TYPE_CHECKING

from .registers import (
    INTERRUPTS,
    REGISTERS,
    TYPE_VERSION_4210,
    Datagram,
    DatagramError,
    RegisterError,
    describe_reply,
    describe_request,
    read_datagram,
    write_datagram,
)
from .stepdir import Edge

if TYPE_CHECKING:  # loaded lazily at run time (__getattr__)
    from .chip import TMC4210, ChipError

__all__ = ["TMC4210", "ChipError", "Datagram", "DatagramError", "Edge", "INTERRUPTS", "REGISTERS",
           "RegisterError", "TYPE_VERSION_4210", "describe_reply", "describe_request", "read_datagram",
           "write_datagram"]


def __getattr__(name: str) -> type:  # the chip pulls in the ramp core; registers and units stand alone
    if name in ("TMC4210", "ChipError"):
        from . import chip
        return getattr(chip, name)
    raise AttributeError(name)
