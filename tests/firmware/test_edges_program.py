"""Edges of standalone programs: the zero flag of negative results, DJNZ with a negative counter,
signed comparisons and jumps to the last program address."""
from __future__ import annotations

import pytest

from .test_program_support import T, module, run_program

BRANCH = """
    {setup}
    {jump} Taken
    SGP 0, 2, 1
    STOP
Taken:
    SGP 0, 2, 2
    STOP
"""


def _taken(setup: str, jump: str, name: str = "TMCM-6212") -> bool:
    """Whether `jump` branches after `setup` (user variable 0 says which way the program went)."""
    w = run_program(BRANCH.format(setup=setup, jump=jump), 20 * T, name)
    assert w.var(0) in (1, 2), "the program did not reach either branch"
    return w.var(0) == 2


@pytest.mark.parametrize(("setup", "zero"), [
    ("CALC LOAD, 5\n CALC SUB, 6", False),       # -1
    ("CALC LOAD, -2147483648", False),           # the most negative 32-bit value
    ("CALC LOAD, 3\n CALC MUL, -1", False),
    ("CALC LOAD, 6\n CALC SUB, 6", True),
    ("CALC LOAD, -1\n CALC ADD, 1", True),
])
def test_the_zero_flag_is_set_by_zero_only_not_by_negative_results(setup, zero):
    """TMCM-6212 3.6.16 JC: "0 ZE - zero", "1 NZ - not zero"; the flags are set by CALC (3.6.14
    "CALC <op>, <value>" with the accumulator): a negative result clears the zero flag, so JC ZE is
    not taken and JC NZ is."""
    assert (_taken(setup, "JC ZE,"), _taken(setup, "JC NZ,")) == (zero, not zero)


@pytest.mark.parametrize(("a", "b", "taken"), [
    (-1, 0, {"LT", "LE", "NE"}), (0, -1, {"GT", "GE", "NE"}), (-5, -5, {"EQ", "GE", "LE", "ZE"}),
    (-2147483648, 2147483647, {"LT", "LE", "NE"}),
])
def test_comp_compares_signed_32_bit_values(a, b, taken):
    """TMCM-6212 3.6.15 COMP: "the accumulator register is compared with the specified value" and
    3.6.16 JC conditions EQ, NE, GT, GE, LT, LE, ZE: the comparison is signed (-1 is lower than 0)."""
    got = {c for c in ("EQ", "NE", "GT", "GE", "LT", "LE", "ZE")
           if _taken(f"CALC LOAD, {a}\n COMP {b}", f"JC {c},")}
    assert got == taken


@pytest.mark.parametrize(("start", "after", "jumps"), [
    (-3, -4, True), (0, -1, True), (1, 0, False), (2, 1, True), (-2147483648, 2147483647, True),
])
def test_djnz_decrements_and_jumps_unless_the_variable_is_zero(start, after, jumps):
    """PD28-1021 3.5 Table 5: "DJNZ 49 <user variable>, <jump address> Decrement and jump if not
    zero": a negative counter is decremented and jumps (it is not zero), only 1 -> 0 falls
    through; the variable wraps at 32 bits."""
    w = run_program(f"SGP 9, 2, {start}\nDJNZ 9, Taken\nSGP 0, 2, 1\nSTOP\nTaken:\nSGP 0, 2, 2\nSTOP",
                    20 * T, "PD28-1021")
    assert (w.var(9), w.var(0)) == (after, 2 if jumps else 1)


@pytest.mark.parametrize("name", ["TMCM-6212", "PD86-1180"])
def test_a_jump_to_the_last_address_runs_it_and_one_beyond_is_ignored(name):
    """1 Features: the program memory holds `program_memory` commands. JA (3.6.17) to the last
    address executes the instruction there, after which the program stops at the end of memory;
    a JA one beyond is refused (status 4, docs/assumptions.md: "a jump outside program memory is
    ignored") and the program goes on with the next instruction."""
    w = module(name)
    last = w.vm.profile.program_memory - 1
    w.download([(22, 0, 0, last + 1), (9, 1, 2, 11), (22, 0, 0, last)])
    w.download([(9, 2, 2, 22)], start=last)
    w.run()
    w.vm.advance(20 * T)
    assert (w.var(1), w.var(2), w.state) == (11, 22, 0)


def test_wait_pos_takes_the_last_motor_and_refuses_the_next():
    """TMCM-6212 3.6.20 WAIT POS, <motor>: motors 0..5; the next one is "4 Invalid value", which a
    program records as its last error and goes on (docs/assumptions.md)."""
    w = run_program("WAIT POS, 6, 0\nSGP 0, 2, 1\nWAIT POS, 5, 0\nSGP 1, 2, 1\nSTOP", 20 * T)
    assert (w.var(0), w.var(1)) == (1, 1)
    assert w.vm.interpreter.last_error == (0, 27, 4)
