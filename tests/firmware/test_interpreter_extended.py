"""The PD28-1021 extended command set (PD28-1021 manual 3.5 Table 5; the manual is cut off before
the detailed pages 3.7.36-3.7.50, so the semantics follow the overview table - see
docs/assumptions.md)."""
from __future__ import annotations

import pytest

from opentmcl.lang.assembler import assemble

from .test_program_support import STOP, T, module
from .test_program_support import run_raw as _run_raw


def run28(source: str, seconds: float = 0.05, setup=None, **asm):
    w = module("PD28-1021")
    if setup:
        setup(w)
    w.download(assemble(source, **asm).instructions)
    w.run()
    w.vm.advance(seconds)
    return w


@pytest.mark.parametrize(("op", "a", "b", "result"), [
    ("ADD", 7, 5, 12), ("SUB", 7, 5, 2), ("MUL", 7, 5, 35), ("DIV", 7, 0, 0), ("MOD", 7, 0, 7),
    ("AND", 6, 3, 2), ("OR", 6, 3, 7), ("XOR", 6, 3, 5), ("NOT", 6, 3, -7), ("LOAD", 6, 3, 3),
])
def test_calcvv_var1_op_var2(op, a, b, result):
    """Table 5: "CALCVV <operation>, <user variable 1>, <user variable 2> - Arithmetical operation
    between two user variables": the result goes to variable 1."""
    w = run28(f"SGP 1, 2, {a}\nSGP 2, 2, {b}\nCALCVV {op}, 1, 2\nSTOP")
    assert (w.var(1), w.var(2), w.a) == (result, b, 0)


def test_calcvv_swap():
    w = run28("SGP 1, 2, 10\nSGP 2, 2, 20\nCALCVV SWAP, 1, 2\nSTOP")
    assert (w.var(1), w.var(2)) == (20, 10)


def test_calcva_calcav_calcvx_calcxv_calcv():
    """Table 5: CALCVA (variable op accumulator -> variable), CALCAV (accumulator op variable ->
    accumulator), CALCVX / CALCXV (the same with the X register), CALCV (variable op value)."""
    src = """
    SGP 3, 2, 100
    CALC LOAD, 7
    CALCVA ADD, 3       // v3 = 100 + 7
    CALCAV SUB, 3       // A = 7 - 107
    CALCX LOAD          // X = -100
    CALCVX MUL, 3       // v3 = 107 * -100
    SGP 4, 2, 3
    CALCXV ADD, 4       // X = -100 + 3
    SGP 5, 2, 50
    CALCV DIV, 5, 7     // v5 = 50 / 7
    STOP"""
    w = run28(src)
    assert (w.a, w.x, w.var(3), w.var(5)) == (-100, -97, -10700, 7)


def test_calcva_swap_and_calcv_swap_refused():
    """SWAP exchanges variable and accumulator; with a constant (CALCV) there is nothing to swap:
    the instruction is refused (no effect)."""
    w = run28("SGP 3, 2, 5\nCALC LOAD, 9\nCALCVA SWAP, 3\nCALCV SWAP, 3, 1\nSTOP")
    assert (w.a, w.var(3)) == (5, 9)
    assert w.vm.interpreter.last_error[1:] == (45, 3)


def test_mvpa_rola_rora_use_the_accumulator():
    """Table 5: MVPA "Move to position specified by accumulator", ROLA / RORA "Rotate left / right,
    velocity specified by accumulator"."""
    w = run28("CALC LOAD, 400\nMVPA ABS, 0\nSTOP", 10.0)
    assert w.ok(6, 0, 0) == 400 and w.ok(6, 1, 0) == 400
    w = run28("CALC LOAD, 300\nROLA 0\nSTOP", 0.01)
    assert w.ok(6, 2, 0) == -300
    w = run28("CALC LOAD, 300\nRORA 0\nSTOP", 0.01)
    assert w.ok(6, 2, 0) == 300
    w = run28("SCO 2, 0, -250\nCALC LOAD, 2\nMVPA COORD, 0\nSTOP", 10.0)
    assert w.ok(6, 0, 0) == -250


def test_djnz_counts_a_loop():
    """Table 5: "DJNZ <user variable>, <jump address> - Decrement and jump if not zero"."""
    w = run28("SGP 9, 2, 5\nLoop: CALC ADD, 10\nDJNZ 9, Loop\nSTOP")
    assert (w.a, w.var(9)) == (50, 0)


def test_siv_giv_aiv_index_with_the_x_register():
    """Table 5: SIV "Set indexed variable", GIV "Get indexed variable", AIV "Accumulator to indexed
    variable": the index is the X register."""
    w = run28("CALC LOAD, 20\nCALCX LOAD\nSIV 1234\nCALC LOAD, 21\nCALCX LOAD\nCALC LOAD, -8\nAIV\n"
              "CALC LOAD, 20\nCALCX LOAD\nGIV\nSTOP")
    assert (w.var(20), w.var(21), w.a) == (1234, -8, 1234)


def test_rst_restarts_at_a_label_dropping_the_stack():
    """Table 5: "RST <jump address> - Restart the program from the given address"; used to leave a
    subroutine, the return address is dropped."""
    w = run28("CSUB Sub\nCALC LOAD, 1\nSTOP\nSub: RST There\nRSUB\nThere: CALC LOAD, 2\nSTOP")
    assert w.a == 2 and w.vm.interpreter.stack == []


def test_call_is_a_conditional_csub():
    """PD28-1021 3.7.44 CALL (Conditional Subroutine Call), command 80: CSUB when the JC condition
    holds."""
    src = ("CALC LOAD, 3\nCOMP 3\nCALL EQ, Sub\nCALL NE, Sub\nSTOP\n"
           "Sub: GGP 0, 2\nCALC ADD, 1\nAGP 0, 2\nRSUB")
    w = run28(src, module="PD28-1021")
    assert w.var(0) == 1 and w.state == 0


def test_extended_commands_are_not_executed_on_other_modules():
    """The TMCM-6212 has no extended set (Table 5 of its manual ends at 39): a stored CALCV is
    skipped (command not available)."""
    w = module("TMCM-6212")
    w.download(assemble("CALCV ADD, 1, 5\nCALC LOAD, 3\nSTOP").instructions)
    w.run()
    w.vm.advance(0.01)
    assert w.var(1) == 0 and w.a == 3
    assert w.vm.interpreter.last_error[1] == 45


def test_calcv_takes_user_variable_0_and_the_last_one():
    """PD28-1021 manual Table 5: "CALCV 45 <operation>, <value> Arithmetical operation between user
    variable and direct value": variable 0 is the first user variable (TMCM-6212 3.6.9 bank 2
    "0...255"), so CALCV ADD on it adds, and on the last one (255, the largest the motor byte holds)
    too."""
    w = module("PD28-1021")
    last = len(w.vm.user_vars) - 1
    w.ok(9, 0, 2, 10)
    w.ok(9, last, 2, 20)
    assert last == 255
    w.download([(45, 0, 0, 5), (45, 0, last, 7), STOP])
    w.run()
    w.vm.advance(20 * T)
    assert (w.var(0), w.var(last)) == (15, 27)
    assert w.vm.interpreter.last_error is None


def test_calcvv_with_an_operation_beyond_swap_is_status_3():
    """PD28-1021 manual Table 5: "CALCVV <operation>, <user variable 1>, <user variable 2>" with the
    operations of CALC (0 ADD ... 9 LOAD, TMCM-6212 3.6.14) and SWAP (10, "CALCVV SWAP"): operation
    11 is none of them - TMCM-6212 3.2.1 Table 4 "3 Wrong type" - and variable 1 keeps its value."""
    w = _run_raw("PD28-1021", (9, 1, 2, 6), (40, 11, 1, 2), STOP)
    assert w.vm.interpreter.last_error == (1, 40, 3)
    assert w.var(1) == 6


def test_rst_restarts_at_address_0_and_refuses_the_end_of_memory():
    """PD28-1021 manual Table 5: "RST 48 <jump address> Restart the program from the given
    address". Address 0, the first of the program memory, is a valid target: the loop ADD 1 /
    COMP 3 / JC EQ / RST 0 runs three times. The first address beyond the memory (2048, 1 Features
    "2048 TMCL commands") is an invalid value (3.2.1 Table 4 "4 Invalid value"; the program goes on
    after it) and the last one (2047) is taken (it runs into the empty memory cell: status 2)."""
    w = module("PD28-1021")
    size = w.vm.program.size
    assert size == 2048
    w.download([(19, 0, 0, 1), (20, 0, 0, 3), (21, 2, 0, 4), (48, 0, 0, 0), (28, 0, 0, 0)])
    w.run()
    w.vm.advance(40 * T)
    assert (w.a, w.state, w.vm.interpreter.last_error) == (3, 0, None)
    w = module("PD28-1021")
    w.download([(48, 0, 0, size), (19, 0, 0, 7), (28, 0, 0, 0)])
    w.run()
    w.vm.advance(10 * T)
    assert (w.a, w.vm.interpreter.last_error) == (7, (0, 48, 4))
    w = module("PD28-1021")
    w.download([(48, 0, 0, size - 1)])
    w.run()
    w.vm.advance(10 * T)
    assert w.vm.interpreter.last_error == (size - 1, 0, 2)
