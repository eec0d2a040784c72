"""Events taken inside the program's run (docs/architecture.md "Time"; docs/performance.md "Round 25"):
while a program runs, the interpreter takes the module's next event itself (a timer expiring, an
interrupt entered, an instruction that cannot run ahead) exactly as `advance_to`'s loop would, and
goes on running ahead after it. The result must be the reference's: every event looked up afresh
and one event per instruction (the oracle, oracle.py).

TMCM-6212 manual 3.5.6 (interrupt processing: VECT, EI, RETI), 3.5.6.1 (interrupt numbers 0-2
timers, 3 target position reached 0, 27 left stop switch 0, 39 input change 0), bank 3 (timer
periods in ms, trigger transitions), 3.6.20 (WAIT), 3.6.1-3.6.4 (ROR, ROL, MST, MVP)."""
from __future__ import annotations

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from opentmcl.firmware.interpreter import INSTRUCTION_TICKS

from .test_carry import loop_lookups
from .test_next_event_cache import started
from .test_next_event_cache import state as program_state


def state(w) -> tuple:
    """The program's state (test_next_event_cache.state), the engines' segment plans (a motor
    stopped one tick later has another plan), timers, pending and active interrupts, the WAIT, the
    subroutine stack, the saved context, the last error, the next instruction's tick, the I/O."""
    vm = w.vm
    plans = tuple((e.now, tuple(tuple(p) for p in getattr(e, "_queue", e).pieces)) if hasattr(e, "_queue")
                  else (e.now, e.position, e.velocity) for e in (ax.engine for ax in vm.axes))
    ints, it = vm.interrupts, vm.interpreter
    return (program_state(w), plans, tuple(ints._due), tuple(sorted(ints.pending)), ints.active,
            vm.heartbeats.fired, it.wait, tuple(it.stack), it.saved, it.last_error, it.next_time,
            tuple(sorted(vm.io.values.items())))


TIMER_LOOP = """
    VECT 0, T
    SGP 0, 3, 1
    EI 0
    EI 255
L:  GGP 0, 2
    CALC ADD, 1
    AGP 0, 2
    GAP 1, 0
    JA L
T:  GGP 1, 2
    CALC ADD, 1
    AGP 1, 2
    RETI"""


def test_timer_interrupts_are_taken_inside_the_run():
    """Bank 3 parameter 0 "Timer 0 period" = 1 ms: 50 interrupts in 50 ms, each entered at an
    instruction slot (3.5.6: the interrupt is handled before the next instruction). The handler
    counts them in user variable 1; the run takes every one of them without going back to
    `advance`'s loop (a handful of passes, not one or more per millisecond), and agrees with the
    reference, which takes one event per instruction."""
    w = started(TIMER_LOOP)
    loop = loop_lookups(w.vm)
    ref = started(TIMER_LOOP, reference=True)
    ref_loop = loop_lookups(ref.vm)
    w.vm.advance(0.05)
    ref.vm.advance(0.05)
    assert state(w) == state(ref)
    # SGP 0, 3, 1 is the 2nd instruction (tick 3200): expiries at 3200 + n * 16000 up to 0.05 s
    assert w.vm.user_vars[1] in (49, 50)
    assert ref_loop[0] >= w.vm.interpreter.executed  # the reference: an event per instruction
    assert loop[0] <= 3


def test_a_world_acting_at_every_tick_takes_the_loop_path():
    """A load over time (scenario `load.by` "time") is checked at every event tick (World.quiet
    False): the events the run takes inside are the full ones (`VirtualModule._event_at`); the
    counts and states equal the reference's."""
    scenario = {"axis": {"0": {"load": {"by": "time", "ramp": [[0, 0.0], [0.04, 0.9]]}}}}
    w, ref = started(TIMER_LOOP, scenario), started(TIMER_LOOP, scenario, reference=True)
    w.vm.advance(0.05)
    ref.vm.advance(0.05)
    assert state(w) == state(ref)
    assert w.vm.user_vars[1] in (49, 50)


def test_an_instruction_that_cannot_run_ahead_is_taken_inside_the_run():
    """MVP REL (3.6.4), WAIT POS and WAIT TICKS (3.6.20: "1 POS - target position reached",
    "0 TICKS - timer ticks (10 ms)") in the loop, then a counting loop: each is an event of its own; the run takes them
    and the motion's events (target reached: interrupt 3) inside it, with the reference's result.
    The handler counts the arrivals: one per move."""
    src = """
        VECT 3, R
        EI 3
        EI 255
        SAP 4, 0, 2047
        SAP 5, 0, 2047
    L:  MVP REL, 0, 50
        WAIT POS, 0, 0
        WAIT TICKS, 0, 1
        CALC LOAD, 20
    I:  CALC SUB, 1
        COMP 0
        JC NE, I
        JA L
    R:  GGP 2, 2
        CALC ADD, 1
        AGP 2, 2
        RETI"""
    w, ref = started(src), started(src, reference=True)
    w.vm.advance(1.0)
    ref.vm.advance(1.0)
    assert state(w) == state(ref)
    moves = w.vm.axes[0].engine.position // 50
    assert moves > 3
    assert w.vm.user_vars[2] in (moves - 1, moves)


def test_a_timer_expiring_with_the_heartbeat_stops_the_motor_there():
    """TMCM-6212 manual 3.6.9 GP68 "Serial heartbeat ... If this time limit is up and no further
    command is received the motor will be stopped" (5 ms here), timer 0 every 1 ms: both set by the
    host at the same tick, so the heartbeat's deadline is the timer's fifth expiry. That event is
    the heartbeat's too: the motor stops exactly there, as in the reference."""
    def prepared(reference: bool):
        w = started(TIMER_LOOP, reference=reference)
        w.vm.advance(0.001)  # the program has run VECT, SGP, EI, EI
        w.ok(1, 0, 0, 800)   # ROR 0: a moving motor
        w.ok(9, 0, 3, 1)     # timer 0: 1 ms, phase from now
        w.ok(9, 68, 0, 5)    # heartbeat 5 ms
        return w
    w, ref = prepared(False), prepared(True)
    w.vm.advance(0.01)
    ref.vm.advance(0.01)
    assert state(w) == state(ref)
    assert w.vm.heartbeats.fired and w.vm.axes[0].engine.velocity == 0


def test_wait_pos_on_another_axis_waits_while_it_rotates():
    """TMCM-6212 manual 3.6.20 WAIT POS: "wait for target position reached"; ROR (3.6.1) rotates
    motor 1, so its target is never reached and the WAIT goes on, also after a GAP of motor 0
    (which brings only motor 0's engine to its tick) and with the world watching motor 0 (AP181,
    stop on stall: events of their own)."""
    for src, at in (("ROR 1, 3000\nGAP 1, 0\nWAIT POS, 1, 0\nAGP 0, 2\nSTOP", 2),
                    ("SAP 181, 0, 50000\nROR 0, 3000\nCALC ADD, 1\nWAIT POS, 0, 0\nAGP 0, 2\nSTOP", 3)):
        w, ref = started(src), started(src, reference=True)
        for vm in (w.vm, ref.vm):
            vm.advance(0.01)
        assert state(w) == state(ref)
        assert w.vm.interpreter.wait is not None and w.vm.program_counter == at


def test_an_active_shutdown_pin_sets_esd_again_after_cle():
    """PD86-1180 GP80 = 1 (SHUTDOWN input high active) with the pin high from the start: the ESD
    flag is set at every event while the pin is active (TMCM-6212 3.6.29 CLE clears it, 3.6.16 JC
    condition ESD tests it), so in each pass CLE 0 is followed by a JC ESD that is taken. A pass is
    6 instructions after the first (SGP): (100 - 1) // 6 = 16 passes in 10 ms, every one counted."""
    src = "SGP 80, 0, 1\nL: CLE 0\nJC ESD, Hit\nJA L\nHit: GGP 0, 2\nCALC ADD, 1\nAGP 0, 2\nJA L"
    scenario = {"shutdown": {"steps": [[0.0, 1]]}}
    w, ref = started(src, scenario, module="PD86-1180"), started(src, scenario, reference=True, module="PD86-1180")
    for vm in (w.vm, ref.vm):
        vm.advance(0.01)
    assert state(w) == state(ref)
    assert w.vm.user_vars[0] == 16


def test_erasing_the_program_from_inside_leaves_the_pc_at_0():
    """GP81 protection switched off by the program erases it; the running program is reset first
    (command 131, docs/assumptions.md): status reset and program counter 0 (135 type 1)."""
    src = "SGP 81, 0, 1\nCALC ADD, 1\nSGP 81, 0, 0\nSTOP"
    w = started(src)
    w.vm.advance(0.01)
    assert w.ok(135, 1) == 3 << 24
    assert (w.vm.application_status, w.vm.program_counter) == (3, 0)


HANDLERS = """
T0: GGP 0, 2
    CALC ADD, 1
    AGP 0, 2
    RETI
T1: GAP 1, 0
    AGP 1, 2
    RETI
R0: GGP 132, 0
    AGP 2, 2
    MVP REL, 0, 400
    RETI
S0: GAP 11, 0
    AGP 3, 2
    ROR 0, 900
    RETI
I0: GIO 0, 0
    AGP 4, 2
    RETI"""
SOURCES = {0: "T0", 1: "T1", 3: "R0", 27: "S0", 39: "I0"}
MAIN = ["GAP 1, 0", "CALCX ADD", "GIO 0, 0", "GGP 132, 0", "MVP REL, 0, 700", "MVP REL, 1, -300", "WAIT POS, 0, 3",
        "SAP 4, 0, 1500", "WAIT TICKS, 0, 1", "SIO 0, 2, 1", "ROL 0, 900", "MST 0", "SGP 0, 3, 2",
        "COMP 0\n    JC EQ, Main", "CSUB Sub", "GAP 8, 0", "CALC ADD, 3"]
SCENARIOS = [
    None,
    {"axis": {"0": {"left": {"position": -1500}, "right": {"position": 2500}}}},
    {"axis": {"1": {"load": {"by": "time", "ramp": [[0, 0.0], [0.4, 0.9]]}}}},
    {"axis": {"0": {"load": {"by": "position", "steps": [[900, 0.95]]}}},
     "input": [{"bank": 0, "port": 0, "steps": [[0.013, 1], [0.031, 0]]}]},
]


def program(periods: tuple[int, int], enabled: list[int], main: list[str]) -> str:
    lines = [f"    VECT {n}, {label}" for n, label in SOURCES.items()]
    lines += [f"    SGP 0, 3, {periods[0]}", f"    SGP 1, 3, {periods[1]}", "    SGP 27, 3, 1", "    SGP 39, 3, 3"]
    lines += [f"    EI {n}" for n in enabled] + ["    EI 255", "Main:"]
    lines += [f"    {ins}" for ins in main] + ["    JA Main", "Sub: CALC ADD, 1", "    RSUB"]
    return "\n".join(lines) + HANDLERS


@settings(max_examples=60, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(st.sampled_from(range(len(SCENARIOS))),
       st.tuples(st.integers(0, 3), st.integers(0, 4)),
       st.lists(st.sampled_from(sorted(SOURCES)), max_size=5, unique=True),
       st.lists(st.sampled_from(MAIN), min_size=1, max_size=8),
       st.lists(st.integers(1, 300), min_size=1, max_size=6))
def test_runs_with_interrupts_equal_the_reference(scenario, periods, enabled, main, chunks):
    """Random programs: timers with periods 0-4 ms, target-reached, stop-switch and input-change
    interrupts, a main loop of reads, motion, WAITs, outputs, jumps and a subroutine, on worlds with
    switches, loads by time and position and an input signal, advanced in chunks of 0.1-30 ms; the
    module and the reference agree after every chunk."""
    src = program(periods, enabled, main)
    fast = started(src, SCENARIOS[scenario])
    ref = started(src, SCENARIOS[scenario], reference=True)
    for n in chunks:
        fast.vm.advance(n * INSTRUCTION_TICKS / 16_000_000)
        ref.vm.advance(n * INSTRUCTION_TICKS / 16_000_000)
        assert state(fast) == state(ref), src


SINGLE_MAIN = [ins for ins in MAIN if ", 1," not in ins] + ["SGP 80, 0, 1", "CLE 0", "JC ESD, Main", "SIO 0, 2, 0"]
EXTENDED = ["CALCVV ADD, 1, 2", "CALCVA SUB, 3", "CALCAV ADD, 3", "CALCV MUL, 4, 3", "DJNZ 5, Main",
            "CALC LOAD, 2\n    CALCX LOAD\n    GIV", "CALL ZE, Sub"]
SINGLE_SCENARIOS = [
    None,
    {"axis": {"0": {"left": {"position": -1500}, "right": {"position": 2500}}}},
    {"axis": {"0": {"load": {"by": "position", "steps": [[900, 0.95]]}}},
     "input": [{"bank": 0, "port": 0, "steps": [[0.013, 1], [0.031, 0]]}]},
    {"shutdown": {"steps": [[0.004, 1], [0.009, 0], [0.02, 1]]}},
]


@settings(max_examples=40, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(st.sampled_from(["PD86-1180", "PD28-1021"]), st.sampled_from(range(len(SINGLE_SCENARIOS))),
       st.tuples(st.integers(0, 3), st.integers(0, 4)),
       st.lists(st.sampled_from(sorted(SOURCES)), max_size=5, unique=True),
       st.lists(st.sampled_from(SINGLE_MAIN + EXTENDED), min_size=1, max_size=8),
       st.lists(st.integers(1, 300), min_size=1, max_size=6))
def test_single_axis_runs_equal_the_reference(module, scenario, periods, enabled, main, chunks):
    """The same on the single-axis modules: the PD86-1180 (TMC429 engine; a SHUTDOWN pin that goes
    active and back, GP80 = 1 set by the program, CLE and JC ESD, PD86-1180 manual 4.6) and the
    PD28-1021 with its extended set (CALCVV, CALCVA, CALCAV, CALCV, DJNZ, GIV, CALL; PD28-1021
    manual 3.5 Table 5; on the PD86-1180 they are invalid commands, `last_error`)."""
    src = program(periods, enabled, main)
    sc = SINGLE_SCENARIOS[scenario]
    if sc is not None and "shutdown" in sc and module != "PD86-1180":
        sc = None
    fast = started(src, sc, module=module)
    ref = started(src, sc, reference=True, module=module)
    for n in chunks:
        fast.vm.advance(n * INSTRUCTION_TICKS / 16_000_000)
        ref.vm.advance(n * INSTRUCTION_TICKS / 16_000_000)
        assert state(fast) == state(ref), src
