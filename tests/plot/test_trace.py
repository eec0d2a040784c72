"""Traces recorded from a virtual run, their CSV form and the derived acceleration."""
from __future__ import annotations

import io

import pytest

from opentmcl.lang import assemble
from opentmcl.plot import Trace, TraceError, derivative, run_virtual

MOVE = """
    SAP 4, 0, 51200      // maximum positioning speed [pps]
    SAP 5, 0, 51200      // maximum acceleration [pps^2]
    SAP 17, 0, 51200     // maximum deceleration [pps^2]
    MVP ABS, 0, 102400
    WAIT POS, 0, 0
    STOP
"""


@pytest.fixture(scope="module")
def move_trace():
    program = assemble(MOVE, module="TMCM-6212")
    return run_virtual(program, module="TMCM-6212", axes=[0, 1], seconds=10, interval=0.01)


def test_move_reaches_target_at_max_speed(move_trace):
    """TMCM-6212 manual 3.6.4 MVP ABS and 4.1 parameters 4/5: the motor accelerates to the maximum
    positioning speed 51200 pps and stops at the target 102400 µsteps."""
    pos = move_trace.column(0, "position")
    vel = move_trace.column(0, "velocity")
    assert pos[0] == 0 and pos[-1] == 102400
    assert max(vel) == 51200
    assert vel[-1] == 0
    assert move_trace.column(0, "target_reached")[-1] == 1
    assert set(move_trace.column(1, "position")) == {0}  # axis 1 never moved


def test_move_takes_three_seconds_and_recording_ends_when_idle(move_trace):
    """Accelerating to 51200 pps at 51200 pps² takes 1 s (25600 µsteps), so the trapezoid is
    1 s up, 1 s at speed, 1 s down (manual 6.5 units; docs/motion.md six-point ramp with V1 = 0)."""
    t, vel = move_trace.time, move_trace.column(0, "velocity")
    moving = [ti for ti, v in zip(t, vel, strict=True) if v]
    assert moving[-1] - moving[0] == pytest.approx(3.0, abs=0.05)
    assert t[-1] < 3.3  # stopped recording soon after the program ended and the axis stood still


def test_derived_acceleration_matches_max_acceleration(move_trace):
    """Axis parameter 5 (manual 4.1): 51200 pps² while the motor speeds up."""
    acc = move_trace.column(0, "acceleration")
    t = move_trace.time
    ramp = [a for ti, a in zip(t, acc, strict=True) if a is not None and 0.2 < ti < 0.8]
    assert ramp and all(a == pytest.approx(51200, rel=0.03) for a in ramp)
    braking = [a for ti, a in zip(t, acc, strict=True) if a is not None and 2.2 < ti < 2.8]
    assert braking and all(a == pytest.approx(-51200, rel=0.03) for a in braking)


def test_rpm_follows_the_manuals_example(move_trace):
    """Manual 6.5: 200 full steps, 256 microsteps (AP 140 = 8): 51200 pps is 60 rpm."""
    assert move_trace.microsteps[0] == (256, 200)
    assert max(v for v in move_trace.rpm(0) if v is not None) == pytest.approx(60.0)


def test_csv_round_trip(move_trace):
    buf = io.StringIO()
    move_trace.to_csv(buf)
    text = buf.getvalue()
    assert text.splitlines()[0] == "# module=TMCM-6212"
    back = Trace.from_csv(io.StringIO(text))
    assert back.axes == [0, 1] and back.module == "TMCM-6212"
    assert back.time == pytest.approx(move_trace.time, abs=1e-6)
    assert back.column(0, "position") == move_trace.column(0, "position")
    assert back.column(0, "velocity") == move_trace.column(0, "velocity")
    assert back.microsteps == move_trace.microsteps


def test_csv_errors_are_trace_errors(tmp_path):
    with pytest.raises(TraceError, match="time_s"):
        Trace.from_csv(io.StringIO("a,b\n1,2\n"))
    with pytest.raises(TraceError, match="column"):
        Trace.from_csv(io.StringIO("time_s,speed_0\n0,1\n"))
    with pytest.raises(TraceError, match="row 3"):
        Trace.from_csv(io.StringIO("time_s,position_0\n0,1\n0.1,x\n"))
    with pytest.raises(TraceError, match="cannot read"):
        Trace.from_csv(tmp_path / "missing.csv")


def test_unknown_axis_or_channel(move_trace):
    with pytest.raises(TraceError):
        move_trace.column(5, "position")
    with pytest.raises(TraceError):
        move_trace.column(0, "jerk")


def test_derivative_is_backward_difference():
    assert derivative([0.0, 0.5, 1.0, 1.5], [0, 10, None, 40]) == [None, 20.0, None, None]


def test_tmc429_velocity_is_converted_to_pps():
    """PD86-1180 manual 5 / TMC4210 datasheet 6.1.12.1: pps = f_CLK * v / (2^pulse_div * 2048 * 32);
    with the default pulse divisor the internal velocity is converted before it is stored."""
    from opentmcl.host.units import tmc429_velocity_to_pps

    program = assemble("    ROR 0, 1000\n    WAIT TICKS, 0, 100\n    MST 0\n    STOP\n", module="PD86-1180")
    trace = run_virtual(program, module="PD86-1180", axes=[0], seconds=5, interval=0.01)
    from opentmcl import connect

    with connect("sim://PD86-1180") as m:
        pulse_div = m.axes[0].get(154)
    assert max(trace.column(0, "velocity")) == pytest.approx(tmc429_velocity_to_pps(1000, pulse_div))
