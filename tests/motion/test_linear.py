"""Linear ramp engine of the PD28-1021 (manual ch. 2.3 AP4/AP5 in pps / pps^2;
AP130 'Minimum speed' after the TMCM-1180 manual ch. 4, here in pps)."""
from __future__ import annotations

import copy

import pytest
from hypothesis import given
from hypothesis import strategies as st

from opentmcl.motion import CLOCK_HZ, Mode
from opentmcl.motion.linear import LinearRampEngine
from opentmcl.motion.sixpoint import wrap32

from .test_sixpoint import events

F = CLOCK_HZ




def test_trapezoid_takes_the_analytic_time():
    """2.3: AP4 'maximum speed used for positioning ramps', AP5 'maximum acceleration in
    positioning ramps'; with minimum speed 0: T = D/AP4 + AP4/AP5."""
    e = LinearRampEngine(max_positioning_speed=51200, max_acceleration=51200, minimum_speed=0)
    e.move_to(102400)
    assert events(e) == [(F, 25600, 51200), (2 * F, 76800, 51200), (3 * F, 102400, 0)]
    assert e.position_reached


def test_default_minimum_speed_reaches_the_target_exactly():
    """TMCM-1180 manual AP130: 'Should always be set 1 to ensure exact reaching of the target
    position.' With the default 1 pps the ramp starts at 1 pps and ends exactly on target."""
    e = LinearRampEngine()
    assert e.params["minimum_speed"] == 1
    e.move_to(51200)
    e.advance(1)
    assert e.velocity_exact >= 1
    ev = events(e)
    # (51200 - 1) / 51200 s = 15999687.5 ticks: 15999687 whole ticks, then the last half
    # tick's acceleration (0.0016 pps) in one jump to AP4
    assert ev[0][0] == F - 313 and ev[0][2] == 51200
    assert ev[-1][1:] == (51200, 0)


def test_minimum_speed_is_start_and_stop_speed():
    """AP130 acts as VSTART and VSTOP of the linear ramp (docs/assumptions.md)."""
    e = LinearRampEngine(max_positioning_speed=51200, max_acceleration=51200, minimum_speed=12800)
    e.move_to(99200)
    e.advance(1)
    assert e.velocity == 12800
    assert events(e) == [(3 * F // 4, 24000, 51200), (7 * F // 4, 75200, 51200), (5 * F // 2, 99200, 0)]


def test_velocity_mode_uses_ap5():
    """2.3 AP5: 'Acceleration and deceleration value in velocity mode.'"""
    e = LinearRampEngine(max_acceleration=25600, minimum_speed=1000)
    e.rotate(-51200)
    assert e.mode is Mode.VELOCITY
    assert events(e) == [(2 * F, -51200, -51200)]
    e.stop()
    assert events(e) == [(4 * F, -102400, 0)]


def test_reversal_without_wait():
    """The PD28-1021 has no ramp wait time: a reversal starts right after the stop."""
    e = LinearRampEngine(minimum_speed=0)
    e.move_to(10**6)
    e.advance(F)
    e.move_to(0)
    ev = events(e)
    stop = next(i for i, (_, _, v) in enumerate(ev) if v == 0)
    t_stop = ev[stop][0]
    probe = LinearRampEngine(minimum_speed=0)
    probe.move_to(10**6)
    probe.advance(F)
    probe.move_to(0)
    probe.advance(t_stop + 1)
    assert probe.velocity_exact < 0
    assert ev[-1][1:] == (0, 0)


def test_on_the_fly_target_and_speed_change():
    """On the fly alteration of motion parameters (PD28-1021 manual ch. 1)."""
    e = LinearRampEngine(minimum_speed=0)
    e.move_to(102400)
    e.advance(F)
    e.configure(max_positioning_speed=25600)
    e.move_to(200000)
    assert events(e)[-1][1:] == (200000, 0)


def test_many_microsteps_per_tick():
    """AP4/AP5 up to 2147483647 pps / pps^2 (2.3): more than one microstep per tick; the
    counter still lands exactly on the target and time_at_position reports the tick on
    which a position is passed."""
    e = LinearRampEngine(max_positioning_speed=2**31 - 1, max_acceleration=2**31 - 1, minimum_speed=1)
    e.move_to(2**31 - 1)
    t = e.time_at_position(10**9)
    probe = copy.deepcopy(e)
    probe.advance(t)
    assert probe.position >= 10**9
    probe2 = copy.deepcopy(e)
    probe2.advance(t - 1)
    assert probe2.position < 10**9
    ev = events(e)
    assert ev[-1][1:] == (2**31 - 1, 0)


def test_wrap_rule():
    """MVP (TMCM-1180 manual 3.6.4): a distance above 2^31-1 goes the other way."""
    e = LinearRampEngine()
    e.move_to(-2**31)                                # distance 2^31 from 0: backwards
    e.advance(F)
    assert e.velocity < 0
    assert events(e)[-1][1:] == (-2**31, 0)


def test_parameter_names():
    """Engine keywords are the profile names of AP4, AP5 and AP130 (PD28-1021 manual 2.3)."""
    with pytest.raises(TypeError):
        LinearRampEngine(velocity_v1=100)
    e = LinearRampEngine(max_positioning_speed=1000, max_acceleration=500, minimum_speed=2)
    assert e.params == {"max_positioning_speed": 1000, "max_acceleration": 500, "minimum_speed": 2}


@given(vmax=st.integers(1, 2**31 - 1), acc=st.integers(1, 2**31 - 1), vmin=st.integers(0, 100_000),
       target=st.integers(-2**31, 2**31 - 1), cut=st.integers(0, 10 * F))
def test_exact_arrival_and_split_invariance(vmax, acc, vmin, target, cut):
    """AP4/AP5 over their whole range 1...2147483647 (2.3): exact arrival on the target, and
    the state does not depend on how time was advanced."""
    a = LinearRampEngine(max_positioning_speed=vmax, max_acceleration=acc, minimum_speed=vmin)
    b = copy.deepcopy(a)
    a.move_to(target)
    b.move_to(target)
    b.advance(cut)
    b.advance(2 * cut)
    a.advance(2 * cut)
    assert (a.position, a.velocity_exact, a.next_event()) == (b.position, b.velocity_exact, b.next_event())
    events(a)
    assert a.position == wrap32(target) and a.position_reached


def test_hold_sets_the_actual_speed_at_once():
    """AP3 written (TMCM-1180 manual 4: 'Actual speed' RW): the speed changes without a ramp and
    stays (velocity mode)."""
    e = LinearRampEngine()
    e.move_to(10**6)
    e.advance(F // 2)
    p = e.position
    e.hold(-1000)
    assert (e.velocity, e.mode, e.next_event(), e.position) == (-1000, Mode.VELOCITY, None, p)
    e.advance(F // 2 + F)
    assert e.position == p - 1000
    e.hold(0)
    assert e.velocity == 0 and e.next_event() is None
