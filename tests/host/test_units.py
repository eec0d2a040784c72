"""Unit conversions pinned to the manuals' formulas and examples."""
from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from opentmcl.host import units


def test_manual_example_51200_pps_is_one_rps_and_60_rpm():
    """TMCM-6212 manual 6.5: "with a 200 fullsteps motor and a microstep setting of 256 (axis
    parameter #140 = 8), a velocity of 51200pps will result in 1rps (60rpm)"."""
    assert units.pps_to_rps(51200, 8, 200) == 1.0
    assert units.pps_to_rpm(51200, 8, 200) == 60.0
    assert units.rps_to_pps(1, 8, 200) == 51200
    assert units.rpm_to_pps(60, 8, 200) == 51200


@pytest.mark.parametrize("code,microsteps", [(0, 1), (1, 2), (2, 4), (3, 8), (4, 16), (5, 32),
                                             (6, 64), (7, 128), (8, 256)])
def test_microstep_resolution_codes(code, microsteps):
    """TMCM-6212 manual 4.1, axis parameter 140: 0 fullstep, 1 halfstep, 2 4 microsteps ... 8 256."""
    assert units.microsteps_per_fullstep(code) == microsteps


def test_fullstep_resolution_enters_the_formula():
    """TMCM-6212 manual 6.5: v_rps = v_pps / (r_fullstep * r_microstep); a 0.9° motor has 400 steps."""
    assert units.pps_to_rps(6400, 4, 400) == 1.0
    assert units.pps_to_rpm(3200, 4, 400) == 30.0


@pytest.mark.parametrize("bad", [-1, 9, 2.0, True, "8"])
def test_bad_microstep_code_is_a_value_error(bad):
    """Axis parameter 140 accepts only 0..8 (TMCM-6212 manual 4.1)."""
    with pytest.raises(ValueError, match="140"):
        units.pps_to_rps(100, bad, 200)


@pytest.mark.parametrize("bad", [0, -200, 1.8])
def test_bad_fullstep_resolution_is_a_value_error(bad):
    with pytest.raises(ValueError, match="202"):
        units.rps_to_pps(1, 8, bad)


def test_tmc429_velocity_2048_at_pulse_div_0_is_one_step_per_32_clocks():
    """TMC4210 datasheet 6.1.12.1: "generates one step pulse with each 1/(32*2^PULSE_DIV) clock pulse
    with a given theoretical velocity setting of 2048"; 1.4.1: f_CLK/32 = 500 kHz at 16 MHz."""
    assert units.tmc429_velocity_to_pps(2048, 0) == 500_000.0
    assert units.tmc429_velocity_to_pps(2048, 3) == 500_000.0 / 8


def test_tmc429_velocity_formula():
    """TMC4210 datasheet 6.1.12.1: R[Hz] = f_CLK * velocity / (2^PULSE_DIV * 2048 * 32)."""
    assert units.tmc429_velocity_to_pps(1000, 5) == pytest.approx(16e6 * 1000 / (32 * 65536))
    assert units.pps_to_tmc429_velocity(16e6 * 1000 / (32 * 65536), 5) == 1000


def test_tmc429_acceleration_formula():
    """TMC4210 datasheet 6.1.12.1: dR[Hz/s] = f_CLK^2 * A_MAX / 2^(PULSE_DIV + RAMP_DIV + 29)."""
    assert units.tmc429_accel_to_pps2(1000, 5, 7) == pytest.approx(16e6**2 * 1000 / 2**41)
    assert units.pps2_to_tmc429_accel(16e6**2 * 1000 / 2**41, 5, 7) == 1000


@pytest.mark.parametrize("pd,rd", [(-1, 0), (14, 0), (0, 14)])
def test_tmc429_divisors_out_of_range(pd, rd):
    """PD86-1180 manual 5, axis parameters 153 / 154: ramp and pulse divisor are 0..13."""
    with pytest.raises(ValueError):
        units.tmc429_accel_to_pps2(1, pd, rd)


def test_tmc5130_acceleration_limit_matches_manual_range():
    """TMCM-6212 manual 4.1, parameter 5: 0...7629278 pps²; AMAX 2^16-1 with a = AMAX*f_CLK²/2^41."""
    assert int(units.tmc5130_accel_to_pps2(2**16 - 1)) == 7629278


@given(st.integers(0, 2047), st.integers(0, 13))
def test_tmc429_velocity_round_trip(v, pd):
    """Converting internal -> pps -> internal gives the same integer."""
    assert units.pps_to_tmc429_velocity(units.tmc429_velocity_to_pps(v, pd), pd) == v


@given(st.integers(-8_000_000, 8_000_000), st.integers(0, 8), st.integers(1, 1000))
def test_pps_rps_round_trip(pps, code, fullsteps):
    assert units.rps_to_pps(units.pps_to_rps(pps, code, fullsteps), code, fullsteps) == pps
