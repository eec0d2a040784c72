"""The PD86-1180 motion engine (Tmc429Engine) on top of the TMC429 core."""
from __future__ import annotations

import pytest

from opentmcl.motion import CLOCK_HZ, Mode, RampEngine
from opentmcl.motion.pmulpdiv import calc_pmul_pdiv
from opentmcl.motion.tmc429 import RAMP_MODE, SOFT_MODE, VELOCITY_MODE
from opentmcl.motion.tmc429_engine import Tmc429ConfigError, Tmc429Engine


def engine(**params) -> Tmc429Engine:
    e = Tmc429Engine()
    e.configure(**params)
    return e


def run_to_rest(e: Tmc429Engine, limit_s: float = 100.0) -> None:
    horizon = e.now + int(limit_s * CLOCK_HZ)
    while (t := e.next_event()) is not None and t <= horizon:
        e.advance(t)


def test_is_a_ramp_engine_on_the_16_mhz_clock():
    """PD86-1180 manual ch. 5 (AP4 unit 16 MHz / 65536 * 2^-pulse_div): the TMC429
    runs at 16 MHz, the VM tick."""
    e = Tmc429Engine()
    assert isinstance(e, RampEngine) and e.clock_hz == 16_000_000
    assert e.mode is Mode.POSITION and e.position == 0 and e.position_reached


def test_manual_example_program_back_and_forth():
    """PD86-1180 manual 8.2: SAP 4, 0, 500 / SAP 5, 0, 100 / MVP ABS, 0, 5000 /
    WAIT POS / MVP ABS, 0, 0 / WAIT POS. 500 internal units are 122 070 steps/s
    (ch. 5 AP4), so 5000 steps take about 41 ms plus the short ramps and the last
    steps at the minimum speed (AP130 default 1). The way back is the same ramp mirrored, except
    that the TMC429's pulse generator first walks back the fraction of a step it made past 5000
    (TMC4210 datasheet 6.1.12.1, signed velocity), so it is never slower; a first move to -5000
    is the exact mirror image of the move to 5000, and so is its way back."""
    e = engine(max_positioning_speed=500, max_acceleration=100)
    e.move_to(5000)
    assert e.target_velocity == 500                         # AP2 during acceleration
    run_to_rest(e)
    assert e.position == 5000 and e.position_reached and e.velocity == 0
    assert 0.040 < e.now / CLOCK_HZ < 0.060
    start = e.now
    e.move_to(0)
    assert e.target_velocity == -500
    run_to_rest(e)
    assert e.position == 0 and e.position_reached
    back = e.now - start
    pulse_period = 32 << e.ramp.pulse_div                   # one step at V_ACTUAL 1 at most:
    assert start - 2048 * pulse_period < back <= start
    mirror = engine(max_positioning_speed=500, max_acceleration=100)
    mirror.move_to(-5000)
    run_to_rest(mirror)
    assert (mirror.position, mirror.now) == (-5000, start)
    mirror.move_to(0)
    run_to_rest(mirror)
    assert (mirror.position, mirror.now - start) == (0, back)


def test_pmul_pdiv_follow_ap5_ap153_ap154():
    """PD86-1180 manual ch. 5, AP5: "Changing this parameter requires re-calculation of
    the acceleration factor and the acceleration divisor, which is done automatically";
    TMC4210 datasheet 6.1.7.1: also after a change of RAMP_DIV or PULSE_DIV."""
    e = engine(max_acceleration=100)
    r = calc_pmul_pdiv(100, 0, 0, 0.01)
    assert (e.pmul, e.pdiv) == (r.pmul, r.pdiv) == (198, 5)
    e.configure(ramp_divisor=3)
    r = calc_pmul_pdiv(100, 3, 0, 0.01)
    assert (e.pmul, e.pdiv) == (r.pmul, r.pdiv)
    e.configure(pulse_divisor=2)
    r = calc_pmul_pdiv(100, 3, 2, 0.01)
    assert (e.pmul, e.pdiv) == (r.pmul, r.pdiv)
    assert e.ramp.ramp_div == 3 and e.ramp.pulse_div == 2


def test_configure_rejects_bad_values():
    """PD86-1180 manual ch. 5 ranges: AP4/AP5/AP130 0..2047, AP138 0..2, AP153/AP154 0..13."""
    e = Tmc429Engine()
    for bad in ({"max_positioning_speed": 2048}, {"max_acceleration": -1}, {"minimum_speed": 5000},
                {"ramp_mode": 3}, {"ramp_divisor": 14}, {"pulse_divisor": -1}, {"velocity": 3},
                {"max_acceleration": 1.5}, {"ramp_mode": True}):
        with pytest.raises(Tmc429ConfigError):
            e.configure(**bad)
    with pytest.raises(ValueError):
        e.rotate(2048)


def test_positions_are_32_bit_and_mvp_takes_the_shorter_way():
    """PD86-1180 manual 4.6.4 MVP: range -2^31 .. 2^31-1, "the distance between the
    actual position and the new one should not be more than 2^31-1 microsteps.
    Otherwise the motor will run in the opposite direction"."""
    e = engine(max_positioning_speed=2047, max_acceleration=2047)
    e.move_to(2**31 - 1)
    e.advance(CLOCK_HZ // 10)
    assert e.velocity > 0 and 2**24 > e.position > 0
    e = engine(max_positioning_speed=2047, max_acceleration=2047)
    e.set_position(-30)
    e.move_to(2**31 - 1)                                    # 2^31 + 29 away: shorter backwards
    e.advance(CLOCK_HZ // 10)
    assert e.velocity < 0 and e.position < -30
    e.set_position(-(2**31))
    assert e.position == -(2**31)


def test_ror_rol_mst():
    """PD86-1180 manual 4.6.1-4.6.3: ROR/ROL select velocity mode with a velocity of
    0..2047 (not limited by AP4, the *positioning* speed); MST sets the target
    velocity to zero and the motor ramps down with AP5."""
    e = engine(max_positioning_speed=100, max_acceleration=1000)
    e.rotate(-1000)
    assert e.mode is Mode.VELOCITY and e.ramp_mode == 2
    run_to_rest(e)
    assert e.velocity == -1000 and e.target_velocity == -1000
    assert e.next_event() is None
    e.stop()
    assert e.target_velocity == 0
    e.advance(e.now + 32 * 256)                             # 256 ramp ticks of A_MAX/256
    assert e.velocity == -1000 + 1000
    e.move_to(e.position + 1000)
    assert e.ramp.v_max == 100                              # AP4 again in position mode


def test_position_reached_in_every_ramp_mode():
    """PD86-1180 manual ch. 5 AP8: "Indicates that the actual position equals the target position"
    (issue 29 item 1): after MVP, arrival and MST (velocity mode) the motor rests on X_TARGET and AP8
    is 1. Passing X_TARGET at speed, and resting elsewhere, leave it 0."""
    e = engine(max_positioning_speed=1000, max_acceleration=100, ramp_divisor=7, pulse_divisor=3)
    e.move_to(2000)
    run_to_rest(e)
    assert (e.position, e.position_reached) == (2000, True)
    e.stop()
    assert (e.mode, e.target_position, e.velocity, e.position_reached) == (Mode.VELOCITY, 2000, 0, True)
    e.rotate(300)
    e.advance(e.now + CLOCK_HZ)
    assert e.position > 2000 and not e.position_reached
    e.rotate(-300)
    back = e.time_at_position(2000)
    e.advance(back)
    assert (e.position, e.target_position) == (2000, 2000) and e.velocity != 0 and not e.position_reached
    e.stop()
    run_to_rest(e)
    assert e.velocity == 0 and e.position < 2000 and not e.position_reached


def test_ap2_reads_zero_while_decelerating_and_at_rest():
    """PD86-1180 manual ch. 5 AP2: "In position mode, this parameter is set by hardware:
    to the maximum speed during acceleration, and to zero during deceleration and rest"."""
    e = engine(max_positioning_speed=800, max_acceleration=50)
    e.move_to(-20_000)
    seen = set()
    while (t := e.next_event()) is not None:
        e.advance(t)
        seen.add((e.actual_acceleration > 0, e.actual_acceleration < 0, e.target_velocity))
    assert any(v == -800 for *_, v in seen) and (False, True, 0) in seen
    assert e.target_velocity == 0 and e.position == -20_000


def test_soft_mode_via_ap138():
    """PD86-1180 manual ch. 5 AP138: "For special purposes, the soft mode (value 1) with
    exponential decrease of speed can be selected"; MVP keeps it."""
    e = engine(max_positioning_speed=400, max_acceleration=200, ramp_mode=1)
    assert e.ramp.mode == SOFT_MODE
    e.move_to(3000)
    assert e.ramp.mode == SOFT_MODE
    run_to_rest(e)
    assert e.position == 3000 and e.position_reached
    e.configure(ramp_mode=2)
    assert e.ramp.mode == VELOCITY_MODE and e.mode is Mode.VELOCITY
    e.configure(ramp_mode=0)
    assert e.ramp.mode == RAMP_MODE


def test_set_position_at_rest_and_while_moving():
    """PD86-1180 manual ch. 5 AP1 ("should only be overwritten for reference point
    setting"): at rest the target follows; TMC4210 datasheet 6.1.2: while moving in
    ramp_mode the motor then drives to X_TARGET from the new position."""
    e = engine(max_positioning_speed=500, max_acceleration=500)
    e.set_position(777)
    assert e.target_position == 777 and e.position_reached
    e.advance(CLOCK_HZ // 100)
    assert e.position == 777
    e.move_to(10_000)
    e.advance(e.now + CLOCK_HZ // 100)
    e.set_position(0)
    run_to_rest(e)
    assert e.position == 10_000 and e.target_position == 10_000


def test_hard_stop_and_time_at_position():
    """TMC4210 datasheet 6.1.10.2 (stop immediately, limits ignored); time_at_position
    gives the cycle of the first pass, exactly as advancing shows."""
    e = engine(max_positioning_speed=1000, max_acceleration=300)
    e.move_to(50_000)
    t = e.time_at_position(12_345)
    e.advance(t - 1)
    assert e.position == 12_344
    e.advance(t)
    assert e.position == 12_345
    e.hard_stop()
    assert e.velocity == 0 and e.target_position == 12_345 and e.position_reached
    assert e.time_at_position(0) is None and e.next_event() is None


def test_sap_138_velocity_mode_keeps_the_speed():
    """PD86-1180 manual ch. 5 AP138 = 2: "The motor will run continuously and the speed
    will be changed with constant (maximum) acceleration, if the parameter target speed
    is changed" — switching during a move keeps the present speed until AP2 changes."""
    e = engine(max_positioning_speed=600, max_acceleration=500)
    e.move_to(1_000_000)
    e.advance(CLOCK_HZ // 10)
    assert e.velocity == 600 and e.moving
    e.configure(ramp_mode=2)
    e.advance(e.now + CLOCK_HZ // 10)
    assert e.velocity == 600 and e.target_velocity == 600 and e.mode is Mode.VELOCITY
    e.rotate(0)
    run_to_rest(e)
    assert not e.moving and e.next_event() is None
