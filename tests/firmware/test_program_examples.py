"""Every example program of the manuals (examples/*.tmc), assembled and run on the matching
virtual module through the wire (132, instructions, 133, 129), does what the manual says."""
from __future__ import annotations

from pathlib import Path

import pytest

from opentmcl.lang.assembler import assemble_file

from .test_program_support import module

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
ALL = sorted(p.name for p in EXAMPLES.glob("*.tmc"))


def module_of(name: str) -> str:
    return "PD86-1180" if name.startswith("pd86_1180") else "TMCM-6212"


def start(name: str, run_from: int | None = None):
    w = module(module_of(name))
    prog = assemble_file(EXAMPLES / name, module=module_of(name))
    w.download(prog.instructions)
    w.run(run_from)
    return w, prog


def positions_visited(w, seconds: float, step: float = 0.01) -> set[int]:
    """The targets (AP0) the program moved to whose position the motor then reached. Sampled
    finely from the first change of target on (the loop is running then), the motor's extreme
    positions equal those targets (the ramp turns there with velocity 0, so a sample near the
    turn is within a microstep or two of it)."""
    targets, low, high = set(), None, None
    first = w.ok(6, 0, 0)
    started = False
    for _ in range(round(seconds / step)):
        w.vm.advance(step)
        target = w.ok(6, 0, 0)
        started = started or target != first
        if not started:
            continue
        targets.add(target)
        p = w.ok(6, 1, 0)
        low = p if low is None else min(low, p)
        high = p if high is None else max(high, p)
    return {t for t in targets if abs(t - low) <= 2 or abs(t - high) <= 2}


def test_there_are_examples_from_both_full_manuals():
    assert len(ALL) >= 15
    assert {module_of(n) for n in ALL} == {"TMCM-6212", "PD86-1180"}


@pytest.mark.parametrize("name", ALL)
def test_every_example_assembles_and_runs_without_errors(name):
    """Each example assembles for its module and runs 3 s without an instruction being refused
    (the PD86-1180 timer example's SIO 3 is the exception: that module has no OUT3)."""
    w, prog = start(name)
    w.vm.advance(3.0)
    if name == "pd86_1180_4.4.2.6.5_timer_interrupt.tmc":
        assert w.vm.interpreter.last_error[1:] == (14, 3)
    else:
        assert w.vm.interpreter.last_error is None
    assert w.vm.interpreter.executed > 0


@pytest.mark.parametrize(("name", "v1", "v2", "targets"), [
    ("tmcm6212_2.4_first_program.tmc", -51200, 51200, {512000, -512000}),
    ("pd86_1180_3.3_first_program.tmc", -500, 250, {10000, -10000}),
])
def test_first_program(name, v1, v2, targets):
    """TMCM-6212 2.4 / PD86-1180 first steps: rotate left 5 s (WAIT TICKS, 0, 500), right 5 s, then
    move between two positions forever."""
    w, _ = start(name)
    w.vm.advance(2.5)
    assert w.ok(6, 2, 0) == v1
    w.vm.advance(5.0)
    assert w.ok(6, 2, 0) == v2
    w.vm.advance(2.6)
    seen = positions_visited(w, 60.0)
    assert targets <= seen


@pytest.mark.parametrize(("name", "targets"), [
    ("tmcm6212_3.6.17_jump_always_loop.tmc", {51200, 0}),
    ("pd86_1180_4.6.19_jump_always_loop.tmc", {10000, 0}),
    ("tmcm6212_3.6.18_call_subroutine.tmc", {10000, 0}),
    ("pd86_1180_4.6.20_call_subroutine.tmc", {10000, 0}),
    ("tmcm6212_7.2_main_loop.tmc", {5000, 0}),
    ("pd86_1180_8.2_main_loop.tmc", {5000, 0}),
    ("tmcm6212_7.3_symbolic_constants.tmc", {500000, 0}),
    ("pd86_1180_8.3_symbolic_constants.tmc", {5000, 0}),
])
def test_loops_alternate_between_two_positions(name, targets):
    """3.6.17 / 4.6.19 JA "An infinite loop", 3.6.18 CSUB example, 7.2 / 8.2 main loop, 7.3 / 8.3 symbolic
    constants: the motor keeps moving between the two positions and stops at each."""
    w, _ = start(name)
    seen = positions_visited(w, 45.0)
    assert seen == targets
    assert w.state == 1


def test_csub_example_waits_half_a_second_at_each_position():
    """3.6.18: SubW does WAIT POS then WAIT TICKS, 0, 50: the motor rests 500 ms at each end."""
    w, _ = start("tmcm6212_3.6.18_call_subroutine.tmc")
    rest, longest = 0, 0
    for _ in range(600):
        w.vm.advance(0.005)
        rest = rest + 1 if w.ok(6, 3, 0) == 0 else 0
        longest = max(longest, rest)
    assert 99 <= longest <= 101                # 500 ms in 5 ms samples


@pytest.mark.parametrize("name", ["tmcm6212_3.6.27_potentiometer.tmc", "pd86_1180_4.6.29_potentiometer.tmc"])
def test_potentiometer_example_follows_the_analog_input(name):
    """3.6.27 / 4.6.29 AAP example: "Position motor #0 by a potentiometer connected to analogue input
    #0": target position = 4 * ADC value, followed as the input changes."""
    w, _ = start(name)
    for adc in (302, 1000, 17):
        w.vm.io.drive_input(1, 0, adc)
        w.vm.advance(0.01)
        assert w.ok(6, 0, 0) == 4 * adc
        for _ in range(240):                  # at most 60 s to get there
            if w.ok(6, 1, 0) == 4 * adc:
                break
            w.vm.advance(0.25)
        assert w.ok(6, 1, 0) == 4 * adc and w.ok(6, 0, 0) == 4 * adc


def test_compare_example_rotates_only_from_1000_on():
    """3.6.15 / 3.6.16: "Jump to the address given by the label when the position of motor #0 is
    greater than or equal to 1000" - Label: ROL 0, 1000."""
    for position, velocity in ((999, 0), (1000, -1000)):
        w = module()
        w.ok(5, 1, 0, position)
        w.download(assemble_file(EXAMPLES / "tmcm6212_3.6.15_compare_and_jump.tmc",
                                 module="TMCM-6212").instructions)
        w.run()
        w.vm.advance(0.01)
        assert w.ok(6, 2, 0) == velocity


@pytest.mark.parametrize("name", ["tmcm6212_7.4_user_variables.tmc", "pd86_1180_8.4_user_variables.tmc"])
def test_user_variables_example(name):
    """7.4 / 8.4: SGP MyVariable, 2, 1234; GGP; CALC MUL, 2; store back: variable 42 holds 2468."""
    w, _ = start(name)
    w.vm.advance(0.01)
    assert w.var(42) == 2468 and w.state == 0


def test_inputs_to_outputs_example_mirrors_the_inputs():
    """PD86-1180 4.6.14: "The following program will show the states of the input lines on the
    output lines" (GIO 255, 0 / SIO 255, 2, -1: "the contents of the lower 8 bits of the
    accumulator are copied to the output pins")."""
    w, _ = start("pd86_1180_4.6.14_inputs_to_outputs.tmc")
    for in0, in1 in ((1, 0), (0, 1), (1, 1), (0, 0)):
        w.vm.io.drive_input(0, 0, in0)
        w.vm.io.drive_input(0, 1, in1)
        w.vm.advance(0.01)
        assert (w.out(0), w.out(1)) == (in0, in1)
    assert w.state == 1


@pytest.mark.parametrize("name", ["tmcm6212_7.6_host_routines.tmc", "pd86_1180_8.6_host_routines.tmc"])
def test_host_callable_routines(name):
    """7.6 / 8.6: "They can be called from a host by issuing a run command with address 0 to call
    the first function, or ... address 1 ... the second ..., or ... address 2 ... the third"."""
    w, prog = start(name, run_from=0)        # Func1: to 1000 and back to 0, then STOP
    assert prog.labels["Func1"] == 0 and prog.labels["Func2"] == 1 and prog.labels["Func3"] == 2
    seen = positions_visited(w, 30.0)
    assert seen == {1000, 0} and w.state == 0
    w.run(1)                                  # Func2: ROL 0, 500 for 100 ticks, then MST
    w.vm.advance(0.5)
    assert w.ok(6, 2, 0) == -500
    w.vm.advance(1.0)
    assert w.ok(6, 2, 0) == 0 and w.state == 0
    w.run(2)                                  # Func3: ROR 0, 1000 for 700 ticks
    w.vm.advance(6.5)
    assert w.ok(6, 2, 0) == 1000 and w.state == 1
    w.vm.advance(1.0)
    assert w.ok(6, 2, 0) == 0 and w.state == 0


def test_pd86_timer_example_toggles_out0():
    """PD86-1180 4.4.2.6.5: the timer 0 handler toggles OUT0 every 1000 ms (just after each full
    second: the handler's SIO runs a few instruction times after the timer fires)."""
    w, _ = start("pd86_1180_4.4.2.6.5_timer_interrupt.tmc")
    levels = []
    for _ in range(8):
        w.vm.advance(0.5)
        levels.append(w.out(0))
    assert levels == [0, 0, 1, 1, 0, 0, 1, 1]
