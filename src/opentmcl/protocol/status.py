"""TMCL status codes (TMCM-6212 manual 3.2.1, PD86-1180 manual 4.2)."""
from __future__ import annotations

from enum import IntEnum


class Status(IntEnum):
    """Reply status codes. 100/101 mean success; 128 is the event reply of command 138."""

    OK = 100
    LOADED = 101
    WRONG_CHECKSUM = 1
    INVALID_COMMAND = 2
    WRONG_TYPE = 3
    INVALID_VALUE = 4
    EEPROM_LOCKED = 5
    NOT_AVAILABLE = 6
    POSITION_REACHED_EVENT = 128


MESSAGES: dict[int, str] = {
    100: "Successfully executed, no error",
    101: "Command loaded into TMCL program EEPROM",
    1: "Wrong checksum",
    2: "Invalid command",
    3: "Wrong type",
    4: "Invalid value",
    5: "Configuration EEPROM locked",
    6: "Command not available",
    128: "Target position reached",
}


def is_success(status: int) -> bool:
    return status in (Status.OK, Status.LOADED, Status.POSITION_REACHED_EVENT)


def message(status: int) -> str:
    return MESSAGES.get(status, f"Unknown status {status}")
