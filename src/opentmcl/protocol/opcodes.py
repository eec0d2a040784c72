"""The TMCL command set as data: numbers, mnemonics, operand forms, symbolic operands.

Sources: TMCM-6212 manual 3.4.1 (overview), 3.6.1-3.6.36 (each command's "Mnemonic:" line and
binary representation); PD86-1180 manual 4.4.1, 4.6.1-4.6.39; PD28-1021 manual 3.5 (overview of the
extended command set 40-57). The PD28-1021 manual is cut off before its detailed descriptions: the
field mapping of the extended commands is inferred from the overview's operand order (see
docs/assumptions.md).

An operand form is the order in which the binary fields appear in TMCL-IDE source, e.g.
``MVP ABS, 0, 1000`` is ``("type", "motor", "value")`` and ``ROL 0, 500`` is ``("motor", "value")``.
A command may have several accepted forms (``GAP 1, 0`` and ``GAP 1, 0, 0`` both appear in the
manuals); the first one is canonical. Fields absent from the form used are 0.
"""
from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from enum import IntEnum
from types import MappingProxyType

from ..limits import LiteralTooLong, check_literal
from .frame import to_int32

TYPE, MOTOR, VALUE = "type", "motor", "value"
FIELDS = (TYPE, MOTOR, VALUE)


# --- symbolic operands -------------------------------------------------------------------------

class MvpType(IntEnum):
    """MVP / MVPA type field (TMCM-6212 3.6.4)."""
    ABS = 0
    REL = 1
    COORD = 2


class RfsType(IntEnum):
    """RFS type field (TMCM-6212 3.6.11)."""
    START = 0
    STOP = 1
    STATUS = 2


class CalcOp(IntEnum):
    """CALC operations (TMCM-6212 3.6.14); CALCX adds SWAP (3.6.26)."""
    ADD = 0
    SUB = 1
    MUL = 2
    DIV = 3
    MOD = 4
    AND = 5
    OR = 6
    XOR = 7
    NOT = 8
    LOAD = 9
    SWAP = 10


class Condition(IntEnum):
    """JC conditions (TMCM-6212 3.6.16: 0-11; PD86-1180 4.6.18 adds ESD = 12)."""
    ZE = 0
    NZ = 1
    EQ = 2
    NE = 3
    GT = 4
    GE = 5
    LT = 6
    LE = 7
    ETO = 8
    EAL = 9
    EDV = 10
    EPO = 11
    ESD = 12


class WaitCondition(IntEnum):
    """WAIT conditions (TMCM-6212 3.6.20). One tick is 10 ms."""
    TICKS = 0
    POS = 1
    REFSW = 2
    LIMSW = 3
    RFS = 4


class ErrorFlag(IntEnum):
    """CLE flags (TMCM-6212 3.6.29)."""
    ALL = 0
    ETO = 1
    EAL = 2
    EDV = 3
    EPO = 4
    ESD = 5


def _names(enum: type[IntEnum], only: tuple[str, ...] | None = None) -> Mapping[str, int]:
    return MappingProxyType({m.name: int(m) for m in enum if only is None or m.name in only})


MVP_TYPES = _names(MvpType)
RFS_TYPES = _names(RfsType)
CALC_OPS = _names(CalcOp, tuple(n for n in CalcOp.__members__ if n != "SWAP"))
CALCX_OPS = _names(CalcOp)
JC_CONDITIONS = _names(Condition)
WAIT_CONDITIONS = _names(WaitCondition)
CLE_FLAGS = _names(ErrorFlag)

# Symbol tables by the name used in Command.symbols.
SYMBOL_TABLES: Mapping[str, Mapping[str, int]] = MappingProxyType({
    "mvp": MVP_TYPES, "rfs": RFS_TYPES, "calc": CALC_OPS, "calcx": CALCX_OPS,
    "jc": JC_CONDITIONS, "wait": WAIT_CONDITIONS, "cle": CLE_FLAGS,
})


# --- what a field names --------------------------------------------------------------------------

AXIS = "motor number"
"""The field selects a motor (an axis): TMCM-6212 3.4.1 "<motor number>"."""
AXIS_PARAMETER = "axis parameter"
"""The field numbers an axis parameter of the motor the motor field selects (3.6.5-3.6.6)."""
GLOBAL_PARAMETER = "global parameter"
"""The field numbers a global parameter in the bank the motor field gives (3.6.7-3.6.10);
bank 2 holds the user variables."""
PORT = "port number"
"""The field numbers an I/O port in the bank the motor field gives (3.6.12-3.6.13)."""
COORDINATE = "coordinate number"
"""The field numbers a coordinate (3.6.4 MVP COORD, 3.6.22-3.6.25)."""
INTERRUPT = "interrupt number"
"""The field numbers an interrupt (3.6.30 EI, 3.6.31 DI, 3.6.32 VECT)."""


@dataclass(frozen=True)
class Meaning:
    """What one field of a command names, from the command's description in the manuals.

    `field` is TYPE, MOTOR or VALUE; `names` is AXIS, AXIS_PARAMETER, GLOBAL_PARAMETER, PORT,
    COORDINATE or INTERRUPT. `access` is what the command does to the parameter or port it names:
    "W" writes it, "R" reads it, "E" stores it to or restores it from EEPROM ("": not checked).
    `types` limits the meaning to these values of the type field (WAIT waits on a motor only for
    POS, REFSW, LIMSW and RFS, 3.6.20; MVP's value is a coordinate only with COORD, 3.6.4); None:
    with every type. `special` is a value of the field that names none of them: 255 for all ports
    (SIO/GIO, PD86-1180 4.6.14-4.6.15), all interrupts (EI/DI, 3.6.30-3.6.31) or, in SCO/GCO's
    motor field, the copy of coordinates between RAM and EEPROM (3.6.22-3.6.23).
    """

    field: str
    names: str
    access: str = ""
    types: frozenset[int] | None = None
    special: int | None = None

    def applies(self, type: int) -> bool:
        """Does the field have this meaning when the type field is `type`?"""
        return self.types is None or type in self.types


# --- commands ----------------------------------------------------------------------------------

@dataclass(frozen=True)
class Command:
    """One TMCL command.

    `forms` lists the accepted source operand orders (first = canonical); `symbols` names the
    symbol table of the type field (a key of SYMBOL_TABLES) or is empty; `label` is True when the
    value field is a program address (JA, JC, CSUB, VECT, ...). `program` is False for the commands
    of direct mode only (the control commands, TMCM-6212 3.6.36, and 138, 3.6.35); `control` marks
    the control commands of the manuals' tables (128-137, TMCM-6212 Table 13; PD86-1180 4.6.39 adds
    139), which download mode executes instead of storing; `direct` is False for the commands the manuals
    call "intended for standalone mode only" (informational: whether a firmware rejects them in
    direct mode is the firmware's decision). `mnemonic` is None for control commands.
    """

    number: int
    mnemonic: str | None
    title: str
    forms: tuple[tuple[str, ...], ...] = ((),)
    symbols: str = ""
    label: bool = False
    program: bool = True
    control: bool = False
    direct: bool = True
    source: str = "TMCM-6212"
    keeps_address: bool = False
    """The command cannot change the module's addresses (GP66, GP87, host GP76), its reply
    suppression (GP255) or its serial mode (ASCII, download): motion, axis parameters, reads,
    EEPROM stores, I/O, coordinates, status and version. SGP keeps them only outside bank 0."""
    replies: bool = True
    """False for the one command the module answers with no reply (137, 3.6.36)."""
    notes: str = field(default="", compare=False)
    meanings: tuple[Meaning, ...] = ()
    """What its fields name (motors, parameters, ports, coordinates, interrupts), for checks
    against a module (lang/capabilities_check.py)."""

    @property
    def operands(self) -> tuple[str, ...]:
        """The canonical operand form."""
        return self.forms[0]

    def symbol_table(self) -> Mapping[str, int]:
        return SYMBOL_TABLES.get(self.symbols, MappingProxyType({}))

    def naming(self, names: str, type: int) -> Meaning | None:
        """The meaning by which one of its fields names `names` (AXIS, COORDINATE, ...) when the
        type field is `type`, or None."""
        for meaning in self.meanings:
            if meaning.names == names and meaning.applies(type):
                return meaning
        return None

    def form_for(self, count: int) -> tuple[str, ...] | None:
        """The accepted form with `count` operands, or None."""
        for form in self.forms:
            if len(form) == count:
                return form
        return None

    def usage(self) -> str:
        """Human-readable accepted forms, for error messages: 'MVP <type>, <motor>, <value>'."""
        out = []
        for form in self.forms:
            names = ", ".join(self._placeholder(f) for f in form)
            out.append(f"{self.mnemonic} {names}".rstrip())
        return " or ".join(out)

    def _placeholder(self, fld: str) -> str:
        if fld == TYPE and self.symbols:
            return "|".join(self.symbol_table())
        if fld == VALUE and self.label:
            return "<label>"
        return f"<{fld}>"


T, M, V = TYPE, MOTOR, VALUE
_ON_AXIS = (Meaning(M, AXIS),)
_COORDINATE_ON_AXIS = (Meaning(T, COORDINATE), Meaning(M, AXIS))
_COPY_OR_COORDINATE_ON_AXIS = (Meaning(T, COORDINATE), Meaning(M, AXIS, special=255))


def _axis_parameter(access: str) -> tuple[Meaning, ...]:
    return Meaning(T, AXIS_PARAMETER, access), Meaning(M, AXIS)


def _global_parameter(access: str) -> tuple[Meaning, ...]:
    return (Meaning(T, GLOBAL_PARAMETER, access),)


_COMMANDS: tuple[Command, ...] = (
    # Motion, parameter and I/O commands (TMCM-6212 3.6.1-3.6.13, PD86-1180 4.6.1-4.6.15).
    Command(1, "ROR", "Rotate right", ((M, V),), keeps_address=True, meanings=_ON_AXIS),
    Command(2, "ROL", "Rotate left", ((M, V),), keeps_address=True, meanings=_ON_AXIS),
    Command(3, "MST", "Motor stop", ((M,), (M, V)), keeps_address=True, meanings=_ON_AXIS),
    Command(4, "MVP", "Move to position", ((T, M, V),), symbols="mvp", keeps_address=True,
            meanings=(Meaning(M, AXIS), Meaning(V, COORDINATE, types=frozenset({MvpType.COORD})))),
    Command(5, "SAP", "Set axis parameter", ((T, M, V),), keeps_address=True, meanings=_axis_parameter("W")),
    Command(6, "GAP", "Get axis parameter", ((T, M), (T, M, V)), keeps_address=True,
            meanings=_axis_parameter("R")),
    Command(7, "STAP", "Store axis parameter", ((T, M), (T, M, V)), source="PD86-1180", keeps_address=True,
            meanings=_axis_parameter("E")),
    Command(8, "RSAP", "Restore axis parameter", ((T, M), (T, M, V)), source="PD86-1180", keeps_address=True,
            meanings=_axis_parameter("E")),
    Command(9, "SGP", "Set global parameter", ((T, M, V),), keeps_address=True, meanings=_global_parameter("W")),
    Command(10, "GGP", "Get global parameter", ((T, M), (T, M, V)), keeps_address=True,
            meanings=_global_parameter("R")),
    Command(11, "STGP", "Store global parameter", ((T, M), (T, M, V)), keeps_address=True,
            meanings=_global_parameter("E")),
    Command(12, "RSGP", "Restore global parameter", ((T, M), (T, M, V)), meanings=_global_parameter("E")),
    Command(13, "RFS", "Reference search", ((T, M), (T,)), symbols="rfs", keeps_address=True,
            meanings=_ON_AXIS),
    Command(14, "SIO", "Set output", ((T, M, V),), keeps_address=True,
            meanings=(Meaning(T, PORT, "W", special=255),)),
    Command(15, "GIO", "Get input", ((T, M), (T, M, V)), keeps_address=True,
            meanings=(Meaning(T, PORT, special=255),)),
    # Calculation and branch commands (3.6.14-3.6.21).
    Command(19, "CALC", "Calculate", ((T, V), (T,)), symbols="calc"),
    Command(20, "COMP", "Compare", ((V,),), direct=False),
    Command(21, "JC", "Jump conditional", ((T, V),), symbols="jc", label=True, direct=False),
    Command(22, "JA", "Jump always", ((V,),), label=True, direct=False),
    Command(23, "CSUB", "Call subroutine", ((V,),), label=True, direct=False),
    Command(24, "RSUB", "Return from subroutine", ((),), direct=False),
    Command(25, "EI", "Enable interrupt", ((T,),), meanings=(Meaning(T, INTERRUPT, special=255),)),
    Command(26, "DI", "Disable interrupt", ((T,),), meanings=(Meaning(T, INTERRUPT, special=255),)),
    Command(27, "WAIT", "Wait for an event", ((T, M, V),), symbols="wait", direct=False,
            meanings=(Meaning(M, AXIS, types=frozenset(WaitCondition) - {WaitCondition.TICKS}),)),
    Command(28, "STOP", "Stop TMCL program execution", ((),), direct=False),
    # Coordinates, X register, accumulator transfers, interrupts (3.6.22-3.6.33).
    Command(30, "SCO", "Set coordinate", ((T, M, V),), keeps_address=True,
            meanings=_COPY_OR_COORDINATE_ON_AXIS),
    Command(31, "GCO", "Get coordinate", ((T, M), (T, M, V)), keeps_address=True,
            meanings=_COPY_OR_COORDINATE_ON_AXIS),
    Command(32, "CCO", "Capture coordinate", ((T, M), (T, M, V)), keeps_address=True,
            meanings=_COORDINATE_ON_AXIS),
    Command(33, "CALCX", "Calculate using the X register", ((T,),), symbols="calcx"),
    Command(34, "AAP", "Accu to axis parameter", ((T, M), (T, M, V)), meanings=_axis_parameter("W")),
    Command(35, "AGP", "Accu to global parameter", ((T, M), (T, M, V)), meanings=_global_parameter("W")),
    Command(36, "CLE", "Clear error flags", ((T,),), symbols="cle"),
    Command(37, "VECT", "Define interrupt vector", ((T, V),), label=True, direct=False,
            meanings=(Meaning(T, INTERRUPT),)),
    Command(38, "RETI", "Return from interrupt", ((),), direct=False),
    Command(39, "ACO", "Accu to coordinate", ((T, M), (T, M, V)), meanings=_COORDINATE_ON_AXIS),
    # PD28-1021 extended command set (PD28-1021 manual 3.5, Table 5).
    Command(40, "CALCVV", "Calculate using two user variables", ((T, M, V),), symbols="calcx",
            source="PD28-1021"),
    Command(41, "CALCVA", "Calculate using a user variable and the accumulator", ((T, M),),
            symbols="calcx", source="PD28-1021"),
    Command(42, "CALCAV", "Calculate using the accumulator and a user variable", ((T, M),),
            symbols="calcx", source="PD28-1021"),
    Command(43, "CALCVX", "Calculate using a user variable and the X register", ((T, M),),
            symbols="calcx", source="PD28-1021"),
    Command(44, "CALCXV", "Calculate using the X register and a user variable", ((T, M),),
            symbols="calcx", source="PD28-1021"),
    Command(45, "CALCV", "Calculate using a user variable and a direct value", ((T, M, V), (T, V)),
            symbols="calcx", source="PD28-1021"),
    Command(46, "MVPA", "Move to position specified by the accumulator", ((T, M),), symbols="mvp",
            source="PD28-1021", meanings=_ON_AXIS),
    Command(48, "RST", "Restart", ((V,),), label=True, direct=False, source="PD28-1021"),
    Command(49, "DJNZ", "Decrement and jump if not zero", ((T, V),), label=True, direct=False,
            source="PD28-1021"),
    Command(50, "ROLA", "Rotate left using the accumulator", ((M,),), source="PD28-1021",
            meanings=_ON_AXIS),
    Command(51, "RORA", "Rotate right using the accumulator", ((M,),), source="PD28-1021",
            meanings=_ON_AXIS),
    Command(55, "SIV", "Set indexed variable", ((V,),), source="PD28-1021"),
    Command(56, "GIV", "Get indexed variable", ((),), source="PD28-1021"),
    Command(57, "AIV", "Accumulator to indexed variable", ((),), source="PD28-1021"),
    Command(80, "CALL", "Conditional subroutine call", ((T, V),), symbols="jc", label=True,
            direct=False, source="PD28-1021",
            notes="number 80 from public TMCL headers; not in the cut-off manual's Table 5"),
    # User functions UF0..UF7 (TMCM-6212 3.6.34).
    *(Command(64 + i, f"UF{i}", f"User function {i}", ((T, M, V), (T, M), (T,), ()))
      for i in range(8)),
    # Control commands: direct mode only, no mnemonic (TMCM-6212 3.6.35, 3.6.36; PD86-1180 4.6.39).
    Command(128, None, "Stop application", program=False, control=True),
    Command(129, None, "Run application", program=False, control=True),
    Command(130, None, "Step application", program=False, control=True),
    Command(131, None, "Reset application", program=False, control=True),
    Command(132, None, "Enter download mode", program=False, control=True),
    Command(133, None, "Exit download mode", program=False, control=True),
    Command(134, None, "Read program memory", program=False, control=True),
    Command(135, None, "Get application status", program=False, control=True, keeps_address=True),
    Command(136, None, "Get firmware version", program=False, control=True, keeps_address=True),
    Command(137, None, "Restore factory settings", program=False, control=True, replies=False),
    Command(138, None, "Request target position reached event", program=False, keeps_address=True),
    Command(139, None, "Enter ASCII mode", program=False, control=True, source="PD86-1180"),
)

COMMANDS: Mapping[int, Command] = MappingProxyType({c.number: c for c in _COMMANDS})
_BY_MNEMONIC: Mapping[str, Command] = MappingProxyType({c.mnemonic: c for c in _COMMANDS if c.mnemonic})



class Op(IntEnum):
    """Every command number by its name: the mnemonic (TMCM-6212 3.5, PD86-1180 4.5) or, for the
    commands without one, the name of the manuals' control command table (TMCM-6212 3.6.36, 3.6.35,
    PD86-1180 4.6.39). Code outside this module names a command by `Op`, never by its number
    (tests/protocol/test_opcodes.py checks that `Op` and `COMMANDS` agree)."""

    ROR = 1
    ROL = 2
    MST = 3
    MVP = 4
    SAP = 5
    GAP = 6
    STAP = 7
    RSAP = 8
    SGP = 9
    GGP = 10
    STGP = 11
    RSGP = 12
    RFS = 13
    SIO = 14
    GIO = 15
    CALC = 19
    COMP = 20
    JC = 21
    JA = 22
    CSUB = 23
    RSUB = 24
    EI = 25
    DI = 26
    WAIT = 27
    STOP = 28
    SCO = 30
    GCO = 31
    CCO = 32
    CALCX = 33
    AAP = 34
    AGP = 35
    CLE = 36
    VECT = 37
    RETI = 38
    ACO = 39
    CALCVV = 40
    CALCVA = 41
    CALCAV = 42
    CALCVX = 43
    CALCXV = 44
    CALCV = 45
    MVPA = 46
    RST = 48
    DJNZ = 49
    ROLA = 50
    RORA = 51
    SIV = 55
    GIV = 56
    AIV = 57
    UF0 = 64
    UF1 = 65
    UF2 = 66
    UF3 = 67
    UF4 = 68
    UF5 = 69
    UF6 = 70
    UF7 = 71
    CALL = 80
    STOP_APPLICATION = 128
    RUN_APPLICATION = 129
    STEP_APPLICATION = 130
    RESET_APPLICATION = 131
    ENTER_DOWNLOAD_MODE = 132
    EXIT_DOWNLOAD_MODE = 133
    READ_PROGRAM_MEMORY = 134
    GET_APPLICATION_STATUS = 135
    GET_FIRMWARE_VERSION = 136
    RESTORE_FACTORY_SETTINGS = 137
    REQUEST_TARGET_REACHED_EVENT = 138
    ENTER_ASCII_MODE = 139


# Control command numbers by name (TMCM-6212 3.6.36), as plain names too.
STOP_APPLICATION = int(Op.STOP_APPLICATION)
RUN_APPLICATION = int(Op.RUN_APPLICATION)
STEP_APPLICATION = int(Op.STEP_APPLICATION)
RESET_APPLICATION = int(Op.RESET_APPLICATION)
ENTER_DOWNLOAD_MODE = int(Op.ENTER_DOWNLOAD_MODE)
EXIT_DOWNLOAD_MODE = int(Op.EXIT_DOWNLOAD_MODE)
READ_PROGRAM_MEMORY = int(Op.READ_PROGRAM_MEMORY)
GET_APPLICATION_STATUS = int(Op.GET_APPLICATION_STATUS)
GET_FIRMWARE_VERSION = int(Op.GET_FIRMWARE_VERSION)
RESTORE_FACTORY_SETTINGS = int(Op.RESTORE_FACTORY_SETTINGS)
REQUEST_TARGET_REACHED_EVENT = int(Op.REQUEST_TARGET_REACHED_EVENT)
ENTER_ASCII_MODE = int(Op.ENTER_ASCII_MODE)
FACTORY_RESET_KEY = 1234  # value that command 137 requires
MOTOR_STOP = int(Op.MST)  # MST (3.6.3)
SET_GLOBAL_PARAMETER = int(Op.SGP)  # SGP (3.6.7)
CONTROL_FIRST = 128
"""Numbers from here up are reserved for control commands (3.6.36); see `is_control`."""
STOP_COMMANDS = frozenset({MOTOR_STOP, STOP_APPLICATION, RESET_APPLICATION})
"""Requests that stop motion or a program: a served module takes them before other waiting
requests (docs/architecture.md "Real time")."""

# --- named sets of commands (one definition each; code elsewhere tests membership) -------------

AXIS_COMMANDS: frozenset[Op] = frozenset(
    Op(c.number) for c in _COMMANDS
    if any(m.field == MOTOR and m.names == AXIS and m.types is None for m in c.meanings))
"""The commands whose motor field selects an axis whatever the type field, read from
`Command.meanings` (TMCM-6212 3.4.1 "<motor number>"): ROR, ROL, MST, MVP, SAP, GAP, STAP, RSAP,
RFS, SCO, GCO, CCO, AAP, ACO, MVPA, ROLA, RORA. Not WAIT, whose motor is an axis only for some
conditions (3.6.20)."""
MOTION_COMMANDS: frozenset[Op] = frozenset({
    Op.ROR, Op.ROL, Op.MST, Op.MVP, Op.RFS, Op.MVPA, Op.ROLA, Op.RORA})
"""The commands that start or stop a motion of the axis in their motor field: "rotate right",
"rotate left", "motor stop", "move to position" (TMCM-6212 3.6.1-3.6.4), "reference search"
(3.6.11) and the PD28-1021's MVPA, ROLA, RORA (PD28-1021 3.5 Table 5)."""
PROGRAM_CONTROL: frozenset[Op] = frozenset({
    Op.STOP_APPLICATION, Op.RUN_APPLICATION, Op.STEP_APPLICATION, Op.RESET_APPLICATION,
    Op.ENTER_DOWNLOAD_MODE, Op.EXIT_DOWNLOAD_MODE, Op.READ_PROGRAM_MEMORY, Op.GET_APPLICATION_STATUS})
"""The control commands that act on the TMCL program or report on it: stop, run, step, reset
the application, enter and exit download mode, read program memory, get application status
(TMCM-6212 3.6.36 Table 13, 128-135). Not 136 (firmware version), 137 (factory settings) or 139
(ASCII mode, PD86-1180 4.6.39)."""
UNANSWERED: frozenset[Op] = frozenset(Op(c.number) for c in _COMMANDS if not c.replies)
"""The commands the module answers with no reply: 137 ("This command does not send a reply",
TMCM-6212 3.6.36), from `Command.replies`."""
ALWAYS_ANSWERED: frozenset[Op] = frozenset({Op.GAP, Op.GGP, Op.GIO})
"""The commands whose reply GP255 never suppresses: "The reply will not be suppressed for GAP,
GGP and GIO commands" (TMCM-6212 5.1, global parameter 255)."""


def is_control(number: int) -> bool:
    """Is `number` a control command, which download mode (132) executes instead of storing
    ("All following commands (except control commands) are not executed but stored", TMCM-6212
    3.6.36)? The commands of Table 13 (and 139 on the PD86-1180, 4.6.39), not 138: 3.6.35 is no
    control command, a 138 sent during a download is stored. A number no command has is one from
    CONTROL_FIRST up."""
    c = COMMANDS.get(number)
    return c.control if c is not None else number >= CONTROL_FIRST


def keeps_addressing(command: int, bank: int) -> bool:
    """Can a module that executed `command` (with `bank` in the motor/bank field) have changed
    its addresses, reply suppression or serial mode? False when it can (`Command.keeps_address`)."""
    c = COMMANDS.get(command)
    return c is not None and c.keeps_address and not (command == SET_GLOBAL_PARAMETER and bank == 0)


class UnknownCommand(KeyError):
    """No command with that number or mnemonic."""

    def __str__(self) -> str:  # KeyError quotes its argument; keep the message readable
        return str(self.args[0])


def by_number(number: int) -> Command:
    """The command with opcode `number`; UnknownCommand if none."""
    try:
        return COMMANDS[number]
    except KeyError:
        raise UnknownCommand(f"unknown TMCL command number {number}") from None


def by_mnemonic(mnemonic: str) -> Command:
    """The command with this mnemonic, case-insensitive; UnknownCommand if none."""
    try:
        return _BY_MNEMONIC[mnemonic.strip().upper()]
    except KeyError:
        raise UnknownCommand(f"unknown TMCL mnemonic {mnemonic!r}") from None


def lookup_symbol(command: Command, name: str) -> int | None:
    """Value of a symbolic type operand of `command` (case-insensitive), or None."""
    return command.symbol_table().get(name.strip().upper())


def symbol_name(command: Command, number: int) -> str | None:
    """Symbolic name of type field value `number` for `command`, or None."""
    for name, value in command.symbol_table().items():
        if value == number:
            return name
    return None


_NUMBER = re.compile(r"([+-]?)\s*(?:0[xX]([0-9A-Fa-f]+)|\$([0-9A-Fa-f]+)|0[bB]([01]+)|([0-9]+))\Z")


def parse_number(text: str) -> int | None:
    """An integer literal: decimal (optionally signed), 0x/$ hex, 0b binary. None if not a literal;
    LiteralTooLong (a ValueError) for more than 32 digits (opentmcl.limits).

    A typographic minus or dash (as printed in the manuals) counts as '-'."""
    m = _NUMBER.match(text.strip().replace("\u2212", "-").replace("\u2013", "-"))
    if not m:
        return None
    sign = -1 if m.group(1) == "-" else 1
    hex_a, hex_b, binary, decimal = m.group(2, 3, 4, 5)
    check_literal(hex_a or hex_b or binary or decimal)
    if decimal is not None:
        return sign * int(decimal, 10)
    if binary is not None:
        return sign * int(binary, 2)
    return sign * int(hex_a or hex_b, 16)


# --- source text of one instruction --------------------------------------------------------------

class OperandError(ValueError):
    """An instruction whose operands do not fit the command's operand forms."""


def choose_form(command: Command, type: int, motor: int, value: int) -> tuple[str, ...] | None:
    """The canonical form if it expresses every non-zero field, else the shortest accepted form
    that does, or None."""
    nonzero = {f for f, v in ((TYPE, type), (MOTOR, motor), (VALUE, value)) if v}
    for form in (command.forms[0], *sorted(command.forms[1:], key=len)):
        if nonzero <= set(form):
            return form
    return None


def format_instruction(command: int, type: int, motor: int, value: int, *,
                       labels: Mapping[int, str] | None = None) -> str | None:
    """Canonical source text (symbolic type names, labels for addresses), or None if the command
    has no mnemonic or its fields cannot be written in any accepted form."""
    cmd = COMMANDS.get(command)
    if cmd is None or cmd.mnemonic is None:
        return None
    form = choose_form(cmd, type, motor, value)
    if form is None:
        return None
    parts = []
    for name in form:
        num = {TYPE: type, MOTOR: motor, VALUE: value}[name]
        text = str(num)
        if name == TYPE:
            text = symbol_name(cmd, num) or text
        elif name == VALUE and cmd.label and labels and num in labels:
            text = labels[num]
        parts.append(text)
    return f"{cmd.mnemonic} {', '.join(parts)}".rstrip()


def parse_instruction(text: str, labels: Mapping[str, int] | None = None) -> tuple[int, int, int, int]:
    """(command, type, motor, value) of one instruction such as 'MVP ABS, 0, 90000'.

    Operands are numbers, the command's symbolic type names, or names from `labels`. This is the
    minimal form used by codecs and tests; the assembler (opentmcl.lang) adds constants, includes
    and expressions.
    """
    head, _, rest = text.strip().partition(" ")
    cmd = by_mnemonic(head)
    operands = [p.strip() for p in rest.split(",")] if rest.strip() else []
    form = cmd.form_for(len(operands))
    if form is None or any(not p for p in operands):
        raise OperandError(f"{text.strip()!r}: expected {cmd.usage()}")
    out = {TYPE: 0, MOTOR: 0, VALUE: 0}
    for name, op in zip(form, operands, strict=True):
        num = lookup_symbol(cmd, op) if name == TYPE else None
        if num is None:
            try:
                num = parse_number(op)
            except LiteralTooLong as exc:
                raise OperandError(f"{name} operand: {exc}") from None
        if num is None and labels is not None:
            num = labels.get(op)
        if num is None:
            raise OperandError(f"{text.strip()!r}: cannot read {name} operand {op!r}")
        if name in (TYPE, MOTOR) and not 0 <= num <= 255:
            raise OperandError(f"{text.strip()!r}: {name} must be 0..255, got {num}")
        if not -(1 << 31) <= num <= 0xFFFFFFFF:
            raise OperandError(f"{text.strip()!r}: {name} out of 32-bit range: {num}")
        out[name] = to_int32(num)
    return cmd.number, out[TYPE], out[MOTOR], out[VALUE]
