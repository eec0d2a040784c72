"""The named sets of commands in protocol/opcodes.py (issue 33: "No bare opcode sets remain outside
[the command table]"), each against the manual section its docstring quotes, written out here by
hand from the manuals."""
from __future__ import annotations

from opentmcl.protocol.opcodes import (
    ALWAYS_ANSWERED,
    AXIS_COMMANDS,
    MOTION_COMMANDS,
    PROGRAM_CONTROL,
    UNANSWERED,
    Op,
)


def test_axis_commands_are_those_whose_motor_field_selects_an_axis_whatever_the_type():
    """TMCM-6212 3.4.1 "<motor number>" in ROR, ROL, MST, MVP, SAP, GAP, RFS, SCO, GCO, CCO, AAP,
    ACO (3.6.1-3.6.6, 3.6.11, 3.6.22-3.6.25, 3.6.27), STAP/RSAP (PD86-1180 4.6.7-4.6.8), MVPA,
    ROLA, RORA (PD28-1021 3.5 Table 5). Not WAIT: its motor is an axis for POS, REFSW, LIMSW and
    RFS but not for TICKS (3.6.20); not SGP/GGP (a bank), not SIO/GIO (a bank)."""
    assert AXIS_COMMANDS == {Op.ROR, Op.ROL, Op.MST, Op.MVP, Op.SAP, Op.GAP, Op.STAP, Op.RSAP, Op.RFS,
                             Op.SCO, Op.GCO, Op.CCO, Op.AAP, Op.ACO, Op.MVPA, Op.ROLA, Op.RORA}
    assert Op.WAIT not in AXIS_COMMANDS and not {Op.SGP, Op.GGP, Op.SIO, Op.GIO} & AXIS_COMMANDS


def test_motion_commands_start_or_stop_a_motion():
    """TMCM-6212 3.6.1-3.6.4 rotate right, rotate left, motor stop, move to position; 3.6.11
    reference search; PD28-1021 3.5 Table 5 MVPA, ROLA, RORA. SAP (a parameter) is none."""
    assert MOTION_COMMANDS == {Op.ROR, Op.ROL, Op.MST, Op.MVP, Op.RFS, Op.MVPA, Op.ROLA, Op.RORA}
    assert Op.SAP not in MOTION_COMMANDS


def test_program_control_is_table_13_up_to_the_application_status():
    """TMCM-6212 3.6.36 Table 13: 128 stop, 129 run, 130 step, 131 reset application, 132 enter and
    133 exit download mode, 134 read program memory, 135 get application status; the last ones of
    the table, 136 firmware version and 137 factory settings, and 139 ASCII mode (PD86-1180 4.6.39)
    act on no program."""
    assert sorted(PROGRAM_CONTROL) == list(range(128, 136))
    assert not {Op.GET_FIRMWARE_VERSION, Op.RESTORE_FACTORY_SETTINGS, Op.ENTER_ASCII_MODE} & PROGRAM_CONTROL


def test_only_137_goes_unanswered():
    """TMCM-6212 3.6.36 Table 13, 137: "This command does not send a reply"."""
    assert UNANSWERED == {Op.RESTORE_FACTORY_SETTINGS}


def test_gap_ggp_and_gio_are_always_answered():
    """TMCM-6212 5.1, GP255: "The reply will not be suppressed for GAP, GGP and GIO commands"."""
    assert ALWAYS_ANSWERED == {Op.GAP, Op.GGP, Op.GIO}
    assert Op.SAP not in ALWAYS_ANSWERED and Op.GCO not in ALWAYS_ANSWERED
