"""Lazy reads of the six-point (TMCM-6212) and linear (PD28-1021) engines (docs/motion.md
"Lazy reads").

`advance` only stores the tick; position (AP1), velocity (AP3) and position reached (AP8) are
evaluated when read and kept for that tick. The ramp they follow: TMCM-6212 firmware manual 4.1
(AP4 "maximum positioning speed", AP5 "maximum acceleration", AP15-AP21 the six-point ramp of the
TMC5130, docs/sources.md "TMC5130"; docs/motion.md "Positioning mode"); PD28-1021 manual ch. 2.3
(AP4, AP5 in pps). The oracles here do not use the engine's read path: the analytic trapezoid of
manual 4.1, and the planned pieces (`segments`) evaluated in exact fractions.
"""
from __future__ import annotations

import math
from fractions import Fraction

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from opentmcl.motion import CLOCK_HZ
from opentmcl.motion.linear import LinearRampEngine
from opentmcl.motion.sixpoint import SixPointRampEngine

from .test_sixpoint import apply, events

F = CLOCK_HZ
ENGINES = [SixPointRampEngine, LinearRampEngine]


def wrap(x: int) -> int:
    return (x + 2**31) % 2**32 - 2**31


def trapezoid(cls):
    """VMAX 51200 pps, AMAX = DMAX 51200 pps^2, no VSTART/VSTOP/V1 jumps: every phase is whole
    ticks (manual 4.1: AP4, AP5, AP17; V1 = 0 disables A1/D1)."""
    if cls is LinearRampEngine:  # one band; AP130 = 0: no minimum-speed jumps
        return cls(max_positioning_speed=51200, max_acceleration=51200, minimum_speed=0)
    return cls(max_positioning_speed=51200, max_acceleration=51200, max_deceleration=51200,
               velocity_v1=0, velocity_vstart=0, velocity_vstop=0, ramp_wait_time=0)


def analytic(k: int) -> tuple[Fraction, Fraction]:
    """Exact (position, velocity) of the 102400-microstep trapezoid at tick k: accelerate 1 s,
    cruise 1 s, decelerate 1 s (x = a t^2 / 2, v = a t)."""
    t = Fraction(k, F)
    a, vmax = 51200, 51200
    if t <= 1:
        return a * t * t / 2, a * t
    if t <= 2:
        return 25600 + vmax * (t - 1), Fraction(vmax)
    if t <= 3:
        r = 3 - t
        return 102400 - a * r * r / 2, a * r
    return Fraction(102400), Fraction(0)


# ticks before, at and after each piece's end (1 s, 2 s, 3 s), and inside the pieces
TICKS = [1, F // 3, F // 2, F - 1, F, F + 1, 3 * F // 2, 2 * F - 1, 2 * F, 2 * F + 1,
         5 * F // 2, 3 * F - 1, 3 * F, 3 * F + 1, 4 * F]


@pytest.mark.parametrize("cls", ENGINES)
def test_reads_follow_the_trapezoid_at_any_tick(cls):
    """Manual 4.1 AP1/AP3/AP8 read at instants before, at and after every phase end: the step
    counter is the last whole microstep passed, AP3 the speed truncated to pps, AP8 set from the
    arrival tick (3 s) on and not one tick earlier."""
    e = trapezoid(cls)
    e.move_to(102400)
    for k in TICKS:
        e.advance(k)
        x, v = analytic(k)
        assert (e.position, e.velocity, e.velocity_exact) == (math.floor(x), math.floor(v), v), k
        assert e.position_reached is (k >= 3 * F), k


@pytest.mark.parametrize("cls", ENGINES)
def test_second_read_at_a_tick_is_the_first(cls):
    """Reading twice at one tick gives the same values (the kept read), and the next tick's
    read is evaluated afresh (0.5 s: 6400 microsteps, one tick later 0.0016 microstep more)."""
    e = trapezoid(cls)
    e.move_to(102400)
    e.advance(F // 2)
    assert [e.position, e.position] == [6400, 6400] and [e.velocity, e.velocity] == [25600, 25600]
    e.advance(F // 2 + 1)
    assert e.position == 6400 and e.velocity_exact == analytic(F // 2 + 1)[1]
    e.advance(3 * F // 2)
    assert (e.position, e.velocity) == (51200, 51200)


@pytest.mark.parametrize("cls", ENGINES)
def test_commands_at_a_read_tick_are_seen_by_the_next_read(cls):
    """Manual 4.1 AP1 ("actual position", writable), MST and MVP (3.6.3, 3.6.4) at a tick that
    was already read: the next read at the same tick shows the new state, not the kept one."""
    e = trapezoid(cls)
    e.move_to(102400)
    e.advance(F // 2)
    assert e.position == 6400
    e.set_position(-7)                       # relabel: AP1 reads the written value at once
    assert e.position == -7 and e.velocity == 25600
    e.set_position(2**31 - 1)                # the last valid 32-bit value
    assert e.position == 2**31 - 1
    e.hard_stop()
    assert (e.position, e.velocity, e.position_reached) == (2**31 - 1, 0, True)
    e.move_to(wrap(2**31 - 1 + 102400))      # across the wrap: the shorter way, forwards
    assert (e.position, e.position_reached) == (2**31 - 1, False)
    e.advance(F // 2 + F // 2)               # half a second into the same trapezoid again
    assert e.position == wrap(2**31 - 1 + 6400) and e.velocity == 25600


def commands(cls):
    """Random commands at random ticks (as tests/motion/test_sixpoint.py, with `cls`'s ramp
    parameters)."""
    return st.lists(st.tuples(st.integers(0, 3 * F), st.one_of(
        st.tuples(st.just("move_to"), st.integers(-300_000, 300_000)),
        st.tuples(st.just("rotate"), st.integers(-200_000, 200_000)),
        st.tuples(st.just("stop")),
        st.tuples(st.just("hold"), st.integers(-200_000, 200_000)),
        st.tuples(st.just("hard_stop")),
        st.tuples(st.just("configure"), st.sampled_from(sorted(cls.PARAMS)), st.integers(0, 200_000)),
        st.tuples(st.just("set_position"), st.integers(-2**31, 2**31 - 1)),
    )), min_size=1, max_size=6)


def oracle(pieces, k: int) -> tuple[int, int, Fraction]:
    """(step counter, truncated pps, exact pps) at tick k from the planned pieces, in Fractions
    (docs/motion.md "Segments": floor while moving forwards, ceil backwards)."""
    s = next(p for p in pieces if p.k0 <= k and (p.k1 is None or k < p.k1))
    x = s.position(k)
    step = math.ceil(x) if s.direction < 0 else math.floor(x)
    v = s.velocity(k) * F
    return step, math.trunc(v), v


@pytest.mark.parametrize("cls", ENGINES)
@settings(max_examples=60, deadline=None)
@given(data=st.data(), reads=st.lists(st.integers(0, 3 * F), min_size=1, max_size=12),
       edges=st.lists(st.integers(-2, 2), max_size=6))
def test_reads_equal_the_plan_at_arbitrary_ticks(cls, data, reads, edges):
    """Commands (MVP, ROR, MST, AP3 hold, hard stop, ramp parameters, AP1) at random ticks,
    reads at random ticks and within two ticks of piece ends: every read equals the plan
    evaluated exactly at that tick, also right after a move_to or configure in a piece."""
    cmds = data.draw(commands(cls))
    e = cls()
    plan = e.segments
    timeline = sorted([(t, 0, cmd) for t, cmd in cmds] + [(t, 1, None) for t in reads])
    for t, is_read, cmd in timeline:
        t = max(t, e.now)
        near = {p.k1 + d for p in plan for d in edges if p.k1 is not None and e.now <= p.k1 + d < t}
        for k in [*sorted(near), t]:
            e.advance(k)
            step, v, vx = oracle(plan, k)
            assert (e.position, e.velocity, e.velocity_exact) == (wrap(step), v, vx)
            assert e.position_reached is (vx == 0 and wrap(step) == e.target_position)
        if not is_read:
            apply(e, cmd)
            plan = e.segments
            step, v, vx = oracle(plan, e.now)
            assert (e.position, e.velocity) == (wrap(step), v)


@pytest.mark.parametrize("cls", ENGINES)
@settings(max_examples=60, deadline=None)
@given(data=st.data(), reads=st.lists(st.integers(0, 3 * F), max_size=10))
def test_reading_does_not_change_later_behaviour(cls, data, reads):
    """An engine read at many ticks and one never read (same commands, same ticks) report the
    same event sequence (tick, position, velocity) and the same state afterwards."""
    cmds = data.draw(commands(cls))
    read, quiet = cls(), cls()
    timeline = sorted([(t, 0, cmd) for t, cmd in cmds] + [(t, 1, None) for t in reads])
    for t, is_read, cmd in timeline:
        for e in (read, quiet):
            e.advance(max(t, e.now))
        if is_read:
            _ = (read.position, read.velocity, read.position_reached, read.moving, read.direction)
        else:
            apply(read, cmd)
            apply(quiet, cmd)
    assert read.segments == quiet.segments
    assert events(read) == events(quiet)
    assert (read.now, read.position, read.velocity_exact, read.position_reached) == \
        (quiet.now, quiet.position, quiet.velocity_exact, quiet.position_reached)


@pytest.mark.parametrize("cls", ENGINES)
def test_position_reached_of_a_moving_engine_evaluates_no_position(cls, monkeypatch):
    """AP8 "position reached" (manual 4.1) is polled after every event by the time loop: while
    the motor moves it is false from the velocity alone, so the position's closed form is not
    evaluated; at rest and once read at the tick it comes from the stored values. The answers
    equal the trapezoid's (false while moving, true at the target)."""
    e = trapezoid(cls)
    e.move_to(51200 * 3)
    reads = []
    real = e._read
    monkeypatch.setattr(e, "_read", lambda: reads.append(e.now) or real())
    for t in (F // 4, F // 2, 2 * F):
        e.advance(t)
        assert e.position_reached is False
    assert reads == []
    e.advance(2 * F)
    position = e.position
    assert reads == [2 * F] and e.position_reached is False and position == e.position
    e.advance(5 * F)  # 1 s up, 2 s at 51200 pps, 1 s down: at rest on the target
    assert e.position_reached is True and e.position == 51200 * 3
