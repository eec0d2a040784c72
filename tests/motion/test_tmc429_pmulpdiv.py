"""PMUL/PDIV search (TMC4210 datasheet 6.1.9.2) and the A_MAX limits (6.1.7.1.1)."""
from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from opentmcl.motion.pmulpdiv import PmulPdivError, a_max_limits, calc_pmul_pdiv, registers_for


def test_datasheet_usage_example():
    """TMC4210 datasheet 6.1.9.2.3: "EXAMPLE : pmulpdiv -a 10 -r 3 -p 3 -pr 0.05".
    p = 10 / (128 * 2^0) = 0.078125; the program's `float` p_reduction 0.05 is a hair
    above 0.05, so p_reduced * 8 * 2^8 = 151.99999... truncates to PMUL = 151 at PDIV = 8
    (the largest PDIV with 128 <= PMUL <= 255)."""
    r = calc_pmul_pdiv(10, 3, 3, 0.05)
    assert r.p_ideal == 0.078125
    assert (r.pmul, r.pdiv) == (151, 8)
    assert r.p_best == 151 / 2**11
    assert (r.a_max_lower_limit, r.a_max_upper_limit) == (1, 4095)


def test_p_formula():
    """TMC4210 datasheet 6.1.9.2: p = A_MAX / (128 * 2^(RAMP_DIV - PULSE_DIV)) and
    6.1.9.2.2: PMUL = p_reduced * 2^3 * 2^PDIV."""
    r = calc_pmul_pdiv(100, 0, 0, 0.01)
    assert r.p_ideal == 100 / 128
    assert r.pmul == int(100 / 128 * 0.99 * 8 * 2**r.pdiv) and 128 <= r.pmul <= 255
    assert (r.pmul, r.pdiv) == (198, 5)
    assert calc_pmul_pdiv(100, 5, 3, 0.0).p_ideal == 100 / 512
    assert calc_pmul_pdiv(100, 3, 5, 0.0).p_ideal == 100 / 32


@given(st.integers(1, 2047), st.integers(0, 13), st.integers(0, 13))
def test_pairs_meet_the_quality_criterion_within_the_limits(a_max, ramp_div, pulse_div):
    """TMC4210 datasheet 6.1.7.1: within the A_MAX limits a valid pair {PMUL, PDIV}
    exists, and 6.1.9.2.1: select a pair with 0.95 < q = p'/p < 1.0 (1 % reduction)."""
    r = calc_pmul_pdiv(a_max, ramp_div, pulse_div, 0.01)
    if r.within_limits:
        assert r.valid
        assert 128 <= r.pmul <= 255 and 0 <= r.pdiv <= 13
        assert 0.95 < r.q < 1.0
    if r.valid:
        assert r.p_best == r.pmul / 2 ** (3 + r.pdiv) <= r.p_reduced


def test_a_max_limits():
    """TMC4210 datasheet 6.1.7.1.1: lower = 2^(RAMP_DIV - PULSE_DIV - 1) (1 if the
    exponent is <= 0; half with V_MAX <= 2048/sqrt(2)), upper = 2^(RAMP_DIV -
    PULSE_DIV + 12) - 1 (any A_MAX up to 2047 if RAMP_DIV - PULSE_DIV + 1 >= 0)."""
    assert a_max_limits(0, 0) == (1, 4095)
    assert a_max_limits(5, 0) == (16, 2**17 - 1)
    assert a_max_limits(5, 0, v_max=1448) == (8, 2**17 - 1)
    assert a_max_limits(5, 0, v_max=1449) == (16, 2**17 - 1)
    assert a_max_limits(0, 1) == (1, 2047)
    assert a_max_limits(0, 4) == (1, 255)
    assert a_max_limits(0, 13)[1] == 0
    assert not calc_pmul_pdiv(300, 0, 4).within_limits


def test_out_of_range_p_has_no_pair_and_registers_for_clamps():
    """TMC4210 datasheet 6.1.9.2.3: the program reports -1 ("no valid pair found") when
    no PMUL fits; registers_for then writes the nearest representable p."""
    too_big = calc_pmul_pdiv(2047, 0, 13, 0.01)
    assert not too_big.valid and too_big.pmul is None
    assert registers_for(2047, 0, 13) == (255, 0)
    too_small = calc_pmul_pdiv(1, 13, 0, 0.01)
    assert not too_small.valid
    assert registers_for(1, 13, 0) == (128, 13)
    assert registers_for(0, 0, 0) == (128, 13)


@pytest.mark.parametrize("args", [(2048, 0, 0), (-1, 0, 0), (1, 14, 0), (1, 0, 14), (1.5, 0, 0),
                                  (True, 0, 0)])
def test_bad_arguments_raise(args):
    """TMC4210 datasheet 6.1.7 (A_MAX 0..2047) and 6.1.12 (divisors 0..13)."""
    with pytest.raises(PmulPdivError):
        calc_pmul_pdiv(*args)
    with pytest.raises(ValueError):
        calc_pmul_pdiv(10, 0, 0, 1.5)
