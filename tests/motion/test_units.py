"""Unit conversions (TMCM-6212 manual 6.5 and 4.1 ranges; docs/sources.md "TMC5130")."""
from __future__ import annotations

from fractions import Fraction

import pytest
from hypothesis import given
from hypothesis import strategies as st

from opentmcl.motion import units


def test_manual_example_51200_pps_is_one_rps():
    """6.5: 'with a 200 fullsteps motor and a microstep setting of 256 (axis parameter #140 = 8),
    a velocity of 51200pps will result in 1rps (60rpm).'"""
    assert units.pps_to_rps(51200, 8, 200) == 1
    assert units.pps_to_rpm(51200, 8, 200) == 60
    assert units.rpm_to_pps(60, 8, 200) == 51200
    assert units.rps_to_pps(1, 8, 200) == 51200


def test_microstep_resolution_codes():
    """4.1 AP140: 0 fullstep, 1 halfstep, 2 4 microsteps ... 8 256 microsteps."""
    assert [units.microsteps_per_fullstep(i) for i in range(9)] == [1, 2, 4, 8, 16, 32, 64, 128, 256]
    assert units.pps_to_rps(400, 1, 200) == 1          # half steps
    with pytest.raises(units.UnitError):
        units.microsteps_per_fullstep(9)
    with pytest.raises(units.UnitError):
        units.pps_to_rps(1, 8, 0)


def test_manual_velocity_limit_from_internal_units():
    """4.1 AP4 range 0...7999774 pps: v_pps = v * 16 MHz / 2^24 of the TMC5130's largest
    usable VMAX value."""
    assert round(units.pps_from_internal_velocity(8388371)) == 7999774
    assert units.internal_velocity_from_pps(7999774) == 8388371
    assert units.pps_from_internal_velocity(2**24) == 16_000_000


def test_manual_acceleration_limit_from_internal_units():
    """4.1 AP5 range 0...7629278 pps^2: a_pps2 = a * 16 MHz^2 / 2^41 with AMAX = 2^16 - 1."""
    assert int(units.pps2_from_internal_acceleration(2**16 - 1)) == 7629278
    assert units.internal_acceleration_from_pps2(7629278) == 2**16 - 1
    assert units.pps2_from_internal_acceleration(2**41) == 16_000_000**2


def test_scales_are_exact():
    """docs/sources.md "TMC5130": v = v_int * f_CLK / 2^24, a = a_int * f_CLK^2 / 2^41, exactly."""
    assert units.VELOCITY_SCALE == Fraction(16_000_000, 2**24)
    assert units.ACCELERATION_SCALE == Fraction(16_000_000**2, 2**41)
    assert units.pps_from_internal_velocity(-1) == -units.VELOCITY_SCALE


@given(st.integers(-(2**23), 2**23))
def test_velocity_round_trip(v):
    """6.5 / AP255 = 0: every internal velocity value survives pps and back."""
    assert units.internal_velocity_from_pps(units.pps_from_internal_velocity(v)) == v


@given(st.integers(0, 2**16 - 1))
def test_acceleration_round_trip(a):
    """6.5 / AP255 = 0: every internal acceleration value survives pps^2 and back."""
    assert units.internal_acceleration_from_pps2(units.pps2_from_internal_acceleration(a)) == a


def test_bad_input():
    """Conversions reject non-numbers and infinities with UnitError."""
    with pytest.raises(units.UnitError):
        units.internal_velocity_from_pps("1")
    with pytest.raises(units.UnitError):
        units.internal_velocity_from_pps(float("inf"))
    with pytest.raises(units.UnitError):
        units.pps_to_rps(1, True, 200)
