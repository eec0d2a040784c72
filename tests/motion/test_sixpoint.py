"""Six-point ramp engine of the TMCM-6212 (manual 4.1 AP0-AP21, 3.6.1-3.6.4; docs/sources.md "TMC5130").

Ramp parameters are chosen so that every phase lasts a whole number of
16 MHz ticks; the analytic times below are then exact tick counts.
"""
from __future__ import annotations

import copy
from fractions import Fraction

import pytest
from hypothesis import given
from hypothesis import strategies as st

from opentmcl.motion import CLOCK_HZ, Mode
from opentmcl.motion.sixpoint import (
    TZEROWAIT_CLOCKS,
    RampParameterError,
    SixPointRampEngine,
    wrap32,
)

F = CLOCK_HZ


def plain(**kw) -> SixPointRampEngine:
    """Trapezoid without the A1/D1 phases and without start/stop jumps."""
    params = dict(max_positioning_speed=51200, max_acceleration=51200, max_deceleration=51200,
                  velocity_v1=0, velocity_vstart=0, velocity_vstop=0, ramp_wait_time=0)
    params.update(kw)
    return SixPointRampEngine(**params)


def events(e, limit=10_000):
    """Advance through every event; returns [(tick, position, velocity)]."""
    out = []
    for _ in range(limit):
        n = e.next_event()
        if n is None:
            return out
        e.advance(n)
        out.append((n, e.position, e.velocity_exact))
    raise AssertionError(f"no rest after {limit} events")


def state(e):
    return (e.now, e.position, e.velocity_exact, e.target_position, e.mode, e.position_reached,
            e.next_event())


# --- positioning: closed-form profiles -------------------------------------------
def test_trapezoid_takes_the_analytic_time():
    """4.1 AP4/AP5: accelerate with AMAX to VMAX, cruise, decelerate: T = D/VMAX + VMAX/AMAX."""
    e = plain()
    e.move_to(102400)
    assert events(e) == [(1 * F, 25600, 51200), (2 * F, 76800, 51200), (3 * F, 102400, 0)]
    assert e.position_reached and e.mode is Mode.POSITION


def test_trapezoid_positions_inside_phases_are_closed_form():
    """Position inside the acceleration phase is a*t^2/2 (floor to whole microsteps)."""
    e = plain()
    e.move_to(102400)
    e.advance(F // 2)           # 0.5 s: 51200 * 0.25 / 2 = 6400
    assert e.position == 6400 and e.velocity == 25600
    e.advance(F // 2 + 1)       # one tick later: still 6400 (0.0016 microstep further)
    assert e.position == 6400
    e.advance(3 * F // 2)       # cruise: 25600 + 0.5 * 51200
    assert e.position == 51200 and e.velocity == 51200


def test_triangular_profile_when_vmax_is_not_reached():
    """Short move: the ramp turns to deceleration before VMAX; D = a*t^2 for a peak at t."""
    e = plain()
    e.move_to(12800)            # peak at 0.5 s with 25600 pps, arrival at 1 s
    assert events(e) == [(F // 2, 6400, 25600), (F, 12800, 0)]


def test_triangular_profile_with_irrational_peak():
    """Peak time sqrt(D/a) is irrational: the deceleration starts on the first whole tick at
    which the remaining distance is at most the braking distance v^2/(2*DMAX); the motor
    then meets the target a moment early with a small residual speed and stops there."""
    e = plain()
    e.move_to(25600)
    peak_tick = 2**0.5 / 2 * F                          # analytic peak at 0.7071 s
    (k, p, v), (arrival, p_end, v_end) = events(copy.deepcopy(e))
    assert k == int(peak_tick) + 1                       # first whole tick after the peak
    before = copy.deepcopy(e)
    before.advance(k - 1)
    rem = 25600 - Fraction(before.segments[0].position(k - 1))
    assert rem > Fraction(before.velocity_exact) ** 2 / (2 * 51200)
    assert (p_end, v_end) == (25600, 0)
    last = copy.deepcopy(e)
    last.advance(arrival - 1)
    assert 0 < last.velocity_exact < 25                  # residual speed jump, like a VSTOP of < 25 pps
    assert abs(arrival - 2 * peak_tick) < 7000           # sqrt(2 * residual / DMAX) early at most


def test_a1_v1_d1_phases():
    """4.1 AP15-18: A1 from VSTART to V1, AMAX to VMAX, DMAX down to V1, D1 down to VSTOP."""
    e = plain(acceleration_a1=102400, velocity_v1=25600, max_deceleration=51200, deceleration_d1=102400)
    e.move_to(96000)
    assert events(e) == [
        (F // 4, 3200, 25600),            # A1 phase: 0.25 s
        (3 * F // 4, 22400, 51200),       # AMAX phase: 0.5 s
        (7 * F // 4, 73600, 51200),       # cruise: 1 s
        (9 * F // 4, 92800, 25600),       # DMAX phase
        (5 * F // 2, 96000, 0),           # D1 phase, arrival
    ]


def test_v1_zero_disables_a1_and_d1():
    """4.1 AP16: 'Setting this value to 0 turns off the first acceleration / deceleration phase'."""
    e = plain(acceleration_a1=1, deceleration_d1=1, velocity_v1=0)
    e.move_to(102400)
    assert events(e)[-1] == (3 * F, 102400, 0)


def test_vstart_and_vstop_jumps():
    """4.1 AP19/AP20: the motor starts at VSTART and stops from VSTOP."""
    e = plain(velocity_vstart=12800, velocity_vstop=12800)
    e.move_to(99200)
    e.advance(1)
    assert e.velocity == 12800
    ev = events(e)
    assert ev == [(3 * F // 4, 24000, 51200), (7 * F // 4, 75200, 51200), (5 * F // 2, 99200, 0)]
    e2 = plain(velocity_vstart=12800, velocity_vstop=12800)
    e2.move_to(99200)
    e2.advance(5 * F // 2 - 1)
    assert e2.velocity >= 12800 and e2.position < 99200   # last tick before the stop: still at VSTOP


def test_default_vstop_stops_exactly_on_target():
    """Manual default VSTOP = 10 pps: the motor stops on the target, never beyond."""
    e = SixPointRampEngine()
    e.move_to(-12345)
    ev = events(e)
    assert ev[-1][1:] == (-12345, 0)
    assert all(p >= -12345 for _, p, _ in ev)
    assert e.position_reached


def test_negative_direction_is_the_mirror_image():
    """MVP with a negative target runs the same profile backwards."""
    e = plain()
    e.move_to(-102400)
    assert events(e) == [(F, -25600, -51200), (2 * F, -76800, -51200), (3 * F, -102400, 0)]


# --- ramp wait time (TZEROWAIT) ---------------------------------------------------
def test_ramp_wait_before_reversal():
    """4.1 AP21: 'waiting time after ramping down to zero velocity before next movement or
    direction inversion can start' (units of 0.000032 s = 512 clocks)."""
    wait = 1000 * TZEROWAIT_CLOCKS
    assert wait == 512_000
    e = plain(ramp_wait_time=1000, velocity_vstart=12800, velocity_vstop=12800)
    e.move_to(1_000_000)
    e.advance(F)                       # cruising at 51200 pps
    e.move_to(0)                       # target behind: ramp down, wait, come back
    ev = events(copy.deepcopy(e))
    stop_tick = next(t for t, _, v in ev if v == 0)
    assert stop_tick == F + 3 * F // 4  # DMAX from 51200 down to VSTOP 12800: 0.75 s
    assert ev[-1][1:] == (0, 0)
    e.advance(stop_tick)
    p_stop = e.position
    e.advance(stop_tick + wait - 1)
    assert (e.position, e.velocity) == (p_stop, 0)
    e.advance(stop_tick + wait)
    assert e.velocity == -12800           # -VSTART right after the wait


def test_ramp_wait_delays_the_next_move_after_arrival():
    """4.1 AP21: the wait also holds back the next movement after a stop."""
    e = plain(ramp_wait_time=100)
    e.move_to(12800)
    events(e)
    arrival = e.now
    e.advance(arrival + 10)
    e.move_to(0)
    assert e.next_event() == arrival + 100 * 512
    e.advance(arrival + 100 * 512)
    assert e.position == 12800
    events(e)
    assert e.now == arrival + 100 * 512 + F


# --- velocity mode ------------------------------------------------------------------
def test_velocity_mode_ramps_with_amax_only():
    """4.1 AP5: 'Acceleration and deceleration value in velocity mode'; A1/V1/VSTART are
    'in position mode only'."""
    e = plain(max_acceleration=25600, acceleration_a1=1, velocity_v1=1000, velocity_vstart=10000)
    e.rotate(51200)
    assert e.mode is Mode.VELOCITY and e.target_velocity == 51200
    e.advance(1)
    assert e.velocity == 0                            # no VSTART jump
    assert e.next_event() == 2 * F
    e.advance(2 * F)
    assert (e.position, e.velocity) == (51200, 51200)
    assert e.next_event() is None                     # cruising: nothing changes


def test_direction_change_through_zero_in_velocity_mode():
    """ROR then ROL: decelerate through zero with AMAX and accelerate the other way."""
    e = plain()
    e.rotate(51200)
    e.advance(F)
    e.rotate(-51200)
    assert e.next_event() == 2 * F
    e.advance(2 * F)
    assert (e.position, e.velocity) == (51200, 0)
    e.advance(2 * F + F // 2)
    assert e.velocity == -25600 and e.position == 51200 - 6400
    events(e)
    assert (e.now, e.position, e.velocity) == (3 * F, 25600, -51200)


def test_ramp_wait_before_a_direction_inversion_in_velocity_mode():
    """4.1 AP21: "waiting time after ramping down to zero velocity before next movement or direction
    inversion can start" - in velocity mode too (issue 29 item 6): ROR then ROL ramps down with
    AMAX, stands for exactly AP21 * 512 clocks, then ramps up the other way."""
    e = plain(ramp_wait_time=1000)
    wait = 1000 * TZEROWAIT_CLOCKS
    e.rotate(51200)                                   # power-up: at rest long ago, no wait
    e.advance(F)
    assert e.velocity == 51200
    e.rotate(-51200)
    e.advance(2 * F)
    assert (e.position, e.velocity) == (51200, 0)     # ramped down, at rest
    assert e.next_event() == 2 * F + wait
    e.advance(2 * F + wait - 1)
    assert (e.position, e.velocity) == (51200, 0)
    events(e)
    assert (e.now, e.position, e.velocity) == (3 * F + wait, 25600, -51200)


def test_ramp_wait_before_a_rotation_from_rest():
    """4.1 AP21: "before next movement ... can start": ROR within AP21 of coming to rest (here MST)
    starts when the wait is over; a change of speed in the same direction is not delayed."""
    e = plain(ramp_wait_time=100)
    e.rotate(51200)
    e.advance(F)
    e.stop()                                          # MST: at rest at 2 F
    e.advance(2 * F + 10)
    e.rotate(51200)
    assert e.next_event() == 2 * F + 100 * 512
    e.advance(2 * F + 100 * 512)
    assert e.velocity == 0
    e.advance(2 * F + 100 * 512 + F // 2)
    assert e.velocity == 25600
    e.rotate(12800)                                   # slower, same direction: at once
    assert e.next_event() == 2 * F + 100 * 512 + F // 2 + F // 4


def test_mst_is_a_soft_stop_with_amax():
    """3.6.3 MST: 'The velocity mode is selected. Then, the target speed is set to zero.'"""
    e = plain(max_deceleration=1000)                  # DMAX must not be used
    e.move_to(10**8)
    e.advance(F)
    e.stop()
    assert e.mode is Mode.VELOCITY and e.target_velocity == 0
    assert events(e) == [(2 * F, 51200, 0)]


def test_position_reached_flag():
    """4.1 AP8 'always set when target position and actual position are equal' (and the
    motor stands there; see docs/assumptions.md)."""
    e = plain()
    assert e.position_reached
    e.move_to(12800)
    assert not e.position_reached
    e.advance(F - 1)
    assert not e.position_reached
    e.advance(F)
    assert e.position_reached
    e.rotate(1000)
    e.advance(F + 1000)
    assert not e.position_reached


# --- on-the-fly changes ----------------------------------------------------------------
def test_target_change_further_on_the_fly():
    """MVP during a move: the ramp continues to the new target."""
    e = plain()
    e.move_to(102400)
    e.advance(3 * F // 2)
    e.move_to(153600)
    assert events(e)[-1] == (4 * F, 153600, 0)


def test_target_change_too_close_overshoots_and_reverses():
    """A target that cannot be reached with DMAX any more: ramp down, then back (as the
    TMC5130 does)."""
    e = plain()
    e.move_to(10**6)
    e.advance(F)                                       # at 25600 with 51200 pps
    e.move_to(30000)                                   # needs 25600 steps to stop: overshoot
    ev = events(e)
    peak = max(p for _, p, _ in ev)
    assert peak > 30000
    assert peak == 25600 + 25600                       # stopped after the full braking distance
    assert ev[-1][1:] == (30000, 0) and e.position_reached


def test_target_behind_reverses():
    """3.6.4 MVP "Further commands may follow without waiting for the motor reaching its end
    position": a target behind the moving motor makes it ramp down with DMAX and come back."""
    e = plain()
    e.move_to(10**6)
    e.advance(F)
    e.move_to(-1000)
    ev = events(e)
    assert ev[0] == (2 * F, 51200, 0)                  # ramp down first
    assert ev[-1][1:] == (-1000, 0)


def test_lower_vmax_mid_move_decelerates_with_dmax():
    """AP4 changed on the fly: the ramp slows down to the new VMAX with DMAX."""
    e = plain(max_deceleration=25600)
    e.move_to(10**6)
    e.advance(F)
    e.configure(max_positioning_speed=25600)
    assert e.next_event() == 2 * F
    e.advance(2 * F)
    assert e.velocity == 25600
    assert events(e)[-1][1:] == (10**6, 0)


def test_configure_with_same_values_keeps_the_plan():
    """Re-planning from the present state reproduces the same motion (also while braking)."""
    ref = SixPointRampEngine(velocity_v1=20000, deceleration_d1=30000, velocity_vstop=7)
    ref.move_to(77777)
    final = events(copy.deepcopy(ref))[-1]
    for t in (F // 3, F, 3 * F // 2, final[0] - 1000):
        e = copy.deepcopy(ref)
        e.advance(t)
        e.configure(max_positioning_speed=51200, velocity_v1=20000)
        e.configure(max_acceleration=51201)
        e.configure(max_acceleration=51200)
        assert events(e)[-1] == final


def test_vmax_zero_stops_and_resumes():
    """4.1 AP4 range 0...7999774: VMAX = 0 during a move ramps the motor to rest short of the
    target (AP8 = 0); restoring AP4 completes the move."""
    e = plain()
    e.move_to(10**6)
    e.advance(F)
    e.configure(max_positioning_speed=0)
    assert events(e) == [(2 * F, 51200, 0)]
    assert not e.position_reached
    e.configure(max_positioning_speed=51200)
    assert events(e)[-1][1:] == (10**6, 0)


# --- position counter -------------------------------------------------------------------
def test_wrap_rule_shorter_way_through_overflow():
    """3.6.4 Note: 'The distance between the actual position and the new position must not
    be more than 2147483647 microsteps. Otherwise the motor will run in the opposite
    direction in order to take the shorter distance (caused by 32 bit overflow).'"""
    e = plain()
    e.set_position(2147483000)
    e.move_to(-2147483000)                             # 1296 steps forwards through 2^31
    ev = events(e)
    assert ev[-1][1:] == (-2147483000, 0)
    assert all(v >= 0 for *_, v in ev)


@pytest.mark.parametrize("distance, direction", [(2**31 - 1, 1), (2**31, -1)])
def test_wrap_rule_boundary(distance, direction):
    """3.6.4 Note: 2^31-1 is the largest distance run in its own direction."""
    e = plain()
    e.move_to(wrap32(distance))
    e.advance(F)
    assert e.velocity == direction * 51200


def test_position_counter_wraps_in_velocity_mode():
    """AP1 range -2147483648 ... 2147483647: the 32-bit counter wraps."""
    e = plain()
    e.set_position(2**31 - 100)
    e.rotate(51200)
    e.advance(2 * F)
    assert e.position == wrap32(2**31 - 100 + 25600 + 51200)


def test_set_position_while_standing_keeps_position_reached():
    """4.1 AP1: 'Should normally only be overwritten for reference position setting.'"""
    e = plain()
    e.move_to(12800)
    events(e)
    e.set_position(0)
    assert (e.position, e.target_position, e.position_reached, e.next_event()) == (0, 0, True, None)


def test_set_position_while_moving_relabels_the_motion():
    """4.1 AP1 "Stop the motor before overwriting it": if it is overwritten anyway, the
    counter and AP0 are relabelled together and the motion goes on unchanged."""
    e = plain()
    e.move_to(102400)
    e.advance(F)
    e.set_position(0)                                  # was 25600
    assert e.target_position == 102400 - 25600
    assert events(e)[-1] == (3 * F, 76800, 0)


def test_hard_stop():
    """Hard stop (stop switch / heartbeat, RampEngine.hard_stop): speed 0 at once, AP0 := AP1."""
    e = plain()
    e.move_to(102400)
    e.advance(F)
    e.hard_stop()
    assert (e.position, e.velocity, e.target_position, e.position_reached) == (25600, 0, 25600, True)
    assert e.next_event() is None


# --- time_at_position ------------------------------------------------------------------
def test_time_at_position_closed_form():
    """Position 25600 of the trapezoid is reached at exactly 1 s, 6400 at 0.5 s."""
    e = plain()
    e.move_to(102400)
    assert e.time_at_position(25600) == F
    assert e.time_at_position(6400) == F // 2
    assert e.time_at_position(0) == 0
    assert e.time_at_position(102401) is None
    assert e.time_at_position(-5) is None


@given(target=st.integers(-200_000, 200_000), frac=st.floats(0, 1),
       vstop=st.integers(0, 5000), v1=st.integers(0, 40000))
def test_time_at_position_is_the_first_tick_there(target, frac, vstop, v1):
    """4.1 AP1 actual position: time_at_position(x) is the first tick at which AP1 = x."""
    e = SixPointRampEngine(velocity_vstop=vstop, velocity_v1=v1, deceleration_d1=30000)
    e.move_to(target)
    x = round(target * frac)
    t = e.time_at_position(x)
    assert t is not None
    probe = copy.deepcopy(e)
    probe.advance(t)
    assert probe.position == x
    if t > 0:
        before = copy.deepcopy(e)
        before.advance(t - 1)
        assert before.position != x


def test_time_at_position_across_the_wrap():
    """4.1 AP1 range -2147483648 ... 2147483647: the search follows the 32-bit wrap."""
    e = plain()
    e.set_position(2**31 - 10)
    e.rotate(51200)
    t = e.time_at_position(-2**31 + 5)
    e.advance(t)
    assert e.position == -2**31 + 5


# --- exactness, cost, split invariance --------------------------------------------------
ramp_params = st.fixed_dictionaries({
    "max_positioning_speed": st.integers(1, 7999774),
    "max_acceleration": st.integers(1, 7629278),
    "acceleration_a1": st.integers(1, 7629278),
    "velocity_v1": st.integers(0, 1_000_000),
    "max_deceleration": st.integers(1, 7629278),
    "deceleration_d1": st.integers(1, 7629278),
    "velocity_vstart": st.integers(0, 249999),
    "velocity_vstop": st.integers(0, 249999),
    "ramp_wait_time": st.integers(0, 65535),
})


@given(params=ramp_params, target=st.integers(-2**31, 2**31 - 1), start=st.integers(-2**31, 2**31 - 1))
def test_arrives_exactly_and_never_overshoots(params, target, start):
    """Positioning: the counter ends exactly on the target (AP8 set) and moves
    monotonically towards it, whatever the ramp parameters."""
    e = SixPointRampEngine(**params)
    e.set_position(start)
    e.move_to(target)
    d = wrap32(target - start)
    assert all(s.direction in (0, (d > 0) - (d < 0)) for s in e.segments)
    ev = events(e)
    assert e.position == target and e.position_reached and e.velocity == 0
    assert len(ev) <= 8                                 # a handful of segments, any distance


def test_one_hour_move_costs_a_handful_of_segments():
    """docs/architecture.md "Time": a one-hour move is a few segment computations."""
    e = plain(max_positioning_speed=1000, max_acceleration=100, max_deceleration=100)
    e.move_to(3600 * 1000)
    assert len(e.segments) <= 4
    ev = events(e)
    assert len(ev) == 3 and ev[-1][0] == (3600 + 10) * F


commands = st.lists(st.tuples(
    st.integers(0, 3 * F),
    st.one_of(
        st.tuples(st.just("move_to"), st.integers(-300_000, 300_000)),
        st.tuples(st.just("rotate"), st.integers(-200_000, 200_000)),
        st.tuples(st.just("stop")),
        st.tuples(st.just("hold"), st.integers(-200_000, 200_000)),
        st.tuples(st.just("hard_stop")),
        st.tuples(st.just("configure"), st.sampled_from(sorted(SixPointRampEngine.PARAMS)),
                  st.integers(0, 200_000)),
        st.tuples(st.just("set_position"), st.integers(-2**31, 2**31 - 1)),
    )), min_size=1, max_size=6)


def apply(e, cmd):
    name, *args = cmd
    if name == "configure":
        e.configure(**{args[0]: args[1]})
    else:
        getattr(e, name)(*args)


@given(cmds=commands, splits=st.lists(st.integers(0, 3 * F), max_size=8), end=st.integers(0, 4 * F))
def test_advance_split_invariance(cmds, splits, end):
    """advance(a); advance(b) == advance(b): the state never depends on how time was cut."""
    cmds = sorted(cmds, key=lambda c: c[0])
    a, b = SixPointRampEngine(), SixPointRampEngine()
    cuts = sorted(splits)
    for t, cmd in cmds:
        a.advance(max(t, a.now))
        while cuts and cuts[0] <= t:
            b.advance(max(cuts.pop(0), b.now))
        b.advance(max(t, b.now))
        assert state(a) == state(b)
        apply(a, cmd)
        apply(b, cmd)
    last = max([cmds[-1][0] + end, *splits])
    while cuts:
        b.advance(max(cuts.pop(0), b.now))
    a.advance(max(last, a.now))
    b.advance(max(last, b.now))
    assert state(a) == state(b)


@given(cmds=commands)
def test_event_stepping_equals_one_jump(cmds):
    """Stepping through next_event() gives the same state as one advance()."""
    e = SixPointRampEngine()
    for _, cmd in sorted(cmds, key=lambda c: c[0]):
        apply(e, cmd)
        e.advance(e.now + F // 7)
    ref = copy.deepcopy(e)
    horizon = e.now + 5 * F
    ref.advance(horizon)
    while (n := e.next_event()) is not None and n <= horizon:
        e.advance(n)
    e.advance(horizon)
    assert state(e) == state(ref)


# --- bad input -------------------------------------------------------------------------
def test_bad_input_raises_typed_errors():
    """Bad ramp parameters or commands raise typed errors and leave the state unchanged."""
    e = SixPointRampEngine()
    with pytest.raises(RampParameterError):
        e.configure(max_acceleration=-1)
    with pytest.raises(RampParameterError):
        SixPointRampEngine(velocity_vstop="fast")
    with pytest.raises(RampParameterError):
        e.configure(max_acceleration=float("nan"))
    with pytest.raises(TypeError):
        e.configure(minimum_speed=1)
    with pytest.raises(TypeError):
        e.move_to(1.5)
    with pytest.raises(ValueError):
        e.advance(-1)
    with pytest.raises(TypeError):
        e.advance(0.5)
    assert e.position == 0 and e.position_reached


def test_zero_accelerations_never_hang():
    """AMAX = 0 with VSTART = 0: the motor cannot start (no hang, no event)."""
    e = plain(max_acceleration=0)
    e.move_to(1000)
    assert e.next_event() is None and e.position == 0 and not e.position_reached
    e = plain(max_deceleration=0)                      # no deceleration ramp: stops dead on target
    e.move_to(51200)
    assert events(e)[-1][1:] == (51200, 0)


def test_internal_unit_parameters_are_exact():
    """AP255 = 0 values converted to fractional pps by units.py are used exactly."""
    from opentmcl.motion.units import pps2_from_internal_acceleration, pps_from_internal_velocity
    e = plain(max_positioning_speed=pps_from_internal_velocity(2**20),     # 1000000 pps
              max_acceleration=pps2_from_internal_acceleration(2**11),     # 238418.58 pps^2
              max_deceleration=pps2_from_internal_acceleration(2**11))
    e.rotate(pps_from_internal_velocity(2**20))
    assert e.velocity_exact == 0 and e.target_velocity == 1_000_000
    assert e.next_event() == 2**26                       # (2^20 / 2^24) / (2^11 / 2^41) ticks exactly


@given(params=ramp_params, first=st.integers(-10**6, 10**6), second=st.integers(-10**6, 10**6),
       when=st.integers(0, 4 * F))
def test_target_change_on_the_fly_always_arrives(params, first, second, when):
    """MVP during a move (3.6.4 'Further commands may follow without waiting'): whatever the
    moment, the motor ends exactly on the new target; a reversal rests for AP21 first."""
    e = SixPointRampEngine(**params)
    e.move_to(first)
    e.advance(when)
    e.move_to(second)
    pieces = list(e.segments)
    ev = events(e)
    assert e.position == second and e.position_reached
    assert len(ev) <= 16
    dirs = [s.direction for s in pieces if s.direction]
    if len(set(dirs)) == 2:                            # reversed: one standstill of >= wait ticks
        waits = [s.k1 - s.k0 for s in pieces if s.standing and s.k1 is not None]
        assert waits == ([params["ramp_wait_time"] * TZEROWAIT_CLOCKS] if params["ramp_wait_time"] else [])


@given(params=ramp_params, change=ramp_params, target=st.integers(-10**6, 10**6),
       when=st.integers(0, 4 * F), keys=st.sets(st.sampled_from(sorted(SixPointRampEngine.PARAMS))))
def test_parameter_change_on_the_fly_still_arrives(params, change, target, when, keys):
    """configure() during a move re-plans from the present state; the target is still met
    exactly (VMAX, accelerations and decelerations all changed at once, too)."""
    e = SixPointRampEngine(**params)
    e.move_to(target)
    e.advance(when)
    e.configure(**{k: change[k] for k in keys})
    events(e)
    assert e.position == target and e.position_reached


@given(v=st.integers(-7999774, 7999774), a=st.integers(1, 7629278), v0=st.integers(-7999774, 7999774))
def test_velocity_mode_reaches_the_exact_target_speed(v, a, v0):
    """ROR/ROL (3.6.1/3.6.2): after the AMAX ramp the actual speed (AP3) equals AP2 exactly."""
    e = plain(max_acceleration=a)
    e.rotate(v0)
    e.advance(F // 3)
    e.rotate(v)
    ev = events(e)
    assert e.velocity_exact == v and e.velocity == v
    assert len(ev) <= 3
