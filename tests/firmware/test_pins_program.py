"""Program and interrupt edges left unpinned by the seeded firmware mutation sample
(issue 12, `python bench/mutation.py --layer firmware --sample 300 --seed 12`, group b)."""
from __future__ import annotations

import pytest

from .test_program_support import T, module


def test_rst_inside_a_handler_drops_its_context_so_reti_is_ignored():
    """PD28-1021 Table 5: "RST 48 <jump address> Restart the program from the given address";
    docs/assumptions.md "RST label: jump, dropping the subroutine stack and any interrupt context"
    and "RETI outside a handler is ignored": a timer handler that restarts with RST and then
    meets a RETI goes on past it (A = 7, the program stops)."""
    w = module("PD28-1021")
    w.load("VECT 0, Tick\nSGP 0, 3, 1\nEI 0\nEI 255\nIdle: JA Idle\n"
           "Tick: RST After\nAfter: DI 255\nRETI\nCALC LOAD, 7\nSTOP\n")
    w.run()
    w.vm.advance(0.01)
    assert (w.a, w.state, w.vm.interrupts.active) == (7, 0, None)


def test_an_interrupt_pending_at_reti_into_a_wait_is_taken_next():
    """TMCM-6212 3.5.6.2 "There is no interrupt nesting", 5.4 priority by number; docs/assumptions.md
    "Interrupts": pending ones follow the RETI, and a WAIT interrupted by a handler resumes with
    its original deadline. Timer 1 expires while timer 0's handler runs: after that RETI the
    program is back in its WAIT with timer 1 pending, which is taken at once; each handler
    switches its timer off (period 0), so each runs once, and the WAIT still ends after 1 s."""
    src = ("VECT 0, T0\nVECT 1, T1\nEI 0\nEI 1\nEI 255\nSGP 0, 3, 10\nSGP 1, 3, 10\n"
           "WAIT TICKS, 0, 100\nSIO 0, 2, 1\nSTOP\n"
           "T0: SGP 0, 3, 0\nGGP 10, 2\nCALC ADD, 1\nAGP 10, 2\nRETI\n"
           "T1: SGP 1, 3, 0\nGGP 11, 2\nCALC ADD, 1\nAGP 11, 2\nRETI\n")
    w = module()
    w.load(src)
    w.run()
    w.vm.advance(0.1)
    assert (w.var(10), w.var(11), w.pc, w.out(0)) == (1, 1, 7, 0)
    w.vm.advance(0.91)
    assert w.out(0) == 1


def test_an_enabled_interrupt_without_vector_does_not_hide_an_input_change():
    """TMCM-6212 3.5.6.2: an interrupt is handled when it "is enabled and a valid interrupt vector
    has been defined". Timer 0 enabled without a vector (EI 0, no VECT 0) must not stop the input
    change interrupt 39 (IN0, both edges: SGP 39, 3, 3) from being seen."""
    w = module()
    w.load("EI 0\nVECT 39, In0\nEI 39\nSGP 39, 3, 3\nEI 255\nIdle: JA Idle\n"
           "In0: GGP 10, 2\nCALC ADD, 1\nAGP 10, 2\nRETI\n")
    w.run()
    w.vm.advance(20 * T)
    w.vm.io.drive_input(0, 0, 1)
    w.vm.advance(20 * T)
    assert w.var(10) == 1


@pytest.mark.parametrize(("period", "a"), [(0x7FFF_FFFF, 0x7FFF_FFFF), (0x8000_0000, -0x8000_0000),
                                           (0xFFFF_FFFF, -1)])
def test_ggp_of_an_unsigned_timer_period_loads_it_as_32_bits(period, a):
    """TMCM-6212 5.4 bank 3: "Timer 0 period ... 0 .. 4294967295 [ms]"; 3.6.10 GGP in a program
    loads the accumulator, a 32-bit register (3.5.5; 135 type 2 returns it on the wire as the
    same 32 bits). The last signed value stays, 2^31 and 2^32 - 1 read back as -2^31 and -1."""
    w = module()
    w.ok(9, 0, 3, period - (1 << 32) if period > 0x7FFF_FFFF else period)
    w.download([(10, 0, 3, 0), (28, 0, 0, 0)])
    w.run()
    w.vm.advance(3 * T)
    assert (w.a, w.state) == (a, 0)


def test_a_module_without_a_timer_period_runs_its_other_timers(tmp_path):
    """docs/profiles.md `[remove]`: a profile without bank-3 parameter 2 (timer 2's period, TMCM-6212
    5.3) has no timer 2 (GGP 2, 3 is status 3, wrong type) - its program and timer 1 run as on
    the TMCM-6212 (3.5.6.4 timer example, a 1 ms period here)."""
    path = tmp_path / "notimer2.toml"
    path.write_text('extends = "TMCM-6212"\n[module]\nname = "NOTIMER2-6212"\n'
                    "[remove]\nglobal_parameter = [[3, 2]]\n")
    w = module(str(path))
    assert w(10, 2, 3).status == 3
    w.load("VECT 1, T1\nSGP 1, 3, 1\nEI 1\nEI 255\nIdle: JA Idle\n"
           "T1: GGP 10, 2\nCALC ADD, 1\nAGP 10, 2\nRETI\n", module="TMCM-6212")
    w.run()
    w.vm.advance(0.0105)
    assert w.var(10) == 10
