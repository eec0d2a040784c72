"""Converters between TMC4210 register values and Hz / Hz/s (datasheet 1.4.1, 6.1.7.1.1, 6.1.12, 8.1)."""
import math

import pytest

from opentmcl.chips.tmc4210 import units


def test_max_step_rate_is_a_32nd_of_the_clock():
    """1.4.1 / 8.1: "f_STEP_MAX = f_CLK / 32": 500 kHz at 16 MHz, 1 MHz at 32 MHz."""
    assert units.max_step_rate(16_000_000) == 500_000
    assert units.max_step_rate(32_000_000) == 1_000_000


def test_step_rate_formula():
    """6.1.12.1: R = f_CLK * velocity / (2^PULSE_DIV * 2048 * 32)."""
    assert units.step_rate(1024, 0, 16_000_000) == 250_000
    assert units.step_rate(1000, 3, 16_000_000) == pytest.approx(16e6 * 1000 / (8 * 2048 * 32))
    assert units.step_rate(-1000, 3) == -units.step_rate(1000, 3)
    # "one step pulse with each 1/(32 * 2^PULSE_DIV) clock pulse with a theoretical velocity of 2048"
    assert units.step_rate(2047, 0) < units.max_step_rate()


def test_velocity_for_rate_inverts_step_rate():
    """6.1.12.1 solved for the velocity register."""
    for pd in range(14):
        for v in (1, 100, 2047):
            assert units.velocity_for_rate(units.step_rate(v, pd), pd) == v


def test_rate_change_formula_and_its_constant():
    """6.1.12.1: dR = f_CLK^2 * A_MAX / 2^(PULSE_DIV + RAMP_DIV + 29), 2^29 = 32*32*256*2048."""
    assert 2 ** 29 == 32 * 32 * 256 * 2048
    assert units.rate_change(1, 0, 0, 16_000_000) == pytest.approx(16e6 ** 2 / 2 ** 29)
    assert units.rate_change(100, 3, 5, 16_000_000) == pytest.approx(16e6 ** 2 * 100 / 2 ** 37)
    assert units.a_max_for_rate_change(units.rate_change(777, 2, 6), 2, 6) == 777


def test_steps_during_acceleration_is_v_squared_over_two_a():
    """6.1.12.2: S = 1/2 * v^2 / a with v = R and a = dR gives 1/2 * v^2/A_MAX * 2^RAMP_DIV/2^PULSE_DIV / 2^3."""
    for v, a, pd, rd in ((1000, 100, 3, 5), (2047, 1, 0, 0), (300, 2047, 7, 2)):
        r, dr = units.step_rate(v, pd), units.rate_change(a, pd, rd)
        assert units.steps_during_acceleration(v, a, pd, rd) == pytest.approx(0.5 * r * r / dr)


def test_step_pulse_length():
    """8.1: t_STEP = 16 * (1 + STPDIV_4210) / f_CLK; at 16 MHz integer multiples of 1 us."""
    for s in range(16):
        assert units.step_pulse_length(s, 16_000_000) == pytest.approx((1 + s) * 1e-6)
    assert units.step_pulse_cycles(15) == 256


def test_a_max_limits():
    """6.1.7.1.1: lower 2^(RAMP_DIV-PULSE_DIV-1) (1 if the exponent <= 0, half with V_MAX <= 1448),
    upper 2^(RAMP_DIV-PULSE_DIV+12) - 1 (any value up to 2047 when that exceeds 2048)."""
    assert units.a_max_limits(ramp_div=13, pulse_div=0) == (4096, 2047)  # no A_MAX is valid
    assert units.a_max_limits(ramp_div=8, pulse_div=2) == (32, 2047)
    assert units.a_max_limits(ramp_div=8, pulse_div=2, v_max=1448) == (16, 2047)
    assert units.a_max_limits(ramp_div=3, pulse_div=3) == (1, 2047)
    assert units.a_max_limits(ramp_div=0, pulse_div=2) == (1, 1023)
    assert units.a_max_limits(ramp_div=0, pulse_div=13) == (1, 0)


@pytest.mark.parametrize("call", [
    lambda: units.step_rate(2048, 0), lambda: units.step_rate(1, 14), lambda: units.rate_change(-1, 0, 0),
    lambda: units.step_rate(1, 0, f_clk=33e6), lambda: units.step_rate(1, 0, f_clk=0),
    lambda: units.velocity_for_rate(600_000, 0), lambda: units.step_pulse_cycles(16),
    lambda: units.step_rate(float("nan"), 0), lambda: units.steps_during_acceleration(10, 0, 0, 0),
    lambda: units.a_max_for_rate_change(-5, 5, 8),
])
def test_bad_values_raise_unit_error(call):
    """Out-of-range register values (6.1.12: 0..2047, dividers 0..13; 13.3: f_CLK up to 32 MHz;
    6.1.7: A_MAX is "the absolute value of the desired acceleration", so no negative dR)."""
    with pytest.raises(units.UnitError):
        call()


def test_unit_error_is_a_value_error():
    assert issubclass(units.UnitError, ValueError)
    assert math.isclose(units.step_rate(1, 0, 32_000_000), 2 * units.step_rate(1, 0, 16_000_000))
