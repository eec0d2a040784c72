"""32-bit two's complement arithmetic of CALC, CALCX and the PD28-1021 CALCxx commands
(TMCM-6212 manual 3.6.14, 3.6.26; PD28-1021 manual 3.5 Table 5).

Operations 0-9: ADD SUB MUL DIV MOD AND OR XOR NOT LOAD; 10 SWAP (CALCX and the
extended set). Results wrap to 32 bits like the modules' C firmware. Division
truncates towards zero and MOD takes the sign of the dividend (C semantics).
Division by zero: DIV gives 0 and MOD leaves the dividend unchanged - what the
ARM Cortex-M hardware divider (SDIV returns 0 for a zero divisor) and the
remainder computed as a - (a / b) * b produce. See docs/assumptions.md.
"""
from __future__ import annotations

from ..protocol.frame import to_int32
from ..protocol.opcodes import Op

ADD, SUB, MUL, DIV, MOD, AND, OR, XOR, NOT, LOAD, SWAP = range(11)
CALCV = int(Op.CALCV)  # PD28-1021 Table 5 (a variable and a direct value)


def last_operation(command: int) -> int:
    """The highest operation type of CALCX (TMCM-6212 3.6.26) and the CALCxx commands: SWAP, but LOAD for
    CALCV, whose source is a constant it cannot exchange with (docs/assumptions.md "PD28-1021
    extended set"). A type above it is "3 Wrong type", in direct mode and in a program alike."""
    return LOAD if command == CALCV else SWAP


def divide(a: int, b: int) -> int:
    if b == 0:
        return 0
    q = abs(a) // abs(b)
    return to_int32(q if (a < 0) == (b < 0) else -q)


def modulo(a: int, b: int) -> int:
    if b == 0:
        return to_int32(a)
    return to_int32(a - divide(a, b) * b)


def binary(op: int, a: int, b: int) -> int | None:
    """`a <op> b` for operations 0-7 and 9 (LOAD gives b); NOT gives ~a. None for other ops."""
    a, b = to_int32(a), to_int32(b)
    if op == ADD:
        return to_int32(a + b)
    if op == SUB:
        return to_int32(a - b)
    if op == MUL:
        return to_int32(a * b)
    if op == DIV:
        return divide(a, b)
    if op == MOD:
        return modulo(a, b)
    if op == AND:
        return to_int32(a & b)
    if op == OR:
        return to_int32(a | b)
    if op == XOR:
        return to_int32(a ^ b)
    if op == NOT:
        return to_int32(~a)
    if op == LOAD:
        return b
    return None
