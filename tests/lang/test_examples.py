"""Every example program of the manuals assembles to the instructions the manual describes.

The programs are transcribed in tests/lang/examples/ (listing line numbers and "..." placeholder
lines removed); each file names its manual section.
"""
from __future__ import annotations

from pathlib import Path

import pytest

from opentmcl.lang.assembler import AsmError, assemble, assemble_file
from opentmcl.lang.disassembler import disassemble

EXAMPLES = Path(__file__).parent / "examples"
STOP = (28, 0, 0, 0)


def module_of(path: Path) -> str:
    return "TMCM-6212" if path.name.startswith("tmcm6212") else "PD86-1180"


def prog(name: str):
    path = EXAMPLES / name
    return assemble_file(path, module=module_of(path))


def ins(p) -> list[tuple[int, int, int, int]]:
    return [tuple(i) for i in p.instructions]


@pytest.mark.parametrize("path", sorted(EXAMPLES.glob("*.tmc")), ids=lambda p: p.stem)
def test_every_example_assembles_and_round_trips(path):
    """Each manual example assembles for its module, ends with the appended STOP (TMCL-IDE format,
    docs/tmcl-assembler.md), and its disassembly re-assembles to identical bytes."""
    p = assemble_file(path, module=module_of(path))
    assert tuple(p.instructions[-1]) == STOP
    again = assemble(disassemble(p.image(), labels=p.labels))
    assert again.image() == p.image()


def test_6212_first_program():
    """TMCM-6212 2.4: the little test program; Loop is the 9th instruction (address 8)."""
    p = prog("tmcm6212_2_4_simple.tmc")
    assert ins(p) == [(2, 0, 0, 51200), (27, 0, 0, 500), (3, 0, 0, 0), (1, 0, 0, 51200), (27, 0, 0, 500),
                      (3, 0, 0, 0), (5, 4, 0, 51200), (5, 5, 0, 51200), (4, 0, 0, 512000), (27, 1, 0, 0),
                      (4, 0, 0, -512000), (27, 1, 0, 0), (22, 0, 0, 8), STOP]
    assert p.labels == {"Loop": 8}


TIMER_PROGRAM = [
    (37, 0, 0, 9), (9, 0, 3, 1000), (25, 0, 0, 0), (25, 255, 0, 0),            # 0..3
    (14, 3, 2, 1), (27, 0, 0, 50), (14, 3, 2, 0), (27, 0, 0, 50), (22, 0, 0, 4),  # Loop = 4
    (15, 0, 2, 0), (21, 1, 0, 13), (14, 0, 2, 1), (38, 0, 0, 0),                # Timer0Irq = 9
    (14, 0, 2, 0), (38, 0, 0, 0),                                               # Out0Off = 13
    STOP,
]


def test_6212_timer_interrupt_example():
    """TMCM-6212 3.5.6.4 (= PD86-1180 4.4.2.6.5): VECT 0 points at Timer0Irq, JC NZ at Out0Off."""
    p = prog("tmcm6212_3_5_6_4_timer_interrupt.tmc")
    assert ins(p) == TIMER_PROGRAM
    assert p.labels == {"Loop": 4, "Timer0Irq": 9, "Out0Off": 13}


def test_6212_timer_interrupt_example_with_interrupts_inc():
    """3.5.6.4: "#include Interrupts.inc / VECT TI_TIMER0, Timer0Irq / SGP TI_TIMER0, 3, 1000 /
    EI TI_TIMER0 / EI TI_GLOBAL" gives the same program (TI_TIMER0 = 0, TI_GLOBAL = 255)."""
    p = prog("tmcm6212_3_5_6_4_timer_interrupt_inc.tmc")
    assert ins(p) == TIMER_PROGRAM
    assert p.constants["TI_TIMER0"] == 0 and p.constants["TI_GLOBAL"] == 255


def test_jc_examples():
    """TMCM-6212 3.6.16 / PD86-1180 4.6.18: JC GE, Label; the 1180 writes GAP with three operands."""
    expected = [(6, 1, 0, 0), (20, 0, 0, 1000), (21, 5, 0, 3), (2, 0, 0, 1000), STOP]
    assert ins(prog("tmcm6212_3_6_16_jc.tmc")) == expected
    assert ins(prog("pd86_1180_4_6_18_jc.tmc")) == expected


def test_ja_and_csub_examples():
    """TMCM-6212 3.6.17/3.6.18 (labels followed by " :" and operands with " , ")."""
    assert ins(prog("tmcm6212_3_6_17_ja.tmc")) == [
        (4, 0, 0, 51200), (27, 1, 0, 0), (4, 0, 0, 0), (27, 1, 0, 0), (22, 0, 0, 0), STOP]
    p = prog("tmcm6212_3_6_18_csub.tmc")
    assert p.labels == {"Loop": 0, "SubW": 5}
    assert ins(p)[1] == (23, 0, 0, 5) and ins(p)[4] == (22, 0, 0, 0) and ins(p)[7] == (24, 0, 0, 0)
    q = prog("pd86_1180_4_6_20_csub.tmc")
    assert q.labels == {"Loop": 0, "SubW": 4}


def test_aap_examples():
    """TMCM-6212 3.6.27 and PD86-1180 4.6.29: GIO 0,1 / CALC MUL, 4 / AAP 0,0 / JA Start."""
    expected = [(15, 0, 1, 0), (19, 2, 0, 4), (34, 0, 0, 0), (22, 0, 0, 0), STOP]
    assert ins(prog("tmcm6212_3_6_27_aap.tmc")) == expected
    assert ins(prog("pd86_1180_4_6_29_aap.tmc")) == expected


def test_vect_example_as_printed_has_a_typo():
    """TMCM-6212 3.6.32 prints "SID 0, 2, 1" inside the handler: there is no SID command, and the
    error names the line and column; with SIO the example assembles."""
    src = "   VECT 0, Timer0Irq\nLoop:\n   JA Loop\nTimer0Irq:\n   SID 0, 2, 1\n   RETI\n"
    with pytest.raises(AsmError) as exc:
        assemble(src, filename="vect.tmc")
    assert (exc.value.file, exc.value.line, exc.value.column) == ("vect.tmc", 5, 4)
    assert "unknown mnemonic 'SID'" in str(exc.value)
    assert ins(prog("tmcm6212_3_6_32_vect.tmc"))[0] == (37, 0, 0, 2)


def test_1180_ei_example_as_printed():
    """PD86-1180 4.6.33 prints "EI, 255" - a comma where the operand should start."""
    with pytest.raises(AsmError, match="expected a space after 'EI'"):
        assemble("EI, 255")
    assert ins(assemble("EI 255")) == [(25, 255, 0, 0), STOP]


def test_1180_vect_at_address_500():
    """PD86-1180 4.6.32: "VECT 3, 500" - a numeric address."""
    assert ins(prog("pd86_1180_4_6_32_vect.tmc")) == [(37, 3, 0, 500), STOP]


def test_1180_sio_all_outputs_program():
    """PD86-1180 4.6.14: GIO 255, 0 / SIO 255, 2,-1 (copy the accumulator to all outputs)."""
    assert ins(prog("pd86_1180_4_6_14_sio.tmc")) == [(15, 255, 0, 0), (14, 255, 2, -1), (22, 0, 0, 0), STOP]


def test_main_loop_and_symbolic_constants():
    """TMCM-6212 7.2 and 7.3: with TMCLParam.tmc, APMaxPositioningSpeed = 4, APMaxAcceleration = 5,
    Motor0 = 0, and the 7.3 program equals the 7.2 program with its own numbers."""
    p72 = prog("tmcm6212_7_2_main_loop.tmc")
    assert ins(p72) == [(5, 4, 0, 50000), (5, 5, 0, 10000), (4, 0, 0, 5000), (27, 1, 0, 0), (4, 0, 0, 0),
                        (27, 1, 0, 0), (22, 0, 0, 2), STOP]
    p73 = prog("tmcm6212_7_3_symbolic_constants.tmc")
    assert ins(p73) == [(5, 4, 0, 50000), (5, 5, 0, 10000), (4, 0, 0, 500000), (27, 1, 0, 0),
                        (4, 0, 0, 0), (27, 1, 0, 0), (22, 0, 0, 2), STOP]
    assert p73.constants["MaxSpeed"] == 50000
    p83 = prog("pd86_1180_8_3_symbolic_constants.tmc")
    assert ins(p83)[:2] == [(5, 4, 0, 500), (5, 5, 0, 100)]
    assert ins(prog("pd86_1180_8_2_main_loop.tmc"))[:2] == [(5, 4, 0, 500), (5, 5, 0, 100)]


def test_variables_example():
    """TMCM-6212 7.4 / PD86-1180 8.4: MyVariable = 42 used as the type of SGP/GGP (bank 2)."""
    expected = [(9, 42, 2, 1234), (10, 42, 2, 0), (19, 2, 0, 2), (34, 42, 2, 0), STOP]
    assert ins(prog("tmcm6212_7_4_variables.tmc")) == expected
    assert ins(prog("pd86_1180_8_4_variables.tmc")) == expected


@pytest.mark.parametrize("name", ["tmcm6212_7_6_direct_and_standalone.tmc", "pd86_1180_8_6_direct_and_standalone.tmc"])
def test_direct_and_standalone_entry_points(name):
    """TMCM-6212 7.6 / PD86-1180 8.6: "a run command with address 0 to call the first function, ...
    address 1 ... the second ..., address 2 ... the third"; the symbol file lists them."""
    p = prog(name)
    assert p.labels == {"Func1": 0, "Func2": 1, "Func3": 2, "Func1Start": 3, "Func2Start": 8, "Func3Start": 12}
    assert ins(p)[:3] == [(22, 0, 0, 3), (22, 0, 0, 8), (22, 0, 0, 12)]
    assert p.symbol_file().splitlines()[:3] == ["Func1\t0", "Func2\t1", "Func3\t2"]


def test_1180_first_program():
    """PD86-1180 3.2: label on the line of its instruction ("Loop:   MVP ABS, 0, 10000")."""
    p = prog("pd86_1180_3_2_simple.tmc")
    assert p.labels == {"Loop": 8}
    assert ins(p)[8] == (4, 0, 0, 10000) and ins(p)[12] == (22, 0, 0, 8)
