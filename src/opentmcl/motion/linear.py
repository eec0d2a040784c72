"""Linear ramp in pps (PD28-1021 / TMCM-1021).

The PD28-1021 manual (chapter 2.3, "Most important axis parameters") gives
AP4 "Maximum positioning speed" and AP5 "Maximum acceleration" in pps and
pps^2; its parameter tables are cut off, so AP130 "Minimum speed" follows the
TMCM-1180 manual 4 ("Should always be set 1 to ensure exact reaching of the
target position"), here in pps. The ramp is the six-point engine reduced to
one band: start at the minimum speed, accelerate with AP5 up to AP4,
decelerate with AP5 down to the minimum speed, stop on the target. Velocity
mode ramps with AP5 ("Acceleration and deceleration value in velocity mode").
No ramp wait time.
"""
from __future__ import annotations

from fractions import Fraction

from .sixpoint import Ramp, SixPointRampEngine


class LinearRampEngine(SixPointRampEngine):
    """Trapezoidal ramp of the PD28-1021 axis.

    Keyword parameters: max_positioning_speed (AP4, pps), max_acceleration
    (AP5, pps^2), minimum_speed (AP130, pps). Defaults are the PD28-1021
    profile defaults.
    """

    PARAMS: dict[str, int] = {
        "max_positioning_speed": 51200,
        "max_acceleration": 51200,
        "minimum_speed": 1,
    }

    def _make_ramp(self, p: dict[str, Fraction]) -> Ramp:
        vmin = p["minimum_speed"]
        return Ramp.from_pps(vmax=p["max_positioning_speed"], amax=p["max_acceleration"],
                             dmax=p["max_acceleration"], vstart=vmin, vstop=vmin)
