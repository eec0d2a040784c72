"""The opcode table against the manuals' command overviews."""
from __future__ import annotations

import pytest

from opentmcl.protocol import opcodes
from opentmcl.protocol.opcodes import (
    CALC_OPS,
    CALCX_OPS,
    CLE_FLAGS,
    JC_CONDITIONS,
    MVP_TYPES,
    RFS_TYPES,
    WAIT_CONDITIONS,
    OperandError,
    UnknownCommand,
    by_mnemonic,
    by_number,
    format_instruction,
    parse_instruction,
)
from opentmcl.protocol.status import MESSAGES, Status, is_success, message

# TMCM-6212 manual 3.4.1 Table 5 plus PD86-1180 4.4.1 (STAP 7, RSAP 8).
OVERVIEW = {
    "ROR": 1, "ROL": 2, "MST": 3, "MVP": 4, "SAP": 5, "GAP": 6, "STAP": 7, "RSAP": 8, "SGP": 9,
    "GGP": 10, "STGP": 11, "RSGP": 12, "RFS": 13, "SIO": 14, "GIO": 15, "CALC": 19, "COMP": 20,
    "JC": 21, "JA": 22, "CSUB": 23, "RSUB": 24, "EI": 25, "DI": 26, "WAIT": 27, "STOP": 28,
    "SCO": 30, "GCO": 31, "CCO": 32, "CALCX": 33, "AAP": 34, "AGP": 35, "CLE": 36, "VECT": 37,
    "RETI": 38, "ACO": 39,
}
# PD28-1021 manual 3.5 Table 5 (extended set).
EXTENDED = {
    "CALCVV": 40, "CALCVA": 41, "CALCAV": 42, "CALCVX": 43, "CALCXV": 44, "CALCV": 45, "MVPA": 46,
    "RST": 48, "DJNZ": 49, "ROLA": 50, "RORA": 51, "SIV": 55, "GIV": 56, "AIV": 57,
}


@pytest.mark.parametrize(("mnemonic", "number"), sorted({**OVERVIEW, **EXTENDED}.items()))
def test_overview_numbers(mnemonic, number):
    """TMCM-6212 3.4.1 / PD86-1180 4.4.1 / PD28-1021 3.5: mnemonic <-> command number."""
    assert by_mnemonic(mnemonic).number == number
    assert by_number(number).mnemonic == mnemonic
    assert by_mnemonic(mnemonic.lower()) is by_number(number)


def test_user_functions_and_control_commands():
    """TMCM-6212 3.6.34: UF0..UF7 are 64..71; 3.6.36: control commands 128..137 have no mnemonic and
    cannot appear in a program; 3.6.35: 138 likewise; PD86-1180 4.4.2.7: 139 enters ASCII mode."""
    for i in range(8):
        assert by_mnemonic(f"uf{i}").number == 64 + i
    for n in range(128, 140):
        cmd = by_number(n)
        assert cmd.mnemonic is None and not cmd.program and cmd.direct
    assert opcodes.ENTER_ASCII_MODE == 139 and opcodes.RUN_APPLICATION == 129


@pytest.mark.parametrize(("mnemonic", "form"), [
    ("ROR", ("motor", "value")), ("ROL", ("motor", "value")), ("MST", ("motor",)),
    ("MVP", ("type", "motor", "value")), ("SAP", ("type", "motor", "value")), ("GAP", ("type", "motor")),
    ("SGP", ("type", "motor", "value")), ("GGP", ("type", "motor")), ("RFS", ("type", "motor")),
    ("SIO", ("type", "motor", "value")), ("GIO", ("type", "motor")), ("CALC", ("type", "value")),
    ("COMP", ("value",)), ("JC", ("type", "value")), ("JA", ("value",)), ("CSUB", ("value",)),
    ("RSUB", ()), ("EI", ("type",)), ("DI", ("type",)), ("WAIT", ("type", "motor", "value")),
    ("STOP", ()), ("SCO", ("type", "motor", "value")), ("GCO", ("type", "motor")),
    ("CALCX", ("type",)), ("CLE", ("type",)), ("VECT", ("type", "value")), ("RETI", ()),
    ("CALCVV", ("type", "motor", "value")), ("MVPA", ("type", "motor")), ("RST", ("value",)),
    ("DJNZ", ("type", "value")), ("ROLA", ("motor",)), ("SIV", ("value",)), ("GIV", ()),
])
def test_canonical_operand_forms(mnemonic, form):
    """Each command's "Mnemonic:" line (TMCM-6212 3.6.x) and PD28-1021 Table 5 operand order."""
    assert by_mnemonic(mnemonic).operands == form


def test_symbol_tables():
    """Symbolic types: MVP 3.6.4, RFS 3.6.11, CALC 3.6.14, JC 3.6.16 (+ESD 12, PD86-1180 4.6.18),
    WAIT 3.6.20, CALCX 3.6.26 (SWAP 10), CLE 3.6.29."""
    assert dict(MVP_TYPES) == {"ABS": 0, "REL": 1, "COORD": 2}
    assert dict(RFS_TYPES) == {"START": 0, "STOP": 1, "STATUS": 2}
    assert list(CALC_OPS) == ["ADD", "SUB", "MUL", "DIV", "MOD", "AND", "OR", "XOR", "NOT", "LOAD"]
    assert list(CALC_OPS.values()) == list(range(10)) and "SWAP" not in CALC_OPS
    assert CALCX_OPS["SWAP"] == 10 and CALCX_OPS["LOAD"] == 9
    assert JC_CONDITIONS == {"ZE": 0, "NZ": 1, "EQ": 2, "NE": 3, "GT": 4, "GE": 5, "LT": 6, "LE": 7,
                             "ETO": 8, "EAL": 9, "EDV": 10, "EPO": 11, "ESD": 12}
    assert dict(WAIT_CONDITIONS) == {"TICKS": 0, "POS": 1, "REFSW": 2, "LIMSW": 3, "RFS": 4}
    assert dict(CLE_FLAGS) == {"ALL": 0, "ETO": 1, "EAL": 2, "EDV": 3, "EPO": 4, "ESD": 5}


def test_symbols_apply_only_to_their_command():
    """CALC has no SWAP (3.6.14 lists 0..9); CALCX has it (3.6.26)."""
    assert parse_instruction("CALCX SWAP") == (33, 10, 0, 0)
    with pytest.raises(OperandError):
        parse_instruction("CALC SWAP, 1")
    with pytest.raises(OperandError):
        parse_instruction("MVP TICKS, 0, 1")


def test_unknown_and_malformed():
    with pytest.raises(UnknownCommand, match="unknown TMCL mnemonic"):
        by_mnemonic("FOO")
    with pytest.raises(UnknownCommand, match="200"):
        by_number(200)
    with pytest.raises(OperandError, match="expected MVP"):
        parse_instruction("MVP ABS, 0")
    with pytest.raises(OperandError, match="0..255"):
        parse_instruction("SAP 256, 0, 1")
    with pytest.raises(OperandError, match="32-bit"):
        parse_instruction("SAP 4, 0, 4294967296")


def test_hex_and_negative_literals():
    """Values are signed 32 bit (TMCM-6212 3.6.4: -2147483648..2147483647); hex wraps like C."""
    assert parse_instruction("MVP ABS, 0, 0xFFFFFFFF") == (4, 0, 0, -1)
    assert parse_instruction("MVP ABS, 0, $10") == (4, 0, 0, 16)
    assert parse_instruction("MVP ABS, 0, -2147483648") == (4, 0, 0, -2147483648)


def test_format_uses_symbols_and_falls_back():
    assert format_instruction(27, 0, 0, 500) == "WAIT TICKS, 0, 500"
    assert format_instruction(4, 7, 0, 1) == "MVP 7, 0, 1"  # no symbol for type 7
    assert format_instruction(6, 1, 0, 5) == "GAP 1, 0, 5"  # don't-care value kept
    assert format_instruction(24, 0, 1, 0) is None  # RSUB cannot carry a motor
    assert format_instruction(136, 0, 0, 0) is None  # control command: no mnemonic


def test_status_codes():
    """TMCM-6212 3.2.1 Table 4 (and PD86-1180 4.2.1): all status codes and their meanings."""
    table = {100: "Successfully executed, no error", 101: "Command loaded into TMCL program EEPROM",
             1: "Wrong checksum", 2: "Invalid command", 3: "Wrong type", 4: "Invalid value",
             5: "Configuration EEPROM locked", 6: "Command not available"}
    for code, text in table.items():
        assert message(code) == text == MESSAGES[code]
        assert Status(code) == code
        assert is_success(code) == (code >= 100)
    assert Status.POSITION_REACHED_EVENT == 128  # 3.6.35 additional reply


def test_every_profile_opcode_is_in_the_table():
    """Each module profile's opcode list (modules/data/*.toml) names only commands of the table."""
    from opentmcl.modules.profile import load_profile, module_names
    for name in module_names():
        for number in load_profile(name).opcodes:
            assert by_number(number).number == number, (name, number)


def test_every_command_has_its_name_in_op():
    """TMCM-6212 3.5 and PD86-1180 4.5 list the commands by mnemonic and number; 3.6.36 and 4.6.39
    the control commands 128-139 by name. `Op` names each command of `COMMANDS` once: by its
    mnemonic where it has one (ROR 1, MST 3, SAP 5, GAP 6, RETI 38, CALL 80), and nothing else."""
    from opentmcl.protocol.opcodes import COMMANDS, Op

    assert sorted(Op) == sorted(COMMANDS)
    for number, command in COMMANDS.items():
        if command.mnemonic is not None:
            assert Op(number).name == command.mnemonic, number
    assert (Op.ROR, Op.MST, Op.SAP, Op.GAP, Op.RETI, Op.CALL) == (1, 3, 5, 6, 38, 80)
    assert (Op.STOP_APPLICATION, Op.ENTER_DOWNLOAD_MODE, Op.REQUEST_TARGET_REACHED_EVENT) == (128, 132, 138)
