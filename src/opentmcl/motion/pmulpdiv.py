"""PMUL/PDIV for a given A_MAX, RAMP_DIV and PULSE_DIV (TMC4210 datasheet 6.1.9.2),
and the A_MAX limits of 6.1.7.1.1.

The proportionality factor the ramp generator needs is (6.1.9.2)

    p = A_MAX / (128 * 2^(RAMP_DIV - PULSE_DIV))

represented as p' = PMUL / 2^(3 + PDIV) with PMUL in 128..255, PDIV in 0..13.
6.1.9.2.2 reduces p by p_reduction (about 1 %) against overshooting, computes
PMUL = int(p_reduced * 8 * 2^PDIV) for every PDIV and keeps the valid pair with
the largest PDIV (finest mantissa), as the datasheet's example program does.
Its p_reduction is a C `float`; `calc_pmul_pdiv` rounds it to single precision
the same way so that the pairs agree with the datasheet's program bit for bit.
"""
from __future__ import annotations

import struct
from dataclasses import dataclass

PMUL_MIN, PMUL_MAX = 128, 255
PDIV_MAX = 13
DIV_MAX = 13
A_MAX_MAX = 2047
DEFAULT_P_REDUCTION = 0.01
"""6.1.9.2 hints: "PMUL should be made approximately 1% smaller than calculated"."""


class PmulPdivError(ValueError):
    """An argument outside the datasheet's ranges."""


@dataclass(frozen=True)
class PmulPdiv:
    """Result of the 6.1.9.2.2 search.

    pmul/pdiv are None when no pair in the registers' ranges represents p
    (A_MAX outside the 6.1.7.1.1 limits, or A_MAX = 0).
    """

    a_max: int
    ramp_div: int
    pulse_div: int
    p_reduction: float
    pmul: int | None
    pdiv: int | None
    p_ideal: float
    p_reduced: float
    p_best: float | None
    a_max_lower_limit: int
    a_max_upper_limit: int

    @property
    def valid(self) -> bool:
        return self.pmul is not None

    @property
    def q(self) -> float | None:
        """Quality criterion q = p' / p of 6.1.9.2.1 (0.95 < q < 1.0 is good)."""
        if self.p_best is None or self.p_ideal == 0:
            return None
        return self.p_best / self.p_ideal

    @property
    def within_limits(self) -> bool:
        """6.1.7.1.1: A_MAX_LOWER_LIMIT <= A_MAX <= A_MAX_UPPER_LIMIT (or A_MAX = 0)."""
        return self.a_max == 0 or self.a_max_lower_limit <= self.a_max <= self.a_max_upper_limit


def _single(x: float) -> float:
    return struct.unpack("<f", struct.pack("<f", x))[0]


def _check(name: str, value: int, hi: int) -> None:
    if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= hi:
        raise PmulPdivError(f"{name} must be an integer 0..{hi}, got {value!r}")


def a_max_limits(ramp_div: int, pulse_div: int, v_max: int = 2047) -> tuple[int, int]:
    """(lower, upper) A_MAX limits of 6.1.7.1.1 for ramp_mode/soft_mode deceleration.

    lower = 2^(RAMP_DIV - PULSE_DIV - 1), 1 when that exponent is <= 0, halved when
    V_MAX <= 2048/sqrt(2) (~1448); upper = 2^(RAMP_DIV - PULSE_DIV + 12) - 1 (0 when
    the exponent is negative: no A_MAX > 0 fits).
    """
    _check("ramp_div", ramp_div, DIV_MAX)
    _check("pulse_div", pulse_div, DIV_MAX)
    _check("v_max", v_max, 2047)
    e = ramp_div - pulse_div
    lower = 2 ** (e - 1) if e - 1 > 0 else 1
    if v_max <= 1448:
        lower = max(1, lower // 2)
    upper = 2 ** (e + 12) - 1 if e + 12 >= 0 else 0
    return lower, upper


def calc_pmul_pdiv(a_max: int, ramp_div: int, pulse_div: int,
                   p_reduction: float = DEFAULT_P_REDUCTION) -> PmulPdiv:
    """PMUL and PDIV for A_MAX (datasheet 6.1.9.2.2/6.1.9.2.3).

    `p_reduction` is a fraction (0.01 = 1 %), 0 <= p_reduction < 1.
    """
    _check("a_max", a_max, A_MAX_MAX)
    _check("ramp_div", ramp_div, DIV_MAX)
    _check("pulse_div", pulse_div, DIV_MAX)
    if isinstance(p_reduction, bool) or not isinstance(p_reduction, (int, float)) \
            or not 0 <= p_reduction < 1:
        raise PmulPdivError(f"p_reduction must be a fraction 0 <= p < 1, got {p_reduction!r}")
    p_ideal = a_max / (2.0 ** (ramp_div - pulse_div) * 128.0)
    p_reduced = p_ideal * (1.0 - _single(float(p_reduction)))
    best: tuple[int, int] | None = None       # (PMUL, PDIV), the last PDIV that fits
    for pdiv in range(PDIV_MAX + 1):
        pmul = int(p_reduced * 8.0 * 2.0 ** pdiv) - 128
        if 0 <= pmul <= 127:
            best = pmul + 128, pdiv
    pm, pd = best if best is not None else (None, None)
    p_best = None if best is None else best[0] / 2.0 ** (best[1] + 3)
    lower, upper = a_max_limits(ramp_div, pulse_div)
    return PmulPdiv(a_max, ramp_div, pulse_div, float(p_reduction), pm, pd, p_ideal, p_reduced,
                    p_best, lower, upper)


def registers_for(a_max: int, ramp_div: int, pulse_div: int,
                  p_reduction: float = DEFAULT_P_REDUCTION) -> tuple[int, int]:
    """A (PMUL, PDIV) pair to write for A_MAX, even when no exact pair exists.

    Uses `calc_pmul_pdiv`; when p is out of the representable range it takes the
    nearest end (PMUL=255, PDIV=0 when p is too large; PMUL=128, PDIV=13 when p is
    too small or A_MAX = 0) — the chip then over- resp. undershoots as 6.1.7.1.1 warns.
    """
    r = calc_pmul_pdiv(a_max, ramp_div, pulse_div, p_reduction)
    if r.pmul is not None and r.pdiv is not None:
        return r.pmul, r.pdiv
    if r.p_reduced >= PMUL_MAX / 8.0:
        return PMUL_MAX, 0
    return PMUL_MIN, PDIV_MAX
