"""The TMC429 core pinned to the datasheet's formulas and worked numbers."""
from __future__ import annotations

from fractions import Fraction
from math import isqrt

import pytest

from opentmcl.motion.tmc429 import (
    HOLD_MODE,
    RAMP_MODE,
    SOFT_MODE,
    VELOCITY_MODE,
    Tmc429Ramp,
    Tmc429RegisterError,
)

F_CLK = 16_000_000


def ramp(**regs) -> Tmc429Ramp:
    r = Tmc429Ramp()
    r.set(**regs)
    return r


def signed24(x: int) -> int:
    return (x + 2**23) % 2**24 - 2**23


# --- step rate ---------------------------------------------------------------------------
@pytest.mark.parametrize("v", [1, 50, 500, 1000, 2047])
@pytest.mark.parametrize("pulse_div", [0, 1, 3, 7, 13])
def test_step_rate_formula(v, pulse_div):
    """TMC4210 datasheet 6.1.12.1: R[Hz] = f_CLK * velocity / (2^PULSE_DIV * 2048 * 32).
    Over one second at 16 MHz: one step per 2048/v ticks of the f_CLK/(32 * 2^PULSE_DIV)
    pulse clock, i.e. R steps up to the last unfinished pulse tick."""
    r = ramp(mode=HOLD_MODE, pulse_div=pulse_div)
    r.set(v_actual=v)
    r.advance(F_CLK)
    pulse_ticks = F_CLK // (32 * 2**pulse_div)
    assert r.x_actual == pulse_ticks * v // 2048
    rate = Fraction(F_CLK * v, 2**pulse_div * 2048 * 32)
    assert abs(r.x_actual - rate) < 1 + Fraction(v, 2048)


def test_maximum_step_frequency_at_16_mhz():
    """TMC4210 datasheet 1.4.1 and 8.1: f_CLK = 16 MHz gives up to 500 kHz microsteps
    ("one step pulse with each 1/(32 * 2^PULSE_DIV) clock pulse with a theoretical
    velocity setting of 2048", range +-2047): V_ACTUAL = 2047 makes 2047/2048 of it."""
    r = ramp(mode=HOLD_MODE, pulse_div=0)
    r.set(v_actual=-2047)
    r.advance(F_CLK)
    assert signed24(r.x_actual) == -(500_000 * 2047 // 2048)


def test_pd86_1180_velocity_unit():
    """PD86-1180 manual ch. 5, AP4: unit 16 MHz / 65536 * 2^-pulse_div microsteps/s;
    AP4 = 500 at pulse divisor 0 is 122 070.3 steps/s, at pulse divisor 3 one eighth."""
    for pulse_div, expected in ((0, 122_070), (3, 15_258)):
        r = ramp(mode=HOLD_MODE, pulse_div=pulse_div)
        r.set(v_actual=500)
        r.advance(F_CLK)
        assert r.x_actual == expected == int(Fraction(16_000_000 * 500, 65536 * 2**pulse_div))


def test_steps_fire_on_accumulator_overflow():
    """TMC4210 datasheet 6.1.12.1: one step per 2048/|v| pulse-clock ticks; at v = 1024
    and PULSE_DIV = 0 a step every second pulse tick, i.e. every 64 clock cycles."""
    r = ramp(mode=HOLD_MODE)
    r.set(v_actual=1024)
    assert r.step_events(64 * 5) == [(64 * k, 1) for k in range(1, 6)]


# --- acceleration ------------------------------------------------------------------------
@pytest.mark.parametrize("a_max", [1, 100, 2047])
@pytest.mark.parametrize("pulse_div,ramp_div", [(0, 0), (2, 5), (5, 2), (13, 13)])
def test_acceleration_formula(a_max, pulse_div, ramp_div):
    """TMC4210 datasheet 6.1.12.1: dR/dt = f_CLK^2 * A_MAX / 2^(PULSE_DIV + RAMP_DIV + 29),
    from A_MAX/256 added to the velocity per ramp-clock tick (6.1.9.2); also the
    PD86-1180 manual's acceleration unit 16 MHz^2 / (536870912 * 2^(pd+rd))."""
    assert 2**29 == 32 * 32 * 256 * 2048 == 536_870_912
    r = ramp(mode=VELOCITY_MODE, pulse_div=pulse_div, ramp_div=ramp_div, v_max=2047, a_max=a_max)
    r.set(v_target=2047)
    ticks = 40
    t = ticks * 32 * 2**ramp_div
    r.advance(t)
    assert r.v_internal == ticks * a_max
    rate = Fraction(F_CLK * r.v_internal, 256 * 2**pulse_div * 2048 * 32)
    assert rate == Fraction(F_CLK**2 * a_max, 2 ** (pulse_div + ramp_div + 29)) * Fraction(t, F_CLK)


def test_acceleration_to_full_speed_spans_2048_256_over_a_max_ticks():
    """TMC4210 datasheet 6.1.9.2: "the acceleration from V_ACTUAL = 0 to V_MAX = 2047
    spans over 2048 * 256 / A_MAX ... clock pulses"."""
    for a_max in (1, 256, 1000):
        r = ramp(mode=VELOCITY_MODE, v_max=2047, a_max=a_max)
        r.set(v_target=2047)
        ticks = -(-2047 * 256 // a_max)
        r.advance(32 * (ticks - 1))
        assert r.v_actual < 2047
        r.advance(32 * ticks)
        assert r.v_actual == 2047
        assert abs(ticks - 2048 * 256 / a_max) <= 256 / a_max + 1


@pytest.mark.parametrize("v,a_max,pulse_div,ramp_div", [(2047, 100, 0, 0), (1000, 50, 2, 3),
                                                          (1500, 400, 3, 1), (800, 7, 4, 4)])
def test_steps_during_linear_acceleration(v, a_max, pulse_div, ramp_div):
    """TMC4210 datasheet 6.1.12.2: S = 1/2 * v^2 / A_MAX * 2^RAMP_DIV / 2^PULSE_DIV / 2^3
    steps while accelerating from 0 to v (the integer ramp lands within 1 %)."""
    r = ramp(mode=VELOCITY_MODE, pulse_div=pulse_div, ramp_div=ramp_div, v_max=v, a_max=a_max)
    r.set(v_target=v)
    while r.v_actual < v:
        r.advance(r.next_event())
    s = 0.5 * v * v / a_max * 2**ramp_div / 2**pulse_div / 8
    assert abs(r.x_actual - s) <= 0.01 * s + 2


def test_v_max_lowered_during_motion_decelerates_with_a_max():
    """TMC4210 datasheet 6.1.4: |v| does not exceed V_MAX "except if the limit V_MAX is
    changed during motion to a value below the current velocity": the velocity then
    comes down with A_MAX per ramp tick (6.1.7)."""
    r = ramp(mode=RAMP_MODE, v_max=1000, a_max=64, v_min=1, pmul=255, pdiv=0)
    r.set(x_target=2**22)
    r.advance(32 * 5000)
    assert r.v_actual == 1000
    r.set(v_max=200)
    r.advance(r.now + 32 * 256)
    assert r.v_internal == 1000 * 256 - 64 * 256
    r.advance(r.now + 32 * 10_000)
    assert r.v_actual == 200


def test_a_max_zero_on_the_fly_cannot_stop():
    """TMC4210 datasheet 6.1.7 note: the motion controller cannot stop the motor if
    A_MAX is set to zero on the fly."""
    r = ramp(mode=VELOCITY_MODE, v_max=300, a_max=500)
    r.set(v_target=300)
    r.advance(32 * 1000)
    r.set(a_max=0, v_target=0)
    r.advance(r.now + 32 * 100_000)
    assert r.v_actual == 300
    assert r.next_event() is None


# --- ramp_mode ---------------------------------------------------------------------------
def _p(a_max: int, pulse_div: int, ramp_div: int, reduction: float = 0.0) -> tuple[int, int]:
    """PMUL/PDIV with the finest mantissa for p = A_MAX / (128 * 2^(rd - pd)) (6.1.9.2)."""
    p = Fraction(a_max, 128) / Fraction(2) ** (ramp_div - pulse_div) * Fraction(1 - reduction)
    best = None
    for pdiv in range(14):
        pmul = int(p * 8 * 2**pdiv)
        if 128 <= pmul <= 255:
            best = (pmul, pdiv)
    return best


def test_deceleration_starts_where_the_braking_distance_begins():
    """TMC4210 datasheet 6.1.9.2: with p = 2048 / S (S = steps to accelerate from 0 to
    2048), the chip starts to decelerate about S steps (scaled by v^2/2048^2)
    before the target, so that braking and acceleration ramps are mirror images."""
    a_max = 256
    pmul, pdiv = _p(a_max, 0, 0, reduction=0.01)
    r = ramp(v_max=2047, v_min=1, a_max=a_max, pmul=pmul, pdiv=pdiv)
    r.set(x_target=100_000)
    while r.a_actual >= 0:          # until the velocity starts to fall (signed A_ACTUAL, 2.4)
        r.advance(r.next_event())
    s = 0.5 * 2047**2 / a_max / 8      # 6.1.12.2, T = 1
    remaining = r.dx
    assert s <= remaining <= 1.02 * s + 2


def test_ramp_mode_reaches_target_exactly_with_v_min_at_least_one():
    """TMC4210 datasheet 6.1.3: "Setting V_MIN to at least one assures reaching each
    target position exactly"; the last steps run at V_MIN (6.1.9.2 hints)."""
    for a_max, pd, rd, target in ((100, 0, 0, 5000), (2047, 3, 3, -7777), (10, 2, 4, 3000)):
        pmul, pdiv = _p(a_max, pd, rd, 0.01)
        r = ramp(v_max=700, v_min=1, a_max=a_max, pmul=pmul, pdiv=pdiv, pulse_div=pd, ramp_div=rd)
        r.set(x_target=target)
        seen_v_min = False
        while (e := r.next_event()) is not None:
            r.advance(e)
            seen_v_min |= abs(r.v_actual) == 1 and r.v_target * r.dx > 0
        assert signed24(r.x_actual) == target and r.position_reached
        # below A_MAX = 256 a ramp tick changes |v| by less than one unit, so V_MIN = 1 is
        # reached on the way; with 2047 the last tick before the arrival may be above it
        assert seen_v_min or a_max >= 256


def test_p_too_large_overshoots():
    """TMC4210 datasheet 6.1.9.1 note: "Setting the factor p too large will cause
    overshooting and even oscillations around the target position"; it still settles."""
    a_max = 100
    pmul, pdiv = _p(a_max, 0, 0)
    r = ramp(v_max=2047, v_min=1, a_max=a_max, pmul=pmul, pdiv=max(0, pdiv - 1))   # p doubled
    r.set(x_target=50_000)
    furthest = 0
    while (e := r.next_event()) is not None:
        r.advance(e)
        furthest = max(furthest, signed24(r.x_actual))
    assert furthest > 50_000
    assert r.x_actual == 50_000 and r.position_reached


def test_v_target_reads_the_computed_velocity_in_ramp_mode():
    """TMC4210 datasheet 6.1.9: the velocity "required for stopping in time ... can be
    read in the register V_TARGET" — v = sqrt(2048 * p * |dx|), within [V_MIN, V_MAX]."""
    r = ramp(v_max=2000, v_min=3, a_max=100, pmul=198, pdiv=5)
    for target, expected in ((10_000, 2000), (100, isqrt(2048 * 198 * 100 // 256)), (-2, -56), (0, 0)):
        r.set(x_target=target)
        assert r.v_target == expected
    r.set(pmul=128, pdiv=13, x_target=-1)     # 2048 * 128 / 2^16 * 1 = 4: sqrt 2 < V_MIN
    assert r.v_target == -3


def test_position_difference_must_stay_below_2_pow_23():
    """TMC4210 datasheet 6.1.1: |X_TARGET - X_ACTUAL| < 2^23 for motion into the
    correct direction: beyond it the 24-bit difference wraps and the motor goes the
    other way round."""
    r = ramp(v_max=100, v_min=1, a_max=100, pmul=198, pdiv=5)
    r.set(x_target=2**23 - 1)
    r.advance(32 * 2000)
    assert 0 < r.x_actual < 2**23
    r = ramp(v_max=100, v_min=1, a_max=100, pmul=198, pdiv=5)
    r.set(x_target=2**23 + 1)
    r.advance(32 * 2000)
    assert signed24(r.x_actual) < 0 and r.x_actual > 2**23


def test_x_actual_overwrite_in_ramp_mode_drives_to_x_target():
    """TMC4210 datasheet 6.1.2: "If X_ACTUAL is overwritten in ramp_mode or soft_mode
    the motor directly drives to X_TARGET"."""
    r = ramp(v_max=500, v_min=1, a_max=200, pmul=198, pdiv=4)
    r.set(x_actual=300)
    assert r.x_target == 0
    while (e := r.next_event()) is not None:
        r.advance(e)
    assert r.x_actual == 0 and r.position_reached


def test_x_actual_overwrite_in_velocity_or_hold_mode_stays():
    """TMC4210 datasheet 6.1.2/6.1.4 homing: choose velocity_mode or hold_mode, then
    set X_TARGET and X_ACTUAL; back in ramp_mode nothing moves."""
    r = ramp(v_max=500, v_min=1, a_max=200, pmul=198, pdiv=4, mode=HOLD_MODE)
    r.set(x_actual=1234, x_target=1234)
    r.set(mode=RAMP_MODE)
    r.advance(32 * 10_000)
    assert r.x_actual == 1234 and r.position_reached


def test_start_stop_speed_procedure():
    """TMC4210 datasheet 9.2: V_MIN := V_START_STOP, hold_mode, X_TARGET, V_ACTUAL :=
    +V_MIN, ramp_mode — the motor starts at V_MIN at once and ends on target."""
    pmul, pdiv = _p(50, 0, 0, 0.01)
    r = ramp(v_max=1500, a_max=50, pmul=pmul, pdiv=pdiv)
    r.set(v_min=200)
    r.set(mode=HOLD_MODE)
    r.set(x_target=20_000)
    r.set(v_actual=200)
    r.set(mode=RAMP_MODE)
    first = r.step_events(32 * 11)
    assert first == [(32 * 11, 1)]          # 5 * 200 + 5 * 201 + 201 >= 2048 (6.1.12.1)
    while (e := r.next_event()) is not None:
        r.advance(e)
    assert r.x_actual == 20_000 and r.v_actual == 0


def test_stop_at_target_only_at_or_below_v_min():
    """TMC4210 datasheet 6.1.3: V_MIN is "the absolute velocity value at or below which
    the stepper motor can be stopped abruptly"."""
    r = ramp(mode=HOLD_MODE, v_min=5)
    r.set(x_target=10)
    r.set(v_actual=5)
    r.set(mode=RAMP_MODE)
    r.advance(32 * 5000)
    assert r.x_actual == 10 and r.v_actual == 0


# --- other modes -------------------------------------------------------------------------
def test_velocity_mode_follows_v_target_within_limits():
    """TMC4210 datasheet 6.1.5: in velocity_mode the motor accelerates until it reaches
    V_TARGET, changing velocity according to the motion parameter limits (V_MAX, A_MAX)."""
    r = ramp(mode=VELOCITY_MODE, v_max=300, a_max=1000)
    r.set(v_target=-2000)
    r.advance(32 * 1000)
    assert r.v_actual == -300
    r.set(v_target=100)
    r.advance(r.now + 32)
    assert r.v_internal == -300 * 256 + 1000


def test_hold_mode_ignores_limits_and_writing_zero_stops_at_once():
    """TMC4210 datasheet 6.1.6: V_ACTUAL is writable in hold_mode only, motion limits
    are ignored, and writing zero stops immediately (hidden bits cleared)."""
    r = ramp(mode=VELOCITY_MODE, v_max=10, a_max=3)
    r.set(v_target=10)
    r.advance(32 * 1000)
    r.set(v_actual=2000)                      # ignored outside hold_mode
    assert r.v_actual == 10
    r.set(mode=HOLD_MODE, v_actual=2000)
    r.advance(r.now + 32 * 100)
    assert r.v_actual == 2000
    r.set(v_actual=0)
    assert r.v_internal == 0
    x = r.x_actual
    r.advance(r.now + 32 * 100)
    assert r.x_actual == x


def test_soft_mode_approaches_exponentially():
    """TMC4210 datasheet 6.1.10.1: soft_mode approaches the target "with exponentially
    reduced velocity": the velocity falls with the remaining distance (v = p * dx)."""
    pmul, pdiv = _p(20, 0, 0, 0.01)
    r = ramp(mode=SOFT_MODE, v_max=500, v_min=1, a_max=20, pmul=pmul, pdiv=pdiv)
    r.set(x_target=200_000)
    samples = []
    while (e := r.next_event()) is not None:
        r.advance(e)
        if r.v_internal * r.dx > 0 and r.v_actual < 400:
            samples.append((r.dx, r.v_actual))
    assert r.x_actual == 200_000 and r.position_reached
    p = pmul / 2 ** (3 + pdiv)
    tail = [(d, v) for d, v in samples if 20 < v < 300]
    assert len(tail) > 50
    assert all(abs(v - p * d) <= 2 for d, v in tail)


def test_switch_stops():
    """TMC4210 datasheet 6.1.10.2 soft_stop: 0 = stop immediately, 1 = stop with a
    linear ramp as determined by A_MAX; the motor then stays."""
    r = ramp(mode=VELOCITY_MODE, v_max=1000, a_max=100)
    r.set(v_target=1000)
    r.advance(32 * 5000)
    r.stop(soft=True)
    r.advance(r.now + 32 * 256)
    assert r.v_internal == 1000 * 256 - 100 * 256
    r.advance(r.now + 32 * 10_000)
    assert r.v_actual == 0 and r.v_target == 0
    r = ramp(v_max=1000, v_min=1, a_max=100, pmul=198, pdiv=5)
    r.set(x_target=100_000)
    r.advance(32 * 5000)
    r.stop(soft=False)
    assert r.v_actual == 0 and r.x_target == r.x_actual and r.position_reached


def test_register_errors_are_typed_and_atomic():
    """TMC4210 datasheet 6.1 register table: V_MIN/V_MAX/A_MAX are 11 bit unsigned,
    V_TARGET/V_ACTUAL 12 bit signed (range +-2047, 6.1.12.1), RAMP_MODE 2 bit."""
    r = Tmc429Ramp()
    for bad in ({"v_max": 2048}, {"a_max": -1}, {"v_target": -2048}, {"mode": 4},
                {"pulse_div": 16}, {"x_target": 2**24}, {"bogus": 1}, {"v_min": 1.5}):
        with pytest.raises(Tmc429RegisterError):
            r.set(**bad)
    with pytest.raises(Tmc429RegisterError):
        r.set(v_max=100, a_max=5000)
    assert r.v_max == 0
    with pytest.raises(ValueError):
        r.advance(-1)
    r.set(pmul=5)
    assert r.pmul == 133                      # 6.1.9.1: the MSB of PMUL is fixed to 1
