"""The reply to a command stored in download mode, left unpinned by the firmware mutation sample
(docs/mutation.md, `program.store_instruction__mutmut_18`)."""
from __future__ import annotations


def test_a_stored_command_answers_status_101_with_value_0(anymod):
    """TMCM-6212 manual 3.6.36: "132 - enter download mode  All following commands (except control
    commands) are not executed but stored in the TMCL memory"; 3.2.1 Table 4 "101 Command loaded
    into TMCL program EEPROM". The manuals give no value for that reply: docs/assumptions.md
    ("Download mode") reads it as 0, whatever the stored value (1234, the largest and the smallest
    32-bit value, -1), while the stored instruction keeps its own value (3.6.36 "134 - read
    program memory", special reply: host address, command, type, motor, value MSB first)."""
    values = (1234, 2**31 - 1, -2**31, -1)
    anymod.ok(132, 0, 0, 0)
    for value in values:
        reply = anymod(5, 4, 0, value)
        assert (reply.status, reply.command, reply.value) == (101, 5, 0)
    anymod.ok(133)
    for address, value in enumerate(values):
        raw = anymod.raw(134, 0, 0, address)
        assert len(raw) == 9 and raw[1:4] == bytes((5, 4, 0))
        assert int.from_bytes(raw[4:8], "big", signed=True) == value
