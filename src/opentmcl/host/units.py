"""Unit helpers: pps <-> rps/rpm, and ramp-generator internal units <-> pps.

- pps and rounds: TMCM-6212 manual 6.5 "Velocity and Acceleration Calculation":
  ``v_rps = v_pps / (r_fullstep * r_microstep)``, ``v_rpm = 60 * v_rps``, where
  r_microstep = 2**(axis parameter 140) microsteps per full step (0 = full step ...
  8 = 256 microsteps) and r_fullstep is axis parameter 202 (200 for a 1.8° motor).
- TMC429 units (TMCM-1180 / PD86-1180, whose velocity parameters are 0..2047
  internal units): TMC4210 datasheet 6.1.12.1 and PD86-1180 manual ch. 5 units:
  ``R[Hz] = f_CLK * velocity / (2**pulse_div * 2048 * 32)`` and
  ``dR[Hz/s] = f_CLK**2 * A_MAX / 2**(pulse_div + ramp_div + 29)``, f_CLK = 16 MHz.
- TMC5130 units (TMCM-6212 with axis parameter 255 = 0; TMC5130 datasheet, docs/assumptions.md):
  ``v = v_internal * f_CLK / 2**24``, ``a = a_internal * f_CLK**2 / 2**41``.

Conversions to physical units return floats; conversions to module units return
the nearest integer (halves away from zero), as the module takes only integers.
A bad argument (not a number, not finite, out of range) is a `TmclValueError` or
`TmclTypeError` (also a ValueError / TypeError) with a one-line message.
"""
from __future__ import annotations

import functools
import math
from collections.abc import Callable
from typing import ParamSpec, TypeVar

from ..motion import units as exact
from .errors import TmclArgumentError, TmclTypeError, TmclValueError

F_CLK = exact.F_CLK  # Hz, the clock of the TMCM-1180 / TMCM-6212 motion controllers

DIVISORS = range(0, 14)  # pulse_div / ramp_div (axis parameters 154 / 153): 0 .. 13


_P = ParamSpec("_P")
_R = TypeVar("_R")


def _typed(func: Callable[_P, _R]) -> Callable[_P, _R]:
    """Turn the argument errors of the exact layer into TmclValueError / TmclTypeError."""
    @functools.wraps(func)
    def wrapper(*args: _P.args, **kwargs: _P.kwargs) -> _R:
        try:
            return func(*args, **kwargs)
        except TmclArgumentError:
            raise
        except TypeError as exc:
            raise TmclTypeError(f"{func.__name__}: {exc}") from None
        except (ValueError, OverflowError, ZeroDivisionError) as exc:
            raise TmclValueError(f"{func.__name__}: {exc}") from None
    return wrapper


def _round(x: float) -> int:
    """Nearest integer, halves away from zero (as the motion layer rounds)."""
    if not math.isfinite(x):
        raise TmclValueError(f"the result must be finite, got {x}")
    r = int(abs(x) + 0.5)
    return r if x >= 0 else -r


def _int_in(name: str, value: int, allowed: range) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value not in allowed:
        raise TmclValueError(f"{name} must be an integer {allowed.start}..{allowed.stop - 1}, got {value!r}")
    return value


@_typed
def microsteps_per_fullstep(microstep_resolution: int) -> int:
    """Axis parameter 140 code -> microsteps per full step (TMCM-6212 manual 4.1, parameter 140)."""
    return exact.microsteps_per_fullstep(microstep_resolution)


@_typed
def pps_to_rps(pps: float, microstep_resolution: int = 8, fullstep_resolution: int = 200) -> float:
    """Microsteps per second -> rounds per second (TMCM-6212 manual 6.5)."""
    return float(exact.pps_to_rps(pps, microstep_resolution, fullstep_resolution))


@_typed
def rps_to_pps(rps: float, microstep_resolution: int = 8, fullstep_resolution: int = 200) -> int:
    """Rounds per second -> microsteps per second, rounded to an integer (TMCM-6212 manual 6.5)."""
    return exact.round_half_away(exact.rps_to_pps(rps, microstep_resolution, fullstep_resolution))


@_typed
def pps_to_rpm(pps: float, microstep_resolution: int = 8, fullstep_resolution: int = 200) -> float:
    """Microsteps per second -> rounds per minute (``v_rpm = v_rps * 60``, TMCM-6212 manual 6.5)."""
    return float(exact.pps_to_rpm(pps, microstep_resolution, fullstep_resolution))


@_typed
def rpm_to_pps(rpm: float, microstep_resolution: int = 8, fullstep_resolution: int = 200) -> int:
    """Rounds per minute -> microsteps per second, rounded to an integer."""
    return exact.round_half_away(exact.rpm_to_pps(rpm, microstep_resolution, fullstep_resolution))


# ---------------------------------------------------------------- TMC429 / TMC4210 (TMCM-1180)

@_typed
def tmc429_velocity_to_pps(velocity: float, pulse_div: int, f_clk: int = F_CLK) -> float:
    """Internal velocity (0..2047) -> microsteps per second (TMC4210 datasheet 6.1.12.1)."""
    _int_in("pulse_div", pulse_div, DIVISORS)
    return f_clk * velocity / ((1 << pulse_div) * 2048 * 32)


@_typed
def pps_to_tmc429_velocity(pps: float, pulse_div: int, f_clk: int = F_CLK) -> int:
    """Microsteps per second -> internal velocity, rounded (inverse of `tmc429_velocity_to_pps`)."""
    _int_in("pulse_div", pulse_div, DIVISORS)
    return _round(pps * 2 ** pulse_div * 2048 * 32 / f_clk)


@_typed
def tmc429_accel_to_pps2(a_max: int, pulse_div: int, ramp_div: int, f_clk: int = F_CLK) -> float:
    """Internal acceleration A_MAX (0..2047) -> microsteps per second² (TMC4210 datasheet 6.1.12.1)."""
    _int_in("pulse_div", pulse_div, DIVISORS)
    _int_in("ramp_div", ramp_div, DIVISORS)
    return f_clk * f_clk * a_max / (1 << (pulse_div + ramp_div + 29))


@_typed
def pps2_to_tmc429_accel(pps2: float, pulse_div: int, ramp_div: int, f_clk: int = F_CLK) -> int:
    """Microsteps per second² -> internal A_MAX, rounded (inverse of `tmc429_accel_to_pps2`)."""
    _int_in("pulse_div", pulse_div, DIVISORS)
    _int_in("ramp_div", ramp_div, DIVISORS)
    return _round(pps2 * 2 ** (pulse_div + ramp_div + 29) / (f_clk * f_clk))


# ---------------------------------------------------------------- TMC5130 (TMCM-6212, unit mode 0)

@_typed
def tmc5130_velocity_to_pps(velocity: int, f_clk: int = F_CLK) -> float:
    """Internal VMAX-style velocity -> microsteps per second (``v * f_CLK / 2**24``)."""
    if f_clk == F_CLK:
        return float(exact.pps_from_internal_velocity(velocity))
    return velocity * f_clk / 2**24


@_typed
def pps_to_tmc5130_velocity(pps: float, f_clk: int = F_CLK) -> int:
    if f_clk == F_CLK:
        return exact.internal_velocity_from_pps(pps)
    return _round(pps * 2**24 / f_clk)


@_typed
def tmc5130_accel_to_pps2(accel: int, f_clk: int = F_CLK) -> float:
    """Internal AMAX-style acceleration -> microsteps per second² (``a * f_CLK**2 / 2**41``)."""
    if f_clk == F_CLK:
        return float(exact.pps2_from_internal_acceleration(accel))
    return accel * f_clk * f_clk / 2**41


@_typed
def pps2_to_tmc5130_accel(pps2: float, f_clk: int = F_CLK) -> int:
    if f_clk == F_CLK:
        return exact.internal_acceleration_from_pps2(pps2)
    return _round(pps2 * 2**41 / (f_clk * f_clk))
