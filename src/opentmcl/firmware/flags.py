"""The TMCL program flags (TMCM-6212 manual 3.6.15 COMP, 3.6.16 JC, 3.6.29 CLE).

`vm.flags` holds the error flags in bits 0-4 in CLE order (ETO = CLE 1 is bit 0,
..., ESD = CLE 5 is bit 4, so `VirtualModule.clear_error_flags(n)` clears bit
n - 1) and the arithmetic flags in bits 8-11. The manual names the flags but
not their layout; this one is our choice (docs/assumptions.md).
"""
from __future__ import annotations

ETO, EAL, EDV, EPO, ESD = 1, 2, 4, 8, 16
ERROR_MASK = 0x1F
ZERO, EQUAL, GREATER, LOWER = 0x100, 0x200, 0x400, 0x800
ARITHMETIC_MASK = 0xF00

# JC / CALL conditions 8-12 test these error flags (TMCM-6212 3.6.16, PD86-1180 4.6.18).
CONDITION_ERROR = {8: ETO, 9: EAL, 10: EDV, 11: EPO, 12: ESD}


def after_compare(flags: int, accumulator: int, operand: int) -> int:
    """COMP: signed comparison of the accumulator with the operand; the zero flag says equal."""
    out = flags & ~ARITHMETIC_MASK
    if accumulator == operand:
        out |= EQUAL | ZERO
    elif accumulator > operand:
        out |= GREATER
    else:
        out |= LOWER
    return out


CONDITIONS = {0: (ZERO, True), 1: (ZERO, False), 2: (EQUAL, True), 3: (EQUAL, False),
              4: (GREATER, True), 5: (GREATER | EQUAL, True), 6: (LOWER, True), 7: (LOWER | EQUAL, True),
              **{c: (bit, True) for c, bit in CONDITION_ERROR.items()}}
"""JC condition -> (flag bits, met when any is set (True) or when none is)."""


def condition(flags: int, cond: int) -> bool | None:
    """JC condition 0-12 against `flags`; None for an unknown condition number."""
    test = CONDITIONS.get(cond)
    if test is None:
        return None
    bits, when_set = test
    return bool(flags & bits) == when_set


def describe(flags: int) -> str:
    """Readable flag set, e.g. ``ZE EQ ETO`` (debugger watch)."""
    names = [(ZERO, "ZE"), (EQUAL, "EQ"), (GREATER, "GT"), (LOWER, "LT"),
             (ETO, "ETO"), (EAL, "EAL"), (EDV, "EDV"), (EPO, "EPO"), (ESD, "ESD")]
    return " ".join(n for bit, n in names if flags & bit) or "-"
