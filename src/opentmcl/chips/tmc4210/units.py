"""Converters between TMC4210 register values and physical rates (datasheet 6.1.12, 6.1.7, 8.1).

    R [Hz]      = f_CLK * velocity / (2^PULSE_DIV * 2048 * 32)            (6.1.12.1)
    dR [Hz/s]   = f_CLK^2 * A_MAX / 2^(PULSE_DIV + RAMP_DIV + 29)          (6.1.12.1)
    S [steps]   = 1/2 * v^2 / A_MAX * 2^RAMP_DIV / 2^PULSE_DIV / 2^3       (6.1.12.2)
    t_STEP [s]  = 16 * (1 + STPDIV_4210) / f_CLK                            (8.1)
    f_STEP_MAX  = f_CLK / 32                                                (1.4.1, 8.1)
"""
from __future__ import annotations

import math

F_CLK_MAX = 32_000_000
"""Highest operation frequency (13.3: f_CLK 0 .. 32 MHz)."""
V_LIMIT = 2047
A_LIMIT = 2047


class UnitError(ValueError):
    """A value that cannot be converted (out of range, not a number)."""


def check_f_clk(f_clk: object) -> int | float:
    if isinstance(f_clk, bool) or not isinstance(f_clk, (int, float)) or not math.isfinite(f_clk):
        raise UnitError(f"f_clk must be a number of Hz, got {f_clk!r}")
    if not 0 < f_clk <= F_CLK_MAX:
        raise UnitError(f"f_clk {f_clk} Hz out of range (0, {F_CLK_MAX}] (datasheet 13.3)")
    return f_clk


def _div(name: str, value: object) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= 13:
        raise UnitError(f"{name} must be an integer 0..13 (6.1.12), got {value!r}")
    return value


def _number(name: str, value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise UnitError(f"{name} must be a finite number, got {value!r}")
    return value


def step_rate(velocity: int, pulse_div: int, f_clk: float = 16_000_000) -> float:
    """Step pulse rate R in Hz for a velocity register value (6.1.12.1); keeps the sign."""
    _number("velocity", velocity)
    if abs(velocity) > V_LIMIT:
        raise UnitError(f"velocity {velocity} out of range -2047..2047")
    return check_f_clk(f_clk) * velocity / (2 ** _div("PULSE_DIV", pulse_div) * 2048 * 32)


def velocity_for_rate(rate_hz: float, pulse_div: int, f_clk: float = 16_000_000) -> int:
    """The velocity register value (rounded) whose step rate is nearest `rate_hz`."""
    v = round(_number("rate", rate_hz) * 2 ** _div("PULSE_DIV", pulse_div) * 2048 * 32 / check_f_clk(f_clk))
    if abs(v) > V_LIMIT:
        raise UnitError(f"{rate_hz} Hz needs velocity {v:.6g}, beyond +-2047 with PULSE_DIV={pulse_div}")
    return v


def rate_change(a_max: int, pulse_div: int, ramp_div: int, f_clk: float = 16_000_000) -> float:
    """Change of step rate dR in Hz/s for an A_MAX register value (6.1.12.1)."""
    _number("A_MAX", a_max)
    if not 0 <= a_max <= A_LIMIT:
        raise UnitError(f"A_MAX {a_max} out of range 0..2047")
    f = check_f_clk(f_clk)
    return f * f * a_max / 2 ** (_div("PULSE_DIV", pulse_div) + _div("RAMP_DIV", ramp_div) + 29)


def a_max_for_rate_change(hz_per_s: float, pulse_div: int, ramp_div: int, f_clk: float = 16_000_000) -> int:
    """The A_MAX register value (rounded) nearest to a change of step rate of `hz_per_s` Hz/s."""
    f = check_f_clk(f_clk)
    if _number("acceleration", hz_per_s) < 0:
        raise UnitError(f"A_MAX is the absolute value of the acceleration (6.1.7): give a change of step "
                        f"rate >= 0 Hz/s, got {hz_per_s}")
    a = round(hz_per_s
              * 2 ** (_div("PULSE_DIV", pulse_div) + _div("RAMP_DIV", ramp_div) + 29) / (f * f))
    if not 0 <= a <= A_LIMIT:
        raise UnitError(f"{hz_per_s} Hz/s needs A_MAX {a}, outside 0..2047 with "
                        f"PULSE_DIV={pulse_div} RAMP_DIV={ramp_div}")
    return a


def steps_during_acceleration(velocity: int, a_max: int, pulse_div: int, ramp_div: int) -> float:
    """Steps S needed to accelerate from 0 to `velocity` with A_MAX (6.1.12.2)."""
    if not isinstance(a_max, int) or isinstance(a_max, bool) or not 1 <= a_max <= A_LIMIT:
        raise UnitError(f"A_MAX must be 1..2047, got {a_max!r}")
    _number("velocity", velocity)
    return 0.5 * velocity * velocity / a_max * 2 ** _div("RAMP_DIV", ramp_div) / 2 ** _div("PULSE_DIV", pulse_div) / 8


def step_pulse_length(stpdiv: int, f_clk: float = 16_000_000) -> float:
    """Length t_STEP of one step pulse in seconds (8.1); also the direction-to-step delay."""
    return step_pulse_cycles(stpdiv) / check_f_clk(f_clk)


def step_pulse_cycles(stpdiv: int) -> int:
    """t_STEP in CLK cycles: 16 * (1 + STPDIV_4210) (8.1)."""
    if isinstance(stpdiv, bool) or not isinstance(stpdiv, int) or not 0 <= stpdiv <= 15:
        raise UnitError(f"STPDIV_4210 must be 0..15, got {stpdiv!r}")
    return 16 * (1 + stpdiv)


def max_step_rate(f_clk: float = 16_000_000) -> float:
    """f_STEP_MAX = f_CLK / 32 (1.4.1, 8.1)."""
    return check_f_clk(f_clk) / 32


def a_max_limits(ramp_div: int, pulse_div: int, v_max: int | None = None) -> tuple[int, int]:
    """(lower, upper) limit of A_MAX in ramp_mode / soft_mode (6.1.7.1.1).

    lower = 2^(RAMP_DIV - PULSE_DIV - 1), at least 1, halved when V_MAX <= 2048/sqrt(2);
    upper = 2^(RAMP_DIV - PULSE_DIV + 12) - 1, clipped to 2047. A lower limit above
    2047 means no A_MAX is valid. The limits themselves come from the shared
    calculator `opentmcl.motion.pmulpdiv`.
    """
    from ...motion.pmulpdiv import PmulPdivError
    from ...motion.pmulpdiv import a_max_limits as limits

    _div("RAMP_DIV", ramp_div)
    _div("PULSE_DIV", pulse_div)
    try:
        lower, upper = limits(ramp_div, pulse_div)
    except PmulPdivError as exc:
        raise UnitError(str(exc)) from None
    if v_max is not None and v_max <= 2048 / math.sqrt(2):
        lower = max(1, lower // 2)
    return lower, min(upper, A_LIMIT)
