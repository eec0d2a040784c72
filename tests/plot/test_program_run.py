"""Program runs on a virtual module: events the module reports, instruction marks, loop passes and
how long a recording without --seconds lasts."""
from __future__ import annotations

import io
import subprocess
import sys

import pytest

from opentmcl.lang import assemble
from opentmcl.plot import Event, Mark, Trace, TraceError, run_virtual
from opentmcl.plot.program import AUTO_SECONDS, DEFAULT_SECONDS, auto_seconds
from opentmcl.plot.recording import MAX_SAMPLES

ORIGIN_PROGRAM = """
    SAP 4, 0, 51200
    SAP 5, 0, 51200
    MVP ABS, 0, 10000
    WAIT POS, 0, 0
    SAP 1, 0, 0          // set the origin here
    MVP ABS, 0, 5000
    WAIT POS, 0, 0
    STOP
"""

LOOP = """
    SAP 4, 0, 51200
    SAP 5, 0, 512000
Loop:
    MVP ABS, 0, 5120
    WAIT POS, 0, 0
    MVP ABS, 0, 0
    WAIT POS, 0, 0
    JA Loop
"""


def _run(source, **kw):
    return run_virtual(assemble(source, module="TMCM-6212").instructions, **kw)


@pytest.fixture(scope="module")
def origin_trace():
    return _run(ORIGIN_PROGRAM)


def test_sap_1_is_recorded_as_an_origin_write_with_the_counter_either_side(origin_trace):
    """TMCM-6212 manual 4.1 AP 1 "Actual position": writing it overwrites the counter (reference
    point setting) without moving the motor: one origin event from 10000 (the target reached,
    3.6.4 MVP ABS) to 0, between the last sample at 10000 and the first at 0."""
    (e,) = origin_trace.events
    assert (e.axis, e.kind, e.before, e.after) == (0, "origin", 10000, 0)
    t, pos = origin_trace.time, origin_trace.column(0, "position")
    i = next(k for k in range(len(t)) if t[k] >= e.time)
    assert 9990 <= pos[i - 1] <= 10000 and pos[i] == 0 and t[i - 1] < e.time
    assert pos[-1] == 5000


def test_the_program_marks_name_the_instruction_at_each_sample_where_the_pc_changed(origin_trace):
    """Command 135 type 1 (manual 3.6.36) gives the program counter: the run spends its time in the
    two WAIT POS (addresses 3 and 6) and ends at the STOP (7)."""
    marks = [(m.pc, m.text) for m in origin_trace.marks]
    assert marks[0][0] == 0 and marks[-1] == (7, "STOP")
    assert (3, "WAIT POS, 0, 0") in marks and (6, "WAIT POS, 0, 0") in marks
    at = {m.pc: m.time for m in origin_trace.marks}
    assert at[3] < origin_trace.events[0].time < at[6]


def test_a_reference_search_sets_the_origin_too():
    """Manual 6 (reference search): the reference point is set where the switch is found; the
    counter jumps from the switch position (start 20000, switch 50000 µsteps left of it) to 0."""
    source = """
    SAP 193, 0, 1
    SAP 194, 0, 51200
    SAP 195, 0, 5120
    RFS START, 0
    WAIT RFS, 0, 0
    STOP
"""
    trace = _run(source, scenario={"axis": {"0": {"start": 20000, "left": {"position": -30000}}}})
    origins = [e for e in trace.events if e.kind == "origin"]
    assert origins and origins[-1].after == 0
    assert origins[-1].before == pytest.approx(-50000, abs=200)


def test_a_limit_switch_stop_is_a_hard_stop_unless_soft_stop_is_enabled():
    """Manual 4.1 AP 26 "Soft stop enable: Use soft stop when motor is stopped by a limit switch"
    (default 0: the motor stops at once): a hard-stop event from 20000 pps to 0; with AP 26 = 1 the
    motor ramps down and no hard stop is reported."""
    scenario = {"axis": {"0": {"right": {"position": 30000}}}}
    hard = _run("    ROR 0, 20000\n    WAIT TICKS, 0, 300\n    STOP\n", scenario=scenario)
    (e,) = hard.events
    assert (e.kind, e.before, e.after) == ("hard_stop", 20000, 0)
    vel = hard.column(0, "velocity")
    i = next(k for k in range(len(hard)) if hard.time[k] >= e.time)
    assert vel[i - 1] == 20000 and vel[i] == 0
    soft = _run("    SAP 26, 0, 1\n    ROR 0, 20000\n    WAIT TICKS, 0, 300\n    STOP\n", scenario=scenario)
    assert soft.events == []


def test_without_seconds_a_loop_is_recorded_twice_then_the_recording_ends():
    """TMCM-6212 manual 3.6.17 JA: the loop runs forever; the recording stops at the start of its
    third pass (two moves out to 5120 and two back to 0, each pass under a second), long before
    the 300 s cap."""
    trace = _run(LOOP)
    pos = trace.column(0, "position")
    out = sum(1 for a, b in zip(pos, pos[1:], strict=False) if a < 2560 <= b)
    back = sum(1 for a, b in zip(pos, pos[1:], strict=False) if a >= 2560 > b)
    assert out == 2 and back == 2
    assert [m.pc for m in trace.marks].count(3) == 3 and trace.time[-1] < 2.5
    longer = _run(LOOP, seconds=3.0, interval=0.05)   # explicit seconds: that long, loops or not
    assert longer.time[-1] == pytest.approx(3.0)


def test_a_loop_that_waits_in_a_subroutine_is_recorded_twice():
    """TMCM-6212 manual 3.6.18 CSUB example (examples/tmcm6212_3.6.18_call_subroutine.tmc): the
    loop body (MVP, CSUB, MVP, CSUB, JA) spends all its time in the subroutine's WAITs, so the
    program counter is hardly ever seen inside the body; each executed JA back is one pass, and the
    recording ends at the start of the third pass - not at the 300 s cap."""
    from pathlib import Path

    source = (Path(__file__).resolve().parents[2] / "examples" / "tmcm6212_3.6.18_call_subroutine.tmc").read_text()
    trace = _run(source)
    pos = trace.column(0, "position")
    out = sum(1 for a, b in zip(pos, pos[1:], strict=False) if a < 5000 <= b)
    back = sum(1 for a, b in zip(pos, pos[1:], strict=False) if a >= 5000 > b)
    assert out == 2 and back == 2
    assert trace.time[-1] < 10.0
    assert trace.column(0, "target")[-1] == 10000      # the third pass has just begun: MVP ABS 10000


TIMER_LOOP = """
#include Interrupts.inc
    VECT TI_TIMER0, Tick
    SGP TI_TIMER0, 3, 100       // timer 0 every 100 ms (manual 3.5.6.4)
    EI TI_TIMER0
    EI TI_GLOBAL
    SAP 4, 0, 51200
    SAP 5, 0, 51200
Loop:
    MVP ABS, 0, 51200
    WAIT POS, 0, 0
    MVP ABS, 0, 0
    WAIT POS, 0, 0
    JA Loop
Tick:
    SIO 0, 2, 1
    RETI
"""


def test_a_timer_interrupt_is_no_loop_pass():
    """TMCM-6212 manual 3.5.6.4: the timer interrupt runs its handler and RETI returns to where the
    program was (here a WAIT POS inside the loop), every 100 ms. The loop itself takes two moves of
    51200 µsteps per pass (about 4 s); the recording shows two passes, not 0.2 s of the first move."""
    trace = _run(TIMER_LOOP)
    pos = trace.column(0, "position")
    assert sum(1 for a, b in zip(pos, pos[1:], strict=False) if a < 25600 <= b) == 2
    assert sum(1 for a, b in zip(pos, pos[1:], strict=False) if a >= 25600 > b) == 2
    assert trace.column(0, "target")[-1] == 51200      # the third pass has just begun


def test_a_jump_to_itself_is_a_halt_not_a_loop():
    """TMCM-6212 manual 3.6.17 JA: "End: JA End" jumps to itself forever and does nothing else - a
    STOP that keeps running. The recording waits for the move to end (the axis at 51200 and still),
    as after a STOP, instead of ending two samples into the move."""
    trace = _run("    SAP 4, 0, 51200\n    MVP ABS, 0, 51200\nEnd:\n    JA End\n")
    assert trace.column(0, "position")[-1] == 51200 and trace.column(0, "velocity")[-1] == 0
    assert trace.time[-1] < 10.0 and trace.marks[-1].text.startswith("JA")


def test_a_polling_loop_closed_by_ja_is_waited_out_too():
    """The same poll written with a JA back and a JC out (manual 3.6.16 JC, 3.6.17 JA): the JC
    can leave the loop, so it ends by itself and is waited out - the recording shows the axis
    passing 20000 and stopping (MST), not two samples of the poll."""
    poll = ("    ROR 0, 20000\nPoll:\n    GAP 1, 0\n    COMP 20000\n    JC GE, Done\n    JA Poll\n"
            "Done:\n    MST 0\n    STOP\n")
    trace = _run(poll)
    assert trace.column(0, "position")[-1] >= 20000 and trace.column(0, "velocity")[-1] == 0
    assert trace.marks[-1].text == "STOP"


def test_a_polling_loop_is_waited_out_like_a_wait():
    """A loop that ends by itself (COMP / JC, manual 3.6.14-3.6.15) is no JA loop: the recording
    goes on until the program stops (position 20000 passed, MST, STOP), while a JA loop polling the
    same way ends after two passes."""
    poll = "    ROR 0, 20000\nMoving:\n    GAP 1, 0\n    COMP 20000\n    JC LT, Moving\n    MST 0\n    STOP\n"
    trace = _run(poll)
    assert trace.column(0, "position")[-1] >= 20000 and trace.column(0, "velocity")[-1] == 0
    assert trace.marks[-1].text == "STOP"
    forever = "    ROR 0, 20000\nMoving:\n    GAP 1, 0\n    JA Moving\n"
    assert len(_run(forever)) <= 4


def test_a_loop_shorter_than_the_interval_is_counted_from_the_executed_instructions():
    """A loop spends all its time in one WAIT: the program counter is the same at every sample, yet
    the module executed the loop in between (WAIT TICKS 1 = 10 ms, manual 3.6.28; samples 0.1 s):
    about ten passes before the second sample, which ends the recording. A loop of 200 ms ends
    it at the first sample after its second pass (0.4 s and a few instructions)."""
    trace = _run("Loop:\n    WAIT TICKS, 0, 1\n    JA Loop\n", interval=0.1)
    assert len(trace) == 2
    slower = _run("Loop:\n    WAIT TICKS, 0, 20\n    JA Loop\n", interval=0.1)
    assert slower.time[-1] == pytest.approx(0.5)


def test_a_program_that_neither_stops_nor_loops_ends_at_the_cap():
    """The hard cap: AUTO_SECONDS of module time (fewer when the interval would make more than
    MAX_SAMPLES samples). Without a program the recording is DEFAULT_SECONDS long."""
    trace = _run("    ROR 0, 1000\n    WAIT TICKS, 0, 100000000\n    STOP\n", interval=1.0)
    assert trace.time[-1] == pytest.approx(AUTO_SECONDS) and len(trace) == AUTO_SECONDS + 1
    assert auto_seconds(1.0) == AUTO_SECONDS
    assert auto_seconds(1e-4) == pytest.approx(MAX_SAMPLES * 1e-4)
    assert auto_seconds(1e-4) < AUTO_SECONDS
    nothing = run_virtual(None, stop_when_idle=False, interval=0.5)   # no program to derive it from
    assert nothing.time[-1] == pytest.approx(DEFAULT_SECONDS) == 10.0


def test_events_and_marks_survive_the_csv(origin_trace):
    buf = io.StringIO()
    origin_trace.to_csv(buf)
    back = Trace.from_csv(io.StringIO(buf.getvalue()))
    assert back.events == [Event(round(e.time, 6), e.axis, e.kind, e.before, e.after) for e in origin_trace.events]
    assert back.marks == [Mark(round(m.time, 6), m.pc, m.text) for m in origin_trace.marks]
    assert back.column(0, "target")[-1] == 5000


def test_csv_event_lines_are_checked():
    """No events line: not known (None); ``events=recorded`` alone: known to be none."""
    body = "time_s,position_0\n0,1\n"
    assert Trace.from_csv(io.StringIO(body)).events is None
    assert Trace.from_csv(io.StringIO("# events=recorded\n" + body)).events == []
    marks = Trace.from_csv(io.StringIO("# mark=0.5,3,WAIT POS, 0, 0\n" + body)).marks
    assert marks == [Mark(0.5, 3, "WAIT POS, 0, 0")]
    for bad in ("# events=recorded\n# event=0.1,0,teleport,1,2\n", "# events=recorded\n# event=0.1,0,origin\n",
                "# mark=x,1,STOP\n", "# event=0.1,0,origin,1,2\n"):
        with pytest.raises(TraceError, match="event|metadata"):
            Trace.from_csv(io.StringIO(bad + body))


def test_cli_without_seconds_records_two_loop_passes(tmp_path):
    """`opentmcl plot` (a subprocess) with no --seconds: the loop twice, then exit 0."""
    src = tmp_path / "loop.tmc"
    src.write_text(LOOP)
    csv, png = tmp_path / "loop.csv", tmp_path / "loop.png"
    done = subprocess.run([sys.executable, "-m", "opentmcl", "plot", str(src), "-o", str(png), "--csv", str(csv),
                           "--phases"], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    trace = Trace.from_csv(csv)
    assert trace.time[-1] < 2.5 and [m.pc for m in trace.marks].count(3) == 3
    assert trace.events == [] and png.read_bytes()[:4] == b"\x89PNG"


def test_cli_bad_trace_metadata_is_a_one_line_error(tmp_path):
    csv = tmp_path / "bad.csv"
    csv.write_text("# event=0.1,0,origin,1,2\ntime_s,position_0\n0,1\n")
    done = subprocess.run([sys.executable, "-m", "opentmcl", "plot", str(csv), "-o", str(tmp_path / "x.png")],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 2 and done.stderr.count("\n") == 1 and "Traceback" not in done.stderr
    assert not (tmp_path / "x.png").exists()


def test_a_pd86_1180_hard_stop_is_reported_in_pps():
    """PD86-1180 manual 5: the actual speed is in TMC429 units, pps = f_CLK * v / (2^pulse_div * 2048
    * 32); the speed before a limit-switch hard stop is converted the same way as the samples."""
    from opentmcl import connect
    from opentmcl.host.units import tmc429_velocity_to_pps

    program = assemble("    ROR 0, 500\n    WAIT TICKS, 0, 300\n    STOP\n", module="PD86-1180").instructions
    trace = run_virtual(program, module="PD86-1180", scenario={"axis": {"0": {"right": {"position": 3000}}}})
    with connect("sim://PD86-1180") as m:
        pulse_div = m.axes[0].get(154)
    (e,) = trace.events
    assert e.kind == "hard_stop" and e.before == pytest.approx(tmc429_velocity_to_pps(500, pulse_div))
    assert e.before == max(trace.column(0, "velocity"))


def test_cli_without_seconds_takes_a_fine_interval(tmp_path):
    """docs/plots.md: without --seconds a program runs at most 300 s, "fewer if the interval would
    give more than 400000 samples" - so --interval 1e-5 is no error there (it was refused as
    "10 s every 1e-05 s"); a scenario alone still records 10 s and is refused."""
    src = tmp_path / "move.tmc"
    src.write_text("    STOP\n")
    png = tmp_path / "move.png"
    done = subprocess.run([sys.executable, "-m", "opentmcl", "plot", str(src), "-o", str(png), "--interval", "1e-5",
                           "--channels", "position"], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    scenario = tmp_path / "world.toml"
    scenario.write_text("[axis.0]\nstart = 0\n")
    done = subprocess.run([sys.executable, "-m", "opentmcl", "plot", str(scenario), "-o", str(png), "--interval",
                           "1e-5"], capture_output=True, text=True, timeout=120)
    assert done.returncode == 2 and "samples" in done.stderr and "Traceback" not in done.stderr
