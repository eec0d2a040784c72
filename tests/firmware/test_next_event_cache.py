"""The next-event cache of `VirtualModule.advance_to` and the reads that run ahead of the motors
(docs/architecture.md "Time"): within one `advance` the next event of the engines, heartbeats,
timers and world is looked up again only after a write that can move it. Each test below lets the
program itself make such a write in the middle of one long `advance` (host commands come between
calls, which start afresh), pins the result to the manual, and compares it with the reference run:
every event looked up afresh and one event per instruction (the oracle, oracle.py)."""
from __future__ import annotations

from opentmcl import VirtualModule
from opentmcl.firmware.interpreter import EVENT, INSTRUCTION_TICKS
from opentmcl.motion import CLOCK_HZ

from .oracle import ReferenceModule
from .test_program_support import Wire

SLOT = INSTRUCTION_TICKS
MS = CLOCK_HZ // 1000


def started(source: str, scenario: dict | None = None, reference: bool = False, module: str = "TMCM-6212") -> Wire:
    """A TMCM-6212 (or `module`) with `source` downloaded and started at tick 0 (129 at now = 0)."""
    vm = (ReferenceModule if reference else VirtualModule)(module, address=1, scenario=scenario)
    w = Wire(vm)
    w.load(source)
    w.run()
    return w


def state(w: Wire) -> tuple:
    """Everything a run can differ in, read without host commands (they restart heartbeats)."""
    vm = w.vm
    axes = tuple((ax.engine.position, ax.engine.velocity) for ax in vm.axes)
    return (vm.now, vm.program_counter, vm.application_status, vm.accumulator, vm.x_register, vm.flags,
            tuple(vm.user_vars[:8]), axes, vm.interpreter.executed, tuple(vm.drain_events()))


def both(source: str, seconds: float, scenario: dict | None = None) -> Wire:
    """Run `source` for `seconds` in one `advance`, cached and in the reference mode; the two
    must agree. Returns the cached run."""
    fast, ref = started(source, scenario), started(source, scenario, reference=True)
    fast.vm.advance(seconds)
    ref.vm.advance(seconds)
    assert state(fast) == state(ref)
    assert fast.vm.interpreter.executed > 100
    return fast


COUNT_ISR = "T: GGP 0, 2\nCALC ADD, 1\nAGP 0, 2\nRETI"  # user variable 0 counts the interrupts


def test_interrupt_enabled_by_the_program_is_seen():
    """TMCM-6212 manual 3.5.6.4: VECT, the period "SGP <type>, 3, <value>", EI <interrupt>, EI 255;
    bank 3 parameter 0 "Timer 0 period ... [ms]". The program enables timer 0 only after 250
    instructions (25.4 ms): the cached limit from before had no timer in it.

    SGP at instruction 2 (tick 3200) starts the phase: expiries at 3200 + n * 16000. EI 0 is
    instruction 254 (tick 406400), so n = 26 (419200) .. 49 (787200) fall in the 50 ms: 24."""
    src = f"""
        VECT 0, T
        SGP 0, 3, 1
        EI 255
    L1: GGP 9, 2
        CALC ADD, 1
        AGP 9, 2
        COMP 50
        JC LT, L1
        EI 0
    L2: GAP 1, 0
        CALCX ADD
        JA L2
    {COUNT_ISR}"""
    w = both(src, 0.05)
    assert w.vm.user_vars[0] == 24
    assert w.vm.user_vars[9] == 50


def test_timer_period_shortened_by_the_program_is_seen():
    """Bank 3 parameter 0 "Time between two interrupts" written by the program from 10 ms to 1 ms
    while the timer runs: the next expiry comes earlier than the cached one. docs/assumptions.md:
    writing the period restarts the timer's phase.

    Timer at 10 ms from tick 3200 (instruction 2): interrupts at 163200, 323200 and 483200; each
    takes 5 slots (the dispatch at the expiry, then the 4 handler instructions, the count stored
    at the third). SGP 0, 3, 1 is instruction 305, at tick 305 * 1600 + 3 * 5 * 1600 = 512000.
    From there every ms: the count is stored at 512000 + n * 16000 + 4800 <= 800000 for
    n = 1 .. 17. In all 3 + 17."""
    src = f"""
        VECT 0, T
        SGP 0, 3, 10
        EI 0
        EI 255
    L1: GGP 9, 2
        CALC ADD, 1
        AGP 9, 2
        COMP 60
        JC LT, L1
        SGP 0, 3, 1
    L2: GAP 8, 0
        CALCX ADD
        JA L2
    {COUNT_ISR}"""
    w = both(src, 0.05)
    assert w.vm.user_vars[0] == 3 + 17


def test_heartbeat_set_by_the_program_stops_the_motor_in_time():
    """TMCM-6212 manual 5 GP68 "Serial heartbeat ... If this time limit is up and no further command
    is received by the module the motor will be stopped." The program turns it on (20 ms) while the
    motor turns and the program reads the axis: the last command (129) came at tick 0, so the motor
    stops at exactly 20 ms, inside one long `advance`."""
    src = "ROR 0, 1000\nSGP 68, 0, 20\nL: GAP 1, 0\nCALCX ADD\nJA L"
    w = started(src)
    w.vm.advance(20 * MS / CLOCK_HZ - 1 / CLOCK_HZ)        # the last tick before the limit
    assert w.vm.axes[0].engine.velocity != 0
    w.vm.advance(1 / CLOCK_HZ)
    assert w.vm.axes[0].engine.velocity == 0
    w2 = both(src, 0.03)
    assert w2.vm.axes[0].engine.velocity == 0


def test_input_edge_from_the_scenario_raises_its_interrupt_at_the_edge():
    """TMCM-6212 manual 3.5.6.1 interrupt 39 "Input change 0", bank 3 parameter 39 "Input 0 trigger
    transition 0=off, 1=low-high"; GP132 the tick timer (ms). The scenario raises input 0 at 12.3 ms;
    the handler, entered at the next instruction slot (12.4 ms), stores the tick timer: 12."""
    src = """
        VECT 39, I
        SGP 39, 3, 1
        EI 39
        EI 255
    L:  GAP 1, 0
        CALCX ADD
        GIO 0, 0
        JA L
    I:  GGP 132, 0
        AGP 1, 2
        GGP 0, 2
        CALC ADD, 1
        AGP 0, 2
        RETI"""
    w = both(src, 0.04, {"input": [{"bank": 0, "port": 0, "steps": [[0.0123, 1]]}]})
    assert (w.vm.user_vars[0], w.vm.user_vars[1]) == (1, 12)


def test_left_switch_stops_the_motor_and_raises_its_interrupt():
    """TMCM-6212 manual 3.5.6.1 interrupt 27 "Left stop switch 0", bank 3 parameter 27 "Stop left 0
    trigger transition" 1 = low-high; manual 4.1 AP11 left limit switch state, AP13 = 0: the switch
    stops the motor. The program moves left onto the switch at -2000 and reads the axis in a loop;
    the handler reads AP11 (1) and the position there (the switching point)."""
    src = """
        VECT 27, S
        SGP 27, 3, 1
        EI 27
        EI 255
        ROL 0, 2000
    L:  GAP 1, 0
        CALCX ADD
        JA L
    S:  GAP 11, 0
        AGP 1, 2
        GAP 1, 0
        AGP 2, 2
        RETI"""
    w = both(src, 1.5, {"axis": {"0": {"left": {"position": -2000}}}})
    assert w.vm.axes[0].engine.velocity == 0 and w.vm.axes[0].engine.position == -2000
    assert (w.vm.user_vars[1], w.vm.user_vars[2]) == (1, -2000)


def test_analog_input_is_read_at_the_instruction_tick():
    """TMCM-6212 manual 3.6.13 GIO bank 1: the analog inputs. A ramp 0 .. 4000 over 50 ms needs no
    events of its own; a GIO run ahead reads it at its own tick. GIO is instruction 3j (tick
    1600 * (3j + 1)); the last one within 30 ms is at tick 476800 (29.8 ms): 4000 * 29.8 / 50 = 2384,
    stored by the AGP after it (tick 478400)."""
    src = "L: GIO 0, 1\nAGP 0, 2\nJA L"
    w = both(src, 0.03, {"input": [{"bank": 1, "port": 0, "ramp": [[0, 0], [0.05, 4000]]}]})
    assert w.vm.user_vars[0] == 2384


def test_motion_started_by_the_program_moves_the_events():
    """TMCM-6212 manual 3.6.4 MVP and 3.6.20 "WAIT POS ... Wait until the target position of the
    motor ... has been reached"; 3.5.6.1 interrupt 3 "Target position reached 0". The program moves
    back and forth between 0 and 300 and reads the axis while it waits; every arrival is an engine
    event the cache must not skip."""
    src = """
        VECT 3, R
        EI 3
        EI 255
    L:  MVP ABS, 0, 300
    W1: GAP 8, 0
        JC ZE, W1
        MVP ABS, 0, 0
        WAIT POS, 0, 0
        JA L
    R:  GGP 0, 2
        CALC ADD, 1
        AGP 0, 2
        RETI"""
    w = both(src, 0.5)
    assert w.vm.user_vars[0] >= 2


def test_the_cache_holds_only_inside_advance():
    """A host command comes between two `advance` calls: every call looks the events up afresh,
    and next_event_in (the servers' sleep) answers from the present state."""
    w = started("L: GAP 1, 0\nJA L")
    w.vm.advance(0.001)
    assert not w.vm.scheduler.limit_held()
    w.ok(9, 0, 3, 5)                        # SGP 0, 3, 5: timer 0 at 5 ms (not enabled: no event)
    w.ok(25, 0, 0, 0)
    w.ok(25, 255, 0, 0)
    w.ok(37, 0, 0, 1)                       # VECT 0 to the loop itself
    assert w.vm.next_event_in() is not None
    assert not w.vm.scheduler.limit_held()


INVALIDATING = ["SGP 0, 3, 1", "SGP 68, 0, 5", "SGP 39, 3, 1", "EI 0", "DI 0", "EI 255", "VECT 0, 0",
                "SAP 181, 0, 100", "SAP 212, 0, 5", "SAP 4, 0, 100", "MVP ABS, 0, 100", "ROR 0, 10", "MST 0",
                "RFS START, 0", "WAIT TICKS, 0, 1", "STOP", "GAP 11, 0"]
KEEPING = ["GAP 1, 0", "GAP 8, 0", "GAP 4, 0", "GAP 207, 0", "GGP 132, 0", "GGP 3, 2", "GIO 0, 0", "GIO 0, 1", "SIO 0, 2, 1", "CLE 0",
           "CALC ADD, 1", "CALCX ADD", "COMP 5", "JA 0", "AGP 1, 2", "SGP 1, 2, 7"]


def test_which_instructions_look_the_events_up_again():
    """docs/architecture.md "Time": after a program instruction that can move an event (SGP of a
    timer period, heartbeat GP68 or input transition, EI/DI/VECT, SAP of the world's or the motion's
    parameters, motion, RFS, WAIT, STOP, a GAP the world computes) the cached limit is
    dropped: it is an event of the scheduler and never runs ahead. Pure instructions (CLE among
    them: the error flags are no event's), reads of the engines, GGP, GIO and SIO keep it (the
    command table's effects, firmware/table.py). Each instruction, executed by single step (130,
    manual 3.6.36) from a limit marked valid, drops it or leaves it as its kind says."""
    for line in INVALIDATING + KEEPING:
        w = started(f"{line}\nJA 0")
        kind, _effect, _step = w.vm.interpreter.compiled(w.vm.program.code[0])
        assert (kind == EVENT) is (line in INVALIDATING), line
        w.ok(128)                              # stop, then step from address 0
        w.ok(131)
        w.vm.scheduler._limit_ok = True
        w.vm.interpreter.step()
        assert w.pc != 0 or line.startswith(("WAIT", "STOP", "JA")), line
        assert w.vm.scheduler.limit_held() is (line in KEEPING), line


def test_wait_that_timed_out_during_an_interrupt_ends_after_reti():
    """TMCM-6212 manual 3.6.20 WAIT TICKS ("one tick is 10 milliseconds") and 3.5.6.2: the handler
    interrupts the WAIT, RETI continues the normal program. The WAIT starts at tick 8000 (deadline
    168000); timer 0 (1 ms from tick 3200) enters the handler at 19200 + 16000 k, the tenth time
    at 163200, and its RETI comes at 169600, after the deadline: the WAIT ends at the tick after
    RETI (169601) and the next instruction follows one slot later (171201)."""
    src = """
        VECT 0, T
        SGP 0, 3, 1
        EI 0
        EI 255
    L:  WAIT TICKS, 0, 1
        GGP 9, 2
        CALC ADD, 1
        AGP 9, 2
        JA L
    T:  GGP 0, 2
        CALC ADD, 1
        AGP 0, 2
        RETI"""
    w = started(src)
    w.vm.advance(171200 / CLOCK_HZ)
    assert w.vm.interpreter.wait is None and w.vm.program_counter == 5
    assert (w.vm.user_vars[0], w.vm.interpreter.executed) == (10, 4 + 1 + 10 * 4)
    w.vm.advance(1 / CLOCK_HZ)
    assert w.vm.interpreter.executed == 4 + 1 + 10 * 4 + 1   # GGP 9, 2 at 171201
    both(src, 0.05)


def test_world_check_between_events_moves_the_next_one():
    """docs/world.md: a load over time is checked at every event tick ("re-evaluated every
    millisecond"); TMCM-6212 manual 4.1 AP212 "Maximum encoder deviation", 3.5.6.1 interrupt 21
    "Deviation axis 0". A rising load makes the motor lose steps at one of the program's ticks;
    from there counter and encoder drift apart, and the deviation limit is crossed before the next
    millisecond of the load: the check that found the step loss must make the module look again."""
    src = """
        VECT 21, D
        EI 21
        EI 255
        SAP 212, 0, 40
        ROR 0, 20000
    L:  GAP 1, 0
        CALCX ADD
        JA L
    D:  GAP 1, 0
        AGP 1, 2
        RETI"""
    w = both(src, 0.3, {"axis": {"0": {"load": {"by": "time", "ramp": [[0, 0.0], [0.3, 1.5]]}}}})
    assert w.vm.user_vars[1] != 0 and w.vm.axes[0].engine.velocity == 0
