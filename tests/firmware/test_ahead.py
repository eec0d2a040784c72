"""The steps written out for the run ahead (firmware/ahead.py) at the edges of what they compute,
each against the manual and against the reference that runs every instruction through its handler
(`run_ahead` False).

TMCM-6212 manual 3.6.14 CALC (ADD, SUB; results wrap to 32 bits, docs/assumptions.md), 3.6.6 GAP 8
"target position reached" (a flag: 0 or 1), 3.6.35 AGP (user variables, bank 2)."""
from __future__ import annotations

from .test_next_event_cache import both

WRAP = """
    CALC LOAD, 2147483646
    CALC ADD, 1
    AGP 0, 2            // the last valid value: 2^31 - 1
    CALC ADD, 1
    AGP 1, 2            // the first one past it wraps to -2^31
    CALC SUB, 1
    AGP 2, 2            // and back
    CALC LOAD, -2147483647
    CALC SUB, 1
    AGP 3, 2            // -2^31
    CALC SUB, 1
    AGP 4, 2            // wraps to 2^31 - 1
L:  GGP 5, 2
    CALC ADD, 1
    AGP 5, 2
    JA L"""


def test_calc_add_and_sub_wrap_at_32_bits_when_run_ahead():
    """CALC ADD and SUB on the accumulator at the ends of the signed 32-bit range."""
    w = both(WRAP, 0.02)
    assert w.vm.user_vars[:5] == [2**31 - 1, -(2**31), 2**31 - 1, -(2**31), 2**31 - 1]
    assert w.vm.user_vars[5] > 10


def test_gap_8_loads_the_integer_flag():
    """GAP 8 of a standing axis (target reached) loads 1, an int as in direct mode, not a bool."""
    w = both("L: GAP 8, 0\n    AGP 0, 2\n    GGP 1, 2\n    CALC ADD, 1\n    AGP 1, 2\n    JA L", 0.02)
    assert w.vm.user_vars[0] == 1 and type(w.vm.accumulator) is int and type(w.vm.user_vars[0]) is int
