"""Issue 11 problem 4 for `opentmcl tmc4210 trace` scripts: number literals are bounded.

Script numbers use the datasheet's notations ($hex, 0xhex, %binary, decimal; script.py). A
datagram is 32 bits (datasheet: "TMC4210 DATAGRAMS ARE WRITTEN AS 32 BIT NUMBERS"), so the longest literal is % and 32
binary digits; a 33rd digit is refused with a one-line ScriptError (opentmcl.limits).
"""
import pytest

from opentmcl.chips.tmc4210.chip import TMC4210
from opentmcl.chips.tmc4210.script import ScriptError, run_line


def test_longest_binary_literal_and_one_digit_more():
    chip = TMC4210()
    run_line(chip, "write V_MAX %" + format(1000, "032b"))
    assert chip.peek("V_MAX") == 1000
    with pytest.raises(ScriptError, match="33 digits is too long"):
        run_line(chip, "write V_MAX %0" + format(1000, "032b"))
    with pytest.raises(ScriptError, match="5000 digits is too long"):
        run_line(chip, "write V_MAX " + "1" * 5000)

