"""The six-point planner loops end or fail fast (issue 12: no hang when an invariant breaks).

TMCM-6212 firmware manual 4.1: AP15 A1 is the "First acceleration between VSTART and V1", AP16 V1
the "First acceleration / deceleration phase target velocity", AP17 DMAX is "Used to decelerate
from maximum positioning speed (axis parameter 4) to velocity V1", AP18 D1 the "Deceleration
between V1 and VSTOP". Each round of a planner loop therefore moves the speed into the next of at most three bands
(below V1, V1..VMAX, above VMAX) or holds it until the braking curve. The helpers below are
broken on purpose so that a round changes nothing: the planner must raise PlanInvariantError
naming the loop, within the test's timeout, instead of looping forever.
"""
from __future__ import annotations

import pytest

from opentmcl.motion import sixpoint_plan
from opentmcl.motion.segments import PSCALE
from opentmcl.motion.sixpoint import PlanInvariantError, Ramp, plan_position

RAMP = Ramp.from_pps(vmax=51200, amax=51200, dmax=51200, vstop=10)


def stuck_band(self: Ramp, u: int, floor: int) -> tuple[int, int]:
    """A deceleration band whose low end is the speed itself."""
    return self.dmax, u


@pytest.mark.timeout(20)
def test_stop_then_fails_fast_when_a_band_does_not_lower_the_speed(monkeypatch):
    """Manual 4.1 AP17/AP18: DMAX decelerates "to velocity V1", D1 "between V1 and VSTOP" —
    stopping for a target behind the motor walks the bands down to VSTOP; a band that keeps the
    speed is a bug."""
    monkeypatch.setattr(Ramp, "decel_band", stuck_band)
    v = RAMP.vmax
    with pytest.raises(PlanInvariantError, match="_stop_then"):
        plan_position(RAMP, 0, 1000 * PSCALE, v, None, 0)


@pytest.mark.timeout(20)
def test_drive_fails_fast_when_a_band_does_not_raise_the_speed(monkeypatch):
    """Manual 4.1 AP15: A1 is the "First acceleration between VSTART and V1" (AMAX above it, up
    to AP4) — a band whose top is the present speed moves nothing."""
    r = Ramp.from_pps(vmax=51200, amax=51200, dmax=51200, vstart=100, vstop=10)
    monkeypatch.setattr(Ramp, "accel_band", lambda self, u: (self.amax, u))
    with pytest.raises(PlanInvariantError, match="_drive"):
        plan_position(r, 0, 0, 0, None, 10**6 * PSCALE)


@pytest.mark.timeout(20)
def test_final_fails_fast_when_holding_does_not_reach_the_braking_curve(monkeypatch):
    """Manual 4.1 AP18: D1 is the "Deceleration between V1 and VSTOP", the last band before the
    target; a hold ahead of the braking curve that lasts no tick never gets there."""
    monkeypatch.setattr(sixpoint_plan, "ceil_div", lambda a, b: 0)
    run = sixpoint_plan._Run(0, 0, 1, RAMP.vmax // 2, None, [])     # far ahead of the braking curve
    with pytest.raises(PlanInvariantError, match="_final"):
        sixpoint_plan._final(RAMP, run, 10**9 * PSCALE)

