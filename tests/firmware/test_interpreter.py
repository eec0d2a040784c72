"""The TMCL interpreter: accumulator, X register, flags, calculation, branches, subroutines, WAIT
(TMCM-6212 manual 3.5.5, 3.6.14-3.6.29; PD86-1180 manual 4.6.16-4.6.31)."""
from __future__ import annotations

import pytest

from opentmcl import VirtualModule
from opentmcl.firmware import flags
from opentmcl.firmware.interpreter import INSTRUCTION_TICKS
from opentmcl.firmware.wait import TICK
from opentmcl.motion import CLOCK_HZ

from .oracle import ReferenceModule
from .test_program_support import STOP, T, Wire, module, run_program
from .test_program_support import run_raw as _run_raw

INT_MIN, INT_MAX = -(2**31), 2**31 - 1


def accu_after(source: str, name: str = "TMCM-6212", seconds: float = 0.05) -> int:
    return run_program(source, seconds, name).a


def test_reading_commands_load_the_accumulator_only_in_a_program():
    """3.5.5: "When executed in a TMCL program ... all TMCL commands that read a value store the
    result in the accumulator ... When a command that reads a value is executed in direct mode the
    accumulator will not be affected."""
    w = module()
    w.ok(5, 4, 0, 12345)
    assert w.ok(6, 4, 0) == 12345 and w.a == 0    # direct GAP: A untouched
    w.load("GAP 4, 0\nSTOP")
    w.run()
    w.vm.advance(5 * T)
    assert w.a == 12345
    w.ok(9, 7, 2, -99)
    w.load("GGP 7, 2\nCALCX LOAD\nGIO 1, 2\nSTOP")   # GGP, then GIO of OUT1 (0)
    w.run(0)
    w.vm.advance(5 * T)
    assert (w.x, w.a) == (-99, 0)


@pytest.mark.parametrize(("op", "a", "operand", "result"), [
    ("ADD", 5, 7, 12), ("ADD", INT_MAX, 1, INT_MIN),          # 32-bit wrap
    ("SUB", 5, 7, -2), ("SUB", INT_MIN, 1, INT_MAX),
    ("MUL", 3, -5000, -15000), ("MUL", 65536, 65536, 0),
    ("DIV", 7, 2, 3), ("DIV", -7, 2, -3), ("DIV", 7, 0, 0), ("DIV", INT_MIN, -1, INT_MIN),
    ("MOD", 7, 3, 1), ("MOD", -7, 3, -1), ("MOD", 7, 0, 7),
    ("AND", 0b1100, 0b1010, 0b1000), ("OR", 0b1100, 0b1010, 0b1110), ("XOR", 0b1100, 0b1010, 0b0110),
    ("NOT", 0, 123, -1), ("LOAD", 99, -42, -42),
])
def test_calc_operations(op, a, operand, result):
    """3.6.14 CALC: ADD, SUB, MUL, DIV, MOD, AND, OR, XOR, NOT ("logical invert accumulator"),
    LOAD, on 32-bit two's complement; division by zero: DIV gives 0, MOD leaves A
    (docs/assumptions.md)."""
    assert accu_after(f"CALC LOAD, {a}\nCALC {op}, {operand}\nSTOP") == result


def test_calc_mul_manual_example():
    """3.6.14 example: "Multiply accumulator by -5000. Mnemonic: CALC MUL, -5000"."""
    assert accu_after("CALC LOAD, 3\nCALC MUL, -5000\nSTOP") == -15000


@pytest.mark.parametrize(("op", "a", "x", "new_a", "new_x"), [
    ("ADD", 5, 3, 8, 3), ("SUB", 5, 3, 2, 3), ("MUL", 5, 3, 15, 3), ("DIV", 7, 2, 3, 2),
    ("MOD", 7, 2, 1, 2), ("AND", 6, 3, 2, 3), ("OR", 6, 3, 7, 3), ("XOR", 6, 3, 5, 3),
    ("NOT", 6, 3, 6, -4),      # "logical invert X register"
    ("LOAD", 6, 3, 6, 6),      # "copy accumulator to X register"
    ("SWAP", 6, 3, 3, 6),      # "swap accumulator and X register"
    ("DIV", 7, 0, 0, 0),
])
def test_calcx_operations(op, a, x, new_a, new_x):
    """3.6.26 CALCX: the second operand is the X register; types 8-10 act on X."""
    w = run_program(f"CALC LOAD, {x}\nCALCX LOAD\nCALC LOAD, {a}\nCALCX {op}\nSTOP", 0.01)
    assert (w.a, w.x) == (new_a, new_x)


@pytest.mark.parametrize(("a", "b", "taken"), [
    (5, 5, {"ZE", "EQ", "GE", "LE"}),
    (6, 5, {"NZ", "NE", "GT", "GE"}),
    (-6, 5, {"NZ", "NE", "LT", "LE"}),
])
def test_comp_and_jc_conditions(a, b, taken):
    """3.6.15 COMP sets the arithmetic flags (signed compare); 3.6.16 JC ZE..LE jump on them."""
    for cond in ("ZE", "NZ", "EQ", "NE", "GT", "GE", "LT", "LE"):
        src = f"CALC LOAD, {a}\nCOMP {b}\nJC {cond}, Yes\nCALC LOAD, 0\nSTOP\nYes: CALC LOAD, 1\nSTOP"
        assert accu_after(src) == (1 if cond in taken else 0), cond


def test_comp_manual_example_jump_if_position_ge_1000():
    """3.6.15 / 3.6.16 example: "GAP 1, 0; COMP 1000; JC GE, Label" jumps when the actual
    position of motor 0 is greater than or equal to 1000."""
    src = "GAP 1, 0\nCOMP 1000\nJC GE, Label\nCALC LOAD, 0\nSTOP\nLabel: CALC LOAD, 1\nSTOP"
    for position, expected in ((999, 0), (1000, 1), (51200, 1), (-2000, 0)):
        w = module()
        w.ok(5, 1, 0, position)
        w.load(src)
        w.run()
        w.vm.advance(0.01)
        assert w.a == expected, position


def test_zero_flag_follows_loaded_value():
    """3.5.6.4 example: "GIO 0, 2 //check if OUT0 is high; JC NZ, Out0Off" - a value loaded into the
    accumulator sets the flags JC ZE / NZ test, without a COMP."""
    for out0, expected in ((0, 0), (1, 1)):
        w = module()
        w.ok(14, 0, 2, out0)
        w.load("GIO 0, 2\nJC NZ, High\nCALC LOAD, 0\nSTOP\nHigh: CALC LOAD, 1\nSTOP")
        w.run()
        w.vm.advance(0.01)
        assert w.a == expected


@pytest.mark.parametrize(("flag", "cle", "cond"), [
    (flags.ETO, "ETO", "ETO"), (flags.EAL, "EAL", "EAL"), (flags.EDV, "EDV", "EDV"),
    (flags.EPO, "EPO", "EPO"), (flags.ESD, "ESD", "ESD"),
])
def test_error_flag_conditions_and_cle(flag, cle, cond):
    """3.6.16 JC 8-11 ETO, EAL, EDV, EPO; PD86-1180 4.6.18 JC 12 ESD; 3.6.29 CLE clears one flag
    (or ALL) and leaves the others."""
    w = module()
    w.load(f"JC {cond}, Set\nCALC LOAD, 0\nSTOP\nSet: CALC LOAD, 1\nCLE {cle}\nJC {cond}, Set\nSTOP")
    other = flags.EAL if flag != flags.EAL else flags.ETO
    w.vm.interpreter.set_error_flag(flag | other)
    w.run()
    w.vm.advance(0.01)
    assert w.a == 1
    assert not w.vm.flags & flag
    assert w.vm.flags & flags.ERROR_MASK      # the other flag survived
    w.load("CLE ALL\nSTOP")
    w.run(0)
    w.vm.advance(0.01)
    assert not w.vm.flags & flags.ERROR_MASK


def test_cle_all_keeps_the_comparison_result():
    """3.6.29 "CLE ALL - all [error] flags": the arithmetic flags of COMP are not error flags."""
    w = run_program("CALC LOAD, 5\nCOMP 5\nCLE ALL\nJC EQ, Yes\nSTOP\nYes: CALC LOAD, 1\nSTOP", 0.01)
    assert w.a == 1


def test_ja_infinite_loop_and_csub_example_alternate_positions():
    """3.6.17 JA and 3.6.18 CSUB example: "MVP ABS, 0, 10000; CSUB SubW; MVP ABS, 0, 0; CSUB SubW;
    JA Loop / SubW: WAIT POS, 0, 0; WAIT TICKS, 0, 50; RSUB" alternates between the two positions."""
    src = """Loop:
    MVP ABS, 0, 10000
    CSUB SubW
    MVP ABS, 0, 0
    CSUB SubW
    JA Loop
SubW:
    WAIT POS, 0, 0
    WAIT TICKS, 0, 50
    RSUB"""
    w = module()
    w.load(src)
    w.run()
    seen = set()
    for _ in range(200):
        w.vm.advance(0.05)
        if w.vm.axes[0].engine.position_reached:
            seen.add(w.ok(6, 1, 0))
    assert seen == {0, 10000}
    assert len(w.vm.interpreter.stack) <= 1


def test_subroutine_stack_is_eight_deep():
    """3.6.18: "The number of entries in the internal stack is limited to 8 ... The command will be
    ignored if there is no more stack space left." 3.6.19: RSUB "will be ignored if the stack is
    empty"."""
    nested = "\n".join(f"S{i}: CALC ADD, 1\nCSUB S{i + 1}\nCALCX LOAD\nRSUB" for i in range(10))
    src = f"CSUB S0\nSTOP\n{nested}\nS10: RSUB"
    w = run_program(src, 0.05)
    # CSUB S0 .. CSUB S7 fill the 8 entries; the CSUB S8 in S7 is ignored, S7 returns.
    assert w.a == 8
    assert w.state == 0 and w.pc == 1 and w.vm.interpreter.stack == []
    w = run_program("RSUB\nCALC LOAD, 5\nSTOP", 0.01)
    assert w.a == 5


def test_wait_ticks_are_10_ms():
    """3.6.20 WAIT TICKS: "one tick is 10 milliseconds". Each instruction takes 100 µs of virtual
    time (docs/assumptions.md): SIO at T, WAIT at 2T, next SIO at 2T + 500 ms + T."""
    assert INSTRUCTION_TICKS == 1600
    w = module()
    w.load("SIO 0, 2, 1\nWAIT TICKS, 0, 50\nSIO 0, 2, 0\nSTOP")
    w.run()
    w.vm.advance(3 * T + 0.5 - 1e-6)
    assert w.out(0) == 1
    w.vm.advance(2e-6)
    assert w.out(0) == 0


def test_wait_pos_timeout_sets_eto():
    """3.6.20: "The timeout flag (ETO) will be set after a timeout limit has been reached. You can
    then use a JC ETO command to check for such errors or clear the error using the CLE command."""
    w = module()
    w.ok(5, 4, 0, 1000)                      # slow: 1000 pps, so 100000 steps take 100 s
    w.load("MVP ABS, 0, 100000\nWAIT POS, 0, 20\nJC ETO, Late\nCALC LOAD, 1\nSTOP\n"
           "Late: CALC LOAD, 2\nCLE ETO\nSTOP")
    w.run()
    w.vm.advance(0.1)
    assert w.pc == 1 and w.ok(135, 1) >> 16 & 0xFF == 1   # waiting
    w.vm.advance(0.15)
    assert w.a == 2 and w.state == 0 and not w.vm.flags & flags.ETO


def test_wait_pos_ends_on_arrival():
    """3.6.20 WAIT POS: "Wait until the target position of the motor ... has been reached"."""
    w = module()
    w.load("MVP ABS, 0, 5000\nWAIT POS, 0, 0\nGAP 1, 0\nSTOP")
    w.run()
    w.vm.advance(10.0)
    assert w.a == 5000 and w.state == 0 and not w.vm.flags & flags.ETO


def test_wait_ends_when_a_host_command_meets_its_condition():
    """3.6.20: "the TMCL program counter is ... held at the address of this WAIT command until the
    condition is met"; 7.6: direct mode commands are processed while the program runs. A host MVP
    to where the stopped motor stands meets WAIT POS at once: the program goes on then, not at the
    end of the host's next `advance` (GP132 tick timer, 1 ms, records when)."""
    w = module()
    w.load("MVP ABS, 0, 10000000\nWAIT POS, 0, 0\nGGP 132, 0\nAGP 1, 2\nSTOP")
    w.run()
    w.vm.advance(0.5)
    w.ok(3, 0, 0)                             # MST: the target is not reached
    w.vm.advance(0.5)
    assert w.pc == 1 and w.state == 1
    w.ok(4, 0, 0, w.ok(6, 1, 0))              # MVP ABS to the actual position at t = 1 s
    w.vm.advance(3.0)
    assert w.state == 0 and 1000 <= w.var(1) <= 1001


def test_wait_met_during_an_interrupt_handler_ends_after_reti():
    """3.5.6.2: after RETI "the execution of the normal program will be continued"; 3.6.20: a WAIT
    holds the PC only "until the condition is met". The motor arrives while the timer handler runs
    (it waits 1 s itself); the interrupted WAIT POS ends right after RETI (about 1050 ms)."""
    w = module()
    w.load("""
    VECT 0, Handler
    SGP 0, 3, 50
    EI 0
    EI 255
    MVP ABS, 0, 100
    WAIT POS, 0, 0
    GGP 132, 0
    AGP 1, 2
    STOP
Handler:
    DI 255
    WAIT TICKS, 0, 100
    RETI""")
    w.run()
    w.vm.advance(5.0)
    assert w.state == 0 and w.ok(6, 1, 0) == 100
    assert 1050 <= w.var(1) <= 1052


def test_wait_rfs_and_refsw_limsw_time_out_without_switches():
    """3.6.20 RFS waits for the end of the reference search; REFSW / LIMSW for a switch - with
    no switch ever closing, each WAIT ends at its timeout with ETO."""
    for cond in ("REFSW", "LIMSW"):
        w = run_program(f"WAIT {cond}, 0, 10\nJC ETO, Late\nSTOP\nLate: CALC LOAD, 7\nSTOP", 0.2)
        assert w.a == 7, cond
    w = run_program("WAIT RFS, 0, 10\nJC ETO, Late\nCALC LOAD, 1\nSTOP\nLate: CALC LOAD, 7\nSTOP", 0.2)
    assert w.a == 1                           # no search running: it has completed


def test_stop_ends_the_program():
    """3.6.21 STOP: "Execution of a TMCL program in standalone mode will be stopped"."""
    w = run_program("CALC LOAD, 1\nSTOP\nCALC LOAD, 2", 0.5)
    assert (w.a, w.state, w.pc) == (1, 0, 1)


def test_aap_agp_aco():
    """3.6.27 AAP, 3.6.28 AGP ("Copy accumulator to user variable #42: AGP 42, 2"), 3.6.25 ACO."""
    w = run_program("CALC LOAD, 4321\nAAP 4, 1\nAGP 42, 2\nACO 3, 2\nSTOP", 0.01)
    assert w.ok(6, 4, 1) == 4321
    assert w.var(42) == 4321
    assert w.ok(31, 3, 2) == 4321


def test_failing_instruction_is_skipped():
    """An instruction the module would answer with an error (here SAP on a motor the module lacks)
    has no effect and the program goes on (docs/assumptions.md)."""
    w = run_program("SAP 4, 9, 100\nCALC LOAD, 3\nSTOP", 0.01)
    assert w.a == 3
    assert w.vm.interpreter.last_error == (0, 5, 4)


def test_direct_mode_alongside_a_running_program():
    """7.6: "When a TMCL program is being executed in standalone mode, direct mode commands are also
    processed (and they do not disturb the flow of the program ...)"; user variables carry data
    between host and program (7.4)."""
    src = """Loop:
    GGP 0, 2
    COMP 0
    JC EQ, Loop
    CALC MUL, 2
    AGP 1, 2
    STOP"""
    w = module()
    w.load(src)
    w.run()
    for _ in range(5):
        w.vm.advance(0.013)
        assert w.ok(6, 1, 0) == 0             # direct GAP answered while the program runs
        assert w.ok(19, 9, 0, 777) in (0, 777)  # direct CALC LOAD: no effect on A
        w.ok(22, 0, 0, 5)                      # direct JA: no effect on the flow
        assert w.state == 1 and w.pc in (0, 1, 2) and w.a == 0
    w.ok(9, 0, 2, 21)
    w.vm.advance(0.01)
    assert w.var(1) == 42 and w.state == 0


def test_runs_are_reproducible():
    """docs/architecture.md "Time": the same program and the same host commands give the same trace."""
    def trace():
        w = module()
        w.load("Loop: GAP 1, 0\nCALC ADD, 100\nAAP 0, 0\nWAIT TICKS, 0, 3\nJA Loop")
        w.run()
        out = []
        for _ in range(40):
            w.vm.advance(0.0071)
            out.append((w.ok(6, 1, 0), w.pc, w.a))
        return out
    assert trace() == trace()


def test_running_pure_instructions_ahead_changes_nothing():
    """docs/architecture.md "Time": batching pure instructions between events (Interpreter.run_ahead) gives
    exactly the trace of one event per instruction - motors, timer interrupt, host commands."""
    src = """
    VECT 0, Tick
    SGP 0, 3, 7
    EI 0
    EI 255
    SAP 4, 0, 20000
Loop:
    GGP 3, 2
    CALC ADD, 1
    AGP 3, 2
    CALC MOD, 50
    COMP 0
    JC NE, Loop
    GAP 1, 0
    CALC ADD, 3000
    AAP 0, 0
    GIO 0, 0
    JC ZE, Loop
    SIO 1, 2, 1
    GIO 1, 2
    AGP 6, 2
    SIO 1, 2, 0
    JA Loop
Tick:
    CALCX LOAD
    CALC LOAD, 1
    AGP 4, 2
    CALCX SWAP
    RETI
"""
    def trace(run_ahead):
        w = module() if run_ahead else Wire(ReferenceModule("TMCM-6212", address=1))
        w.load(src)
        w.run()
        out = []
        for i in range(60):
            w.vm.advance(0.0037)
            if i == 20:
                w.vm.io.drive_input(0, 0, 1)
                w.ok(9, 3, 2, 1000)
            out.append((w.ok(6, 1, 0), w.ok(6, 0, 0), w.pc, w.a, w.x, w.vm.flags, w.var(3), w.var(4),
                        w.var(6), w.out(1)))
        return out, w.vm.interpreter.executed
    fast, slow = trace(True), trace(False)
    assert fast == slow
    assert fast[1] > 1000


def test_wait_rfs_and_limsw_with_a_switch_on_the_stage():
    """3.6.20 "RFS: Wait until the reference search of the motor ... has been reached [completed]";
    "LIMSW: Wait until a limit switch of the motor ... has been triggered". Stage: left switch at
    -30000 (a scenario); reference search mode 1 (left switch, TMCM-6212 6.1.1)."""
    from opentmcl import VirtualModule

    from .test_program_support import Wire
    w = Wire(VirtualModule("TMCM-6212", address=1, scenario={"axis": {"0": {"left": {"position": -30000}}}}))
    w.load("SAP 193, 0, 1\nRFS START, 0\nWAIT RFS, 0, 0\nGAP 1, 0\nWAIT LIMSW, 0, 5\nSTOP")
    w.run()
    w.vm.advance(0.5)
    assert (w.state, w.pc) == (1, 2) and w.ok(13, 2, 0) == 1     # still searching, PC held at WAIT
    w.vm.advance(10.0)
    assert (w.state, w.pc, w.a) == (0, 5, 0)                       # searched, A = position 0
    assert not w.vm.flags & flags.ETO                              # the switch satisfied LIMSW


def test_csub_beyond_program_memory_is_status_4_and_the_last_address_is_called():
    """TMCM-6212 3.6.18 CSUB "<subroutine address>": an address outside the program memory is an
    invalid value (3.2.1 Table 4 "4 Invalid value"; the call is ignored), while the last address
    of the memory is called (the PC moves there and runs into the empty memory cell:
    status 2, invalid command)."""
    size = VirtualModule("TMCM-6212").program.size
    w = _run_raw("TMCM-6212", (23, 0, 0, size), STOP, seconds=10 * T)
    assert w.vm.interpreter.last_error == (0, 23, 4)
    assert w.pc == 1
    w = _run_raw("TMCM-6212", (23, 0, 0, size - 1), seconds=3 * T)
    assert w.vm.interpreter.last_error == (size - 1, 0, 2)


def test_wait_ticks_ends_exactly_one_tick_after_it_began():
    """TMCM-6212 3.6.20 WAIT: "the TMCL program counter is set held at the address of this WAIT
    command until the condition is met or the timeout has expired", "one tick is 10 milliseconds":
    WAIT TICKS, 0, 1 still waits (135 wait flag, bit 16) 1/16 MHz before the 10 ms are up and no
    longer waits when they are (the WAIT, the first instruction, begins after one instruction time,
    100 us - docs/assumptions.md)."""
    w = module()
    w.download([(27, 0, 0, 1), (9, 0, 2, 1), STOP])
    w.run()
    w.vm.advance(0.001)
    begun = INSTRUCTION_TICKS
    assert w.ok(135, 0) >> 16 & 1
    w.vm.advance_to(begun + CLOCK_HZ // 100 - 1)
    assert w.ok(135, 0) >> 16 & 1
    w.vm.advance_to(begun + CLOCK_HZ // 100)
    assert not w.ok(135, 0) >> 16 & 1


def test_wait_refsw_on_a_module_without_a_home_switch_parameter_times_out(tmp_path):
    """TMCM-6212 3.6.20 "REFSW: Wait until a reference switch has been triggered ... The timeout flag
    (ETO) will be set after a timeout limit has been reached". A profile that removes AP9 (home
    switch state, 4.1; docs/profiles.md `[remove]`) has no switch to wait for: the WAIT ends by
    its timeout of 5 ticks and sets ETO (docs/assumptions.md "Firmware edges where the manuals are
    silent"), the same as on a module whose home switch stays open."""
    path = tmp_path / "nohome.toml"
    path.write_text('extends = "TMCM-6212"\n[module]\nname = "NOHOME-6212"\n'
                    "[remove]\naxis_parameter = [9]\n")
    for name in ("TMCM-6212", str(path)):
        w = module(name)
        w.download([(27, 2, 0, 5), (21, 8, 0, 3), (28, 0, 0, 0), (19, 9, 0, 9), (28, 0, 0, 0)])
        w.run()
        w.vm.advance(3 * T)
        assert w.pc == 0, name  # still waiting
        w.vm.advance(0.1)
        assert (w.a, w.state) == (9, 0), name


@pytest.mark.parametrize(("ticks", "wait"), [(-1, 0), (0, 0), (1, TICK)])
def test_wait_ticks_0_goes_on_at_once_and_1_waits_one_tick(ticks, wait):
    """TMCM-6212 3.6.20 WAIT TICKS: "one tick is 10 milliseconds"; docs/assumptions.md "WAIT":
    `WAIT TICKS, 0, n` with n <= 0 does not wait, and the next instruction follows one slot
    after the wait ends: SIO at 1 slot, WAIT at 2, the next SIO exactly at 3 slots + n ticks
    (n = 1, the first that waits: 10 ms), to the clock tick."""
    w = module()
    w.download([(14, 0, 2, 1), (27, 0, 0, ticks), (14, 0, 2, 0), (28, 0, 0, 0)])
    w.run()
    due = w.vm.now + 3 * INSTRUCTION_TICKS + wait
    w.vm.advance_to(due - 1)
    assert w.out(0) == 1
    w.vm.advance_to(due)
    assert w.out(0) == 0


def test_ja_beyond_program_memory_is_ignored_with_status_4():
    """TMCM-6212 3.6.17 "JA <jump address>", 1 Features: 6144 commands, so 6144 is beyond the memory:
    docs/assumptions.md "Program memory end": a JA one beyond the end is ignored (3.2.1 Table 4
    "4 Invalid value" in the program's last error) and the program goes on; JA 6143 is taken."""
    w = module()
    size = w.vm.program.size
    w.download([(22, 0, 0, size), (19, 9, 0, 3), (28, 0, 0, 0)])
    w.run()
    w.vm.advance(10 * T)
    assert (w.a, w.vm.interpreter.last_error) == (3, (0, 22, 4))
    w = module()
    w.download([(22, 0, 0, size - 1)])
    w.run()
    w.vm.advance(10 * T)
    assert w.vm.interpreter.last_error == (size - 1, 0, 2)


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


def test_flag_names_for_the_debugger():
    """TMCM-6212 3.6.16 JC names ZE, EQ, GT, LT and the error flags ETO, EAL, EDV, EPO, ESD (3.6.29
    CLE); `describe` spells each set flag with the manual's name, "-" for none."""
    everything = flags.ZERO | flags.EQUAL | flags.GREATER | flags.LOWER | flags.ERROR_MASK
    assert flags.describe(everything) == "ZE EQ GT LT ETO EAL EDV EPO ESD"
    assert flags.describe(0) == "-"


def test_csub_may_call_address_0():
    """TMCM-6212 3.6.18 CSUB "Call subroutine": address 0 is a program address like any other; the
    subroutine at 0 runs twice (once as the program, once when called) and RSUB returns."""
    src = """
    Sub:
        GGP 5, 2
        CALC ADD, 1
        AGP 5, 2
        COMP 2
        JC EQ, Back
        CSUB Sub
        STOP
    Back:
        RSUB
    """
    w = run_program(src, 40 * T)
    assert (w.var(5), w.state) == (2, 0)
