"""Unit conversions of the TMCM-6212 (manual 6.5; TMC5130 datasheet, docs/motion.md).

With AP255 = 1 (default) velocities are in pps (microsteps per second) and
accelerations in pps^2. With AP255 = 0 the TMC5130's internal units are used:

    v[pps]   = v_internal * f_CLK / 2^24
    a[pps^2] = a_internal * f_CLK^2 / 2^41        (f_CLK = 16 MHz)

Rounds: v_rps = v_pps / (r_fullstep * r_microstep), v_rpm = 60 * v_rps, with
r_microstep = 2^AP140 and r_fullstep = AP202 (manual 6.5).
"""
from __future__ import annotations

from fractions import Fraction
from numbers import Integral, Rational

from .base import CLOCK_HZ

F_CLK = CLOCK_HZ
VELOCITY_SCALE = Fraction(F_CLK, 1 << 24)
"""pps per internal velocity unit (0.95367431640625)."""
ACCELERATION_SCALE = Fraction(F_CLK * F_CLK, 1 << 41)
"""pps^2 per internal acceleration unit (~116.415)."""

MAX_VELOCITY_PPS = 7999774
"""Manual 4.1 limit of AP2-AP4: the internal value 8388371 (= 2^23 - 237) in pps, rounded."""
MAX_ACCELERATION_PPS2 = 7629278
"""Manual 4.1 limit of AP5 and AP15-18: AMAX's 16-bit maximum 65535 in pps^2, rounded down."""


class UnitError(ValueError):
    """A value that cannot be converted (wrong type or out of range)."""


def _number(name: str, x: object) -> Fraction:
    if isinstance(x, bool) or not isinstance(x, (Rational, float)):
        raise UnitError(f"{name} must be a number, got {x!r}")
    try:
        return Fraction(x)
    except (ValueError, OverflowError) as exc:
        raise UnitError(f"{name} must be finite, got {x!r}") from exc


def round_half_away(x: Fraction) -> int:
    """Round half away from zero."""
    n = abs(x)
    r = int(n + Fraction(1, 2))
    return r if x >= 0 else -r


# --- TMC5130 internal units (AP255 = 0) ------------------------------------
def pps_from_internal_velocity(v: int | Fraction) -> Fraction:
    """Exact pps of an internal velocity value: v * f_CLK / 2^24."""
    return _number("velocity", v) * VELOCITY_SCALE


def internal_velocity_from_pps(pps: int | float | Fraction) -> int:
    """Nearest internal velocity value of a pps value."""
    return round_half_away(_number("velocity", pps) / VELOCITY_SCALE)


def pps2_from_internal_acceleration(a: int | Fraction) -> Fraction:
    """Exact pps^2 of an internal acceleration value: a * f_CLK^2 / 2^41."""
    return _number("acceleration", a) * ACCELERATION_SCALE


def internal_acceleration_from_pps2(pps2: int | float | Fraction) -> int:
    """Nearest internal acceleration value of a pps^2 value."""
    return round_half_away(_number("acceleration", pps2) / ACCELERATION_SCALE)


# --- rounds per second / minute (manual 6.5) --------------------------------
def microsteps_per_fullstep(microstep_resolution: int) -> int:
    """AP140 code (0 full step ... 8 = 256 microsteps) -> microsteps per full step."""
    if isinstance(microstep_resolution, bool) or not isinstance(microstep_resolution, Integral) \
            or not 0 <= microstep_resolution <= 8:
        raise UnitError(f"microstep resolution (AP140) must be 0..8, got {microstep_resolution!r}")
    return 1 << int(microstep_resolution)


def _perround_half_away(microstep_resolution: int, fullstep_resolution: int) -> int:
    if isinstance(fullstep_resolution, bool) or not isinstance(fullstep_resolution, Integral) \
            or fullstep_resolution <= 0:
        raise UnitError(f"full step resolution (AP202) must be a positive integer, got {fullstep_resolution!r}")
    return int(fullstep_resolution) * microsteps_per_fullstep(microstep_resolution)


def pps_to_rps(pps, microstep_resolution: int = 8, fullstep_resolution: int = 200) -> Fraction:
    """v_rps = v_pps / (r_fullstep * r_microstep) (manual 6.5)."""
    return _number("velocity", pps) / _perround_half_away(microstep_resolution, fullstep_resolution)


def rps_to_pps(rps, microstep_resolution: int = 8, fullstep_resolution: int = 200) -> Fraction:
    return _number("velocity", rps) * _perround_half_away(microstep_resolution, fullstep_resolution)


def pps_to_rpm(pps, microstep_resolution: int = 8, fullstep_resolution: int = 200) -> Fraction:
    """v_rpm = 60 * v_rps (manual 6.5)."""
    return 60 * pps_to_rps(pps, microstep_resolution, fullstep_resolution)


def rpm_to_pps(rpm, microstep_resolution: int = 8, fullstep_resolution: int = 200) -> Fraction:
    return rps_to_pps(_number("velocity", rpm) / 60, microstep_resolution, fullstep_resolution)
