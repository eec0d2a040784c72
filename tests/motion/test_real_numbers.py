"""A real number the engines cannot take exactly is refused with the library's typed error.

TMCM-6212 firmware manual 4.1: AP4 (maximum positioning speed) and AP2 (target speed) are
numbers of pps; the library converts them exactly (Fraction). A value that registers as a
numbers.Real yet is neither rational nor a float has no exact Fraction: the caller gets
RampParameterError / UnitError (both ValueError), never a bare TypeError from fractions.
"""
from __future__ import annotations

import numbers

import pytest

from opentmcl.motion.sixpoint import RampParameterError, SixPointRampEngine
from opentmcl.motion.units import UnitError, internal_velocity_from_pps


class Measured:
    """A real number type of some measuring library: registered as numbers.Real only."""

    def __init__(self, value: float) -> None:
        self.value = value

    def __repr__(self) -> str:
        return f"Measured({self.value})"


numbers.Real.register(Measured)


def test_engine_refuses_a_real_without_exact_value():
    """Manual 4.1 AP4 "maximum positioning speed" in pps: configure() takes it exactly or not."""
    e = SixPointRampEngine()
    with pytest.raises(RampParameterError, match="max_positioning_speed"):
        e.configure(max_positioning_speed=Measured(1000.0))
    with pytest.raises(RampParameterError, match="velocity"):
        e.rotate(Measured(1000.0))
    e.configure(max_positioning_speed=1000.5)      # a float is exact: accepted
    assert e.target_velocity == 0


def test_unit_conversion_refuses_a_real_without_exact_value():
    """Manual 4.1 AP255 = 0 (TMC5130 units): velocities converted from pps exactly or refused."""
    with pytest.raises(UnitError, match="velocity"):
        internal_velocity_from_pps(Measured(1000.0))
    assert internal_velocity_from_pps(0.0) == 0
