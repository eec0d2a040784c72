"""Short ramp_mode moves of the TMC429 core settle on the target (TMC4210 datasheet 6.1.3,
6.1.7.1.1, 6.1.9.2, 6.1.12.1): the signed pulse accumulator that walks an overshoot back."""
from __future__ import annotations

from hypothesis import example, given, settings
from hypothesis import strategies as st

from opentmcl.motion.pmulpdiv import a_max_limits, registers_for
from opentmcl.motion.tmc429 import HOLD_MODE, Tmc429Ramp

from .tmc429_reference import ReferenceRamp


def signed(x: int, bits: int = 24) -> int:
    return (x + (1 << (bits - 1))) % (1 << bits) - (1 << (bits - 1))


def test_a_reversal_first_walks_back_the_fraction_of_a_step():
    """6.1.12.1: "one step pulse with each 1/(32 * 2^PULSE_DIV) clock pulse with a given
    theoretical velocity setting of 2048. [Attention: Range +-2047]" - the pulse generator takes
    the signed velocity, so after a reversal the fraction of a step already made forward is
    undone first: with fraction f (of 2048) and |V_ACTUAL| = u the step back comes after
    ceil((f + 1) / u) pulse ticks, not after ceil((2048 - f) / u) (6.1.6: hold_mode sets V_ACTUAL)."""
    forward, ticks_fwd, back = 300, 10, 100
    fraction = forward * ticks_fwd - 2048           # one step made, this much of the next
    expected = -(-(fraction + 1) // back)
    for r in (Tmc429Ramp(), ReferenceRamp()):
        r.set(mode=HOLD_MODE, pulse_div=0)
        r.set(v_actual=forward)
        r.advance(32 * ticks_fwd)
        assert r.x_actual == 1
        r.set(v_actual=-back)
        r.advance(r.now + 32 * (expected - 1))
        assert r.x_actual == 1
        r.advance(r.now + 32)
        assert r.x_actual == 0
    assert expected < -(-(2048 - fraction) // back)  # the old unsigned accumulator was slower


@given(st.integers(0, 3), st.integers(0, 4), st.integers(1, 400))
def test_the_first_move_after_power_on_is_the_same_in_either_direction(pd, extra, distance):
    """6.1.1: X_TARGET may lie on either side ("moves the stepper motor in the direction of
    X_TARGET"); from power-on a move of -d is the mirror image of a move of +d, step for step."""
    runs = []
    for sign in (1, -1):
        r = Tmc429Ramp()
        a_max = min(a_max_limits(pd + extra, pd)[1], 2047) // 3 + 1
        pmul, pdiv = registers_for(a_max, pd + extra, pd)
        r.set(pulse_div=pd, ramp_div=pd + extra, v_min=2, v_max=700, a_max=a_max, pmul=pmul, pdiv=pdiv)
        r.set(x_target=sign * distance)
        steps = []
        while not r.position_reached:
            steps += [(t, d * sign) for t, d in r.step_events(r.next_event())]
        runs.append(steps)
    assert runs[0] == runs[1]
    assert sum(d for _, d in runs[0]) == distance


def _settle(r: Tmc429Ramp, target: int, bound: int) -> tuple[int, int]:
    """Walk from event to event up to `bound` cycles; (cycles taken, largest overshoot)."""
    start, over, x = r.now, 0, r.x_actual
    s = 1 if signed(target - x) > 0 else -1
    while not r.position_reached and r.now < start + bound:
        e = r.next_event()
        if e is None:
            break
        for _, direction in r.step_events(min(e, start + bound)):
            x += direction
            over = max(over, s * signed(x - target))
    return r.now - start, over


moves = st.tuples(st.integers(0, 6), st.integers(0, 6), st.floats(0, 1), st.integers(1, 2047),
                  st.integers(1, 10), st.integers(-60, 60), st.integers(-60, 60))


@example((0, 5, 0.25, 17, 3, 0, 1))        # swung 0 / 1 / 2 for ever before
@example((3, 5, 0.0, 1514, 3, 0, 40))      # overshot by 3 steps and swung 39 / 40 / 41
@settings(deadline=None)
@given(moves)
def test_short_moves_within_the_a_max_limits_settle_in_bounded_time(move):
    """6.1.7.1.1: with A_MAX inside [A_MAX_LOWER_LIMIT, A_MAX_UPPER_LIMIT] any target position is
    reached "without oscillations"; 6.1.3: V_MIN >= 1 "assures reaching each target position
    exactly". Two consecutive short moves (the second one starts with whatever the first left in
    the pulse accumulator) each end on X_TARGET with V_ACTUAL = 0 within twice the time of a ramp
    up to V_MAX and down (6.1.12.1) plus the distance at V_MIN; an overshoot (6.1.9.2 hints) comes
    back."""
    pd, extra, where, v_max, v_min, first, second = move
    rd = pd + extra
    lower, upper = a_max_limits(rd, pd)
    upper = min(upper, 2047)
    a_max = lower + int(where * (upper - lower))
    pmul, pdiv = registers_for(a_max, rd, pd)
    v_max = max(v_max, v_min)
    r = Tmc429Ramp()
    r.set(pulse_div=pd, ramp_div=rd, v_min=v_min, v_max=v_max, a_max=a_max, pmul=pmul, pdiv=pdiv)
    ramp_period, pulse_period = 32 << rd, 32 << pd
    for target in (first, second):
        r.set(x_target=target)
        distance = abs(signed(target - r.x_actual))
        ramps = 2 * (256 * v_max // a_max + 1) * ramp_period
        crawl = distance * 2048 // v_min * pulse_period
        taken, over = _settle(r, target, 2 * (ramps + crawl) + 2 * ramp_period)
        assert r.position_reached and signed(r.x_actual) == target, (taken, over)
        assert r.next_event() is None                  # nothing moves any more
        r.advance(r.now + 50 * ramp_period)
        assert r.position_reached and signed(r.x_actual) == target
