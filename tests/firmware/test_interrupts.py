"""TMCL interrupts: VECT/EI/DI/RETI, global enable 255, priority, no nesting, context save,
timers and event sources (TMCM-6212 manual 3.5.6, 3.6.30-3.6.33, 5.4; PD86-1180 manual 4.4.2.6)."""
from __future__ import annotations

from pathlib import Path

import pytest

from .test_program_support import T, module

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"

# An ISR per interrupt that appends its digit to user variable 10 (v10 = v10 * 10 + digit).
def isr(label: str, digit: int) -> str:
    return (f"{label}:\n GGP 10, 2\n CALC MUL, 10\n CALC ADD, {digit}\n AGP 10, 2\n"
            f" WAIT TICKS, 0, 1\n RETI\n")


MAIN_IDLE = "Idle: JA Idle\n"


def test_timer_example_toggles_out0_every_second_and_out3_every_half_second():
    """3.5.6.4 example: timer 0 with "SGP 0, 3, 1000 //... set its period to 1000ms"; its handler
    toggles OUT0, while the main loop toggles OUT3 with WAIT TICKS, 0, 50 (500 ms)."""
    src = (EXAMPLES / "tmcm6212_3.5.6.4_timer_interrupt.tmc").read_text()
    w = module()
    w.load(src)
    w.run()
    out0, out3 = [], []
    for _ in range(400):                     # 4 s in 10 ms samples
        w.vm.advance(0.01)
        out0.append(w.out(0))
        out3.append(w.out(3))

    def edges(samples):
        return [i + 1 for i in range(1, len(samples)) if samples[i] != samples[i - 1]]

    e0, e3 = edges(out0), edges(out3)
    assert out0[0] == 0 and out3[0] == 1
    assert e0 == [101, 201, 301]              # first 10 ms sample after 1 s, 2 s, 3 s
    gaps3 = [b - a for a, b in zip(e3, e3[1:], strict=False)]
    assert len(e3) == 7 and all(g == 50 for g in gaps3)


def test_priority_lower_number_first_and_no_nesting():
    """5.4: "Interrupts with a lower number have a higher priority"; 3.5.6.2 "There is no interrupt
    nesting": an interrupt that occurs during a handler runs after its RETI."""
    src = ("VECT 15, Stall\nVECT 21, Dev\nVECT 39, In0\nEI 15\nEI 21\nEI 39\nSGP 39, 3, 3\nEI 255\n"
           + MAIN_IDLE + isr("Stall", 1) + isr("Dev", 2) + isr("In0", 3))
    w = module()
    w.load(src)
    w.run()
    w.vm.advance(20 * T)
    assert w.vm.interrupts.trigger(21) and w.vm.interrupts.trigger(15)
    w.vm.advance(0.005)                       # inside the first handler (its WAIT)
    assert w.vm.interrupts.active == 15
    w.vm.io.drive_input(0, 0, 1)              # input change 0 while a handler runs
    w.vm.advance(0.1)
    assert w.var(10) == 123
    assert w.vm.interrupts.active is None


def test_context_is_saved_and_restored():
    """3.5.6.2: "Before an interrupt handling routine gets called, the context of the normal program
    (i.e. accumulator register, X register, flags) will be saved automatically ... On return ...
    restored"."""
    src = ("VECT 0, Tick\nSGP 0, 3, 20\nEI 0\nEI 255\n"
           "CALC LOAD, 77\nCALCX LOAD\nCALC LOAD, 5\nCOMP 5\n"
           "Loop: JC NE, Broken\nCOMP 5\nJA Loop\nBroken: STOP\n"
           "Tick: CALC LOAD, 1\nCALCX LOAD\nCOMP 9\nGGP 11, 2\nCALC ADD, 1\nAGP 11, 2\nRETI")
    w = module()
    w.load(src)
    w.run()
    w.vm.advance(1.0)
    assert w.state == 1                      # the main loop never saw the handler's flags
    assert w.var(11) >= 45
    w.ok(128)
    assert (w.a, w.x) in ((5, 77),) or w.vm.interrupts.active is not None


def test_global_enable_and_di():
    """3.6.30 / 3.6.31: "Interrupt number 255 globally enables interrupt processing"; DI disables."""
    base = "VECT 39, In0\nEI 39\nSGP 39, 3, 1\n"
    for extra, expected in (("", 0), ("EI 255\n", 3), ("EI 255\nDI 39\n", 0), ("EI 255\nDI 255\n", 0)):
        w = module()
        w.load(base + extra + MAIN_IDLE + isr("In0", 3))
        w.run()
        w.vm.advance(0.01)
        w.vm.io.drive_input(0, 0, 1)
        w.vm.advance(0.05)
        assert w.var(10) == expected, extra


@pytest.mark.parametrize(("mode", "levels", "expected"), [
    (0, [1, 0, 1], 0),       # off
    (1, [1, 0, 1], 33),      # low-high
    (2, [1, 0, 1], 3),       # high-low
    (3, [1, 0, 1], 333),     # both
])
def test_input_change_trigger_transitions(mode, levels, expected):
    """5.4 Table 20: "Input 0 trigger transition 0=off, 1=low-high, 2=high-low, 3=both"."""
    w = module()
    w.load(f"VECT 39, In0\nEI 39\nSGP 39, 3, {mode}\nEI 255\n" + MAIN_IDLE + isr("In0", 3))
    w.run()
    w.vm.advance(0.01)
    for level in levels:
        w.vm.io.drive_input(0, 0, level)
        w.vm.advance(0.05)
    assert w.var(10) == expected


def test_stop_switch_interrupt_from_injected_level():
    """Table 12: 27 "Left stop switch 0", 28 "Right stop switch 0"; Table 20 trigger transitions.
    The switch level is injected directly (forced through the world model)."""
    w = module()
    w.load("VECT 28, R0\nEI 28\nSGP 28, 3, 1\nEI 255\n" + MAIN_IDLE + isr("R0", 8))
    w.run()
    w.vm.advance(0.01)
    w.vm.world.axis(0).force_switch("right", 1)
    w.vm.advance(0.05)
    assert w.var(10) == 8
    w.vm.world.axis(0).force_switch("right", 0)   # high-low: not selected (mode 1)
    w.vm.advance(0.05)
    assert w.var(10) == 8


def test_stop_switch_interrupt_when_the_stage_reaches_the_switch():
    """The right limit switch of a scenario stage at 5000 is reached by ROR: interrupt 28 runs its
    handler, which reads the position (GAP 1, 0) near the switch."""
    from opentmcl import VirtualModule

    from .test_program_support import Wire
    w = Wire(VirtualModule("TMCM-6212", address=1, scenario={"axis": {"0": {"right": {"position": 5000}}}}))
    w.load("VECT 28, R0\nEI 28\nSGP 28, 3, 1\nEI 255\nROR 0, 20000\n" + MAIN_IDLE
           + "R0: GAP 1, 0\nAGP 20, 2\nRETI")
    w.run()
    w.vm.advance(0.1)
    assert w.var(20) == 0
    w.vm.advance(2.0)
    assert 5000 <= w.var(20) <= 5100


def test_target_reached_interrupt_per_axis():
    """Table 12: 3 + n "Target position reached n": the handler runs when motor 1 arrives."""
    w = module()
    w.load("VECT 4, Arrived\nEI 4\nEI 255\nMVP ABS, 1, 2000\nMVP ABS, 0, 100\n" + MAIN_IDLE
           + isr("Arrived", 4))
    w.run()
    w.vm.advance(0.002)
    assert w.var(10) == 0
    w.vm.advance(5.0)
    assert w.var(10) == 4 and w.ok(6, 1, 1) == 2000


def test_timer_interrupts_a_wait_which_keeps_its_deadline():
    """3.6.20 WAIT holds the program; an interrupt taken meanwhile returns to the same WAIT, which
    ends at its original time (docs/assumptions.md)."""
    src = ("VECT 1, T1\nSGP 1, 3, 100\nEI 1\nEI 255\nWAIT TICKS, 0, 50\nSIO 0, 2, 1\nSTOP\n"
           "T1: GGP 12, 2\nCALC ADD, 1\nAGP 12, 2\nRETI")
    w = module()
    w.load(src)
    w.run()
    w.vm.advance(0.5)
    assert w.out(0) == 0 and w.var(12) == 4
    w.vm.advance(0.01)
    assert w.out(0) == 1


def test_no_interrupt_without_vector_or_when_stopped():
    """3.5.6.2: an interrupt is handled only when it "is enabled and a valid interrupt vector has been
    defined"; a stopped program handles none."""
    w = module()
    w.load("EI 40\nSGP 40, 3, 3\nEI 255\n" + MAIN_IDLE)
    w.run()
    w.vm.advance(0.01)
    assert not w.vm.interrupts.trigger(40)
    w.load("VECT 40, In1\nEI 40\nEI 255\n" + MAIN_IDLE + isr("In1", 1))
    w.run(0)
    w.vm.advance(0.01)
    w.ok(128)
    assert not w.vm.interrupts.trigger(40)


def test_vector_table_of_each_module():
    """Table 12 (TMCM-6212: 0-8, 15-42) and PD86-1180 4.4.2.6.3 (0-3, 15, 21, 27, 28, 39, 40):
    EI of a number outside the module's table is refused (status 3, wrong type)."""
    w6212, w1180 = module(), module("PD86-1180")
    assert w6212(25, 8).status == 100 and w1180(25, 8).status == 3
    assert w6212(25, 42).status == 100 and w1180(25, 41).status == 3
    assert w1180(25, 40).status == 100 and w1180(25, 255).status == 100


def test_vect_255_is_a_wrong_type_vect_0_is_taken():
    """Manual 3.5.6.4 / Table 12: 255 "Global interrupts" is the switch of EI 255 / DI 255, not a
    vector: VECT 255 is refused with status 3 (wrong type, docs/assumptions.md "Interrupts
    (Table 12)"), before its address is looked at; VECT 0 (timer 0) with the same address is taken."""
    from opentmcl import VirtualModule

    vm = VirtualModule("TMCM-6212")
    assert vm.request(37, 255, 0, 0).status == 3
    assert vm.request(37, 255, 0, 10**6).status == 3
    assert vm.request(37, 0, 0, 0).status == 100


def test_di_drops_the_pending_occurrence_of_its_interrupt():
    """TMCM-6212 3.6.31 "DI <interrupt number>" disables an interrupt; docs/assumptions.md
    (Interrupts): "DI n drops n's pending occurrence": interrupt 21 occurring during the handler of
    15 is pending (3.5.6.2 "There is no interrupt nesting"); the handler's DI 21 drops it, so the
    EI 21 after it does not bring it back and handler 21 never runs."""
    src = ("VECT 15, Stall\nVECT 21, Dev\nEI 15\nEI 21\nEI 255\nIdle: JA Idle\n"
           "Stall: GGP 10, 2\n CALC ADD, 1\n AGP 10, 2\n WAIT TICKS, 0, 1\n DI 21\n EI 21\n RETI\n"
           "Dev: GGP 10, 2\n CALC ADD, 10\n AGP 10, 2\n RETI\n")
    w = module()
    w.load(src)
    w.run()
    w.vm.advance(20 * T)
    assert w.vm.interrupts.trigger(15)
    w.vm.advance(0.005)                       # inside handler 15 (its WAIT)
    assert w.vm.interrupts.active == 15
    assert w.vm.interrupts.trigger(21)        # latched, pending until RETI
    w.vm.advance(0.1)
    assert w.var(10) == 1 and w.vm.interrupts.active is None


def test_reti_right_after_power_up_is_ignored():
    """TMCM-6212 3.6.33 RETI ends an interrupt handling routine; docs/assumptions.md "Interrupts":
    "RETI outside a handler is ignored". A program started with 129 type 0 ("from current
    address", 3.6.36) just after power-up, whose first instruction is RETI, goes on to the next."""
    w = module()
    w.download([(38, 0, 0, 0), (19, 9, 0, 4), (28, 0, 0, 0)])
    w.run()
    w.vm.advance(10 * T)
    assert (w.a, w.state, w.vm.interpreter.last_error) == (4, 0, None)


def test_vect_takes_the_last_address_and_refuses_the_first_beyond():
    """TMCM-6212 3.6.32 "VECT <interrupt number>, <label>": the label is an address of the program
    memory (1 Features: 6144 commands, 0...6143). 6143 is set; 6144 is an invalid value (3.2.1
    Table 4 "4 Invalid value"), and the program goes on after it."""
    w = module()
    size = w.vm.program.size
    w.download([(37, 0, 0, size - 1), (37, 1, 0, size), (28, 0, 0, 0)])
    w.run()
    w.vm.advance(10 * T)
    assert w.vm.interrupts.vectors[0] == size - 1
    assert w.vm.interpreter.last_error == (1, 37, 4)
    assert (w.pc, w.state) == (2, 0)


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
