"""What each command's fields name (`Command.meanings`), against the manuals' command overviews.

The overview tables list each command's operands by what they name: TMCM-6212 manual 3.4.1
("Overview of all TMCL Commands"), PD86-1180 manual 4.4.1 (STAP, RSAP) and PD28-1021 manual 3.5
Table 5 (MVPA, ROLA, RORA). The i-th operand there is the i-th field of the command's canonical
operand form. Issue 33: "No bare opcode sets remain outside [the command table]" - the module
checks read this data instead of their own sets of opcode numbers.
"""
from __future__ import annotations

import pytest

from opentmcl.protocol.opcodes import (
    AXIS,
    AXIS_PARAMETER,
    COMMANDS,
    COORDINATE,
    GLOBAL_PARAMETER,
    INTERRUPT,
    MOTOR,
    PORT,
    TYPE,
    VALUE,
    MvpType,
    WaitCondition,
    by_mnemonic,
)

# The "Parameter" column of the overviews, as printed.
OVERVIEW = {
    # TMCM-6212 3.4.1
    "ROR": "<motor number>, <velocity>",
    "ROL": "<motor number>, <velocity>",
    "MST": "<motor number>",
    "MVP": "ABS REL COORD, <motor number>, <position offset>",
    "SAP": "<parameter>, <motor number>, <value>",
    "GAP": "<parameter>, <motor number>",
    "SGP": "<parameter>, <bank number>, <value>",
    "GGP": "<parameter>, <bank number>",
    "STGP": "<parameter>, <bank number>",
    "RSGP": "<parameter>, <bank number>",
    "RFS": "<START STOP STATUS>, <motor number>",
    "SIO": "<port number>, <bank number>, <value>",
    "GIO": "<port number>, <bank number>",
    "CALC": "<operation>, <value>",
    "COMP": "<value>",
    "JC": "<condition>, <jump address>",
    "JA": "<jump address>",
    "CSUB": "<subroutine address>",
    "RSUB": "",
    "EI": "<interrupt number>",
    "DI": "<interrupt number>",
    "WAIT": "<condition>, <motor number>, <ticks>",
    "STOP": "",
    "SCO": "<coordinate number>, <motor number>, <position>",
    "GCO": "<coordinate number>, <motor number>",
    "CCO": "<coordinate number>, <motor number>",
    "CALCX": "<operation>",
    "AAP": "<parameter>, <motor number>",
    "AGP": "<parameter>, <bank number>",
    "CLE": "<flag>",
    "VECT": "<interrupt number>, <address>",
    "RETI": "",
    "ACO": "<coordinate number>, <motor number>",
    # PD86-1180 4.4.1
    "STAP": "<parameter>, <motor number>",
    "RSAP": "<parameter>, <motor number>",
    # PD28-1021 3.5 Table 5
    "MVPA": "ABS|REL|COORD, <motor number>",
    "ROLA": "<motor number>",
    "RORA": "<motor number>",
}

NAMES = {"<motor number>": AXIS, "<coordinate number>": COORDINATE, "<interrupt number>": INTERRUPT,
         "<port number>": PORT}


def from_overview(mnemonic: str) -> set[tuple[str, str]]:
    """(field, what it names) read off the overview's operand list."""
    operands = [p.strip() for p in OVERVIEW[mnemonic].split(",") if p.strip()]
    form = by_mnemonic(mnemonic).operands
    out = set()
    for i, (fld, text) in enumerate(zip(form, operands, strict=True)):
        if text in NAMES:
            out.add((fld, NAMES[text]))
        elif text == "<parameter>":  # an axis parameter of a motor, a global one of a bank
            out.add((fld, AXIS_PARAMETER if operands[i + 1] == "<motor number>" else GLOBAL_PARAMETER))
    return out


@pytest.mark.parametrize("mnemonic", sorted(OVERVIEW))
def test_meanings_are_the_overviews_operands(mnemonic):
    """Every operand the overview names as a motor, parameter, port, coordinate or interrupt
    number is a meaning of that field, and the command has no other meaning with every type."""
    cmd = by_mnemonic(mnemonic)
    always = {(m.field, m.names) for m in cmd.meanings if m.types is None}
    by_type = {(m.field, m.names) for m in cmd.meanings if m.types is not None}
    assert always | by_type >= from_overview(mnemonic)
    assert always <= from_overview(mnemonic)


def test_every_command_with_meanings_is_in_an_overview():
    """No meaning without a manual line behind it."""
    assert {c.mnemonic for c in COMMANDS.values() if c.meanings} <= set(OVERVIEW)


def test_wait_names_a_motor_only_for_the_conditions_on_a_motor():
    """TMCM-6212 3.6.20: the motor field is "<motor number>" for POS, REFSW, LIMSW and RFS and
    "0 (don't care)" for TICKS."""
    wait = by_mnemonic("WAIT")
    assert {c for c in WaitCondition if wait.naming(AXIS, c)} == {
        WaitCondition.POS, WaitCondition.REFSW, WaitCondition.LIMSW, WaitCondition.RFS}
    assert wait.naming(AXIS, WaitCondition.TICKS) is None
    assert wait.naming(AXIS, 5) is None  # the first number after the last condition


def test_mvp_value_is_a_coordinate_only_with_coord():
    """TMCM-6212 3.6.4: with "2 - COORD" the value is "<coordinate number (0..20)>"; with ABS and
    REL a position or an offset."""
    mvp = by_mnemonic("MVP")
    meaning = mvp.naming(COORDINATE, MvpType.COORD)
    assert meaning is not None and meaning.field == VALUE
    assert mvp.naming(COORDINATE, MvpType.ABS) is None and mvp.naming(COORDINATE, MvpType.REL) is None
    assert mvp.naming(AXIS, MvpType.COORD).field == MOTOR


@pytest.mark.parametrize(("mnemonic", "access"), [
    ("SAP", "W"), ("AAP", "W"), ("GAP", "R"), ("STAP", "E"), ("RSAP", "E"),
    ("SGP", "W"), ("AGP", "W"), ("GGP", "R"), ("STGP", "E"), ("RSGP", "E"),
])
def test_parameter_access(mnemonic, access):
    """TMCM-6212 3.6.5-3.6.10, 3.6.27-3.6.28, PD86-1180 4.6.7-4.6.8: SAP/SGP and AAP/AGP write a
    parameter, GAP/GGP read it, STAP/STGP and RSAP/RSGP store it to or restore it from EEPROM."""
    cmd = by_mnemonic(mnemonic)
    meaning = cmd.naming(AXIS_PARAMETER, 0) or cmd.naming(GLOBAL_PARAMETER, 0)
    assert meaning is not None and meaning.field == TYPE and meaning.access == access


def test_255_names_all_ports_all_interrupts_and_the_coordinate_copy():
    """PD86-1180 4.6.14-4.6.15: port 255 is all ports of a bank (docs/assumptions.md "Port 255");
    TMCM-6212 3.6.30-3.6.31: "Interrupt number 255 globally enables [disables] interrupt
    processing"; 3.6.22-3.6.23: "SCO 0, 255, 0 copies all coordinates ... to
    the EEPROM" (GCO likewise from it). VECT, CCO and ACO have no such value."""
    special = {(c.mnemonic, m.names, m.special) for c in COMMANDS.values() for m in c.meanings
               if m.special is not None}
    assert special == {("SIO", PORT, 255), ("GIO", PORT, 255), ("EI", INTERRUPT, 255),
                       ("DI", INTERRUPT, 255), ("SCO", AXIS, 255), ("GCO", AXIS, 255)}


def test_only_sio_needs_a_writable_port():
    """3.6.12 SIO sets an output; 3.6.13 GIO reads inputs and outputs alike."""
    assert by_mnemonic("SIO").naming(PORT, 0).access == "W"
    assert by_mnemonic("GIO").naming(PORT, 0).access == ""

