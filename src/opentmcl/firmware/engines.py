"""Which ramp engine drives an axis of each module family, and which axis
parameters configure it (keyword names = profile parameter names)."""
from __future__ import annotations

from ..motion import RampEngine

ENGINE_PARAMS: dict[str, dict[int, str]] = {
    # TMCM-6212 manual 4.1: AP4, AP5, AP15-AP21 (six-point ramp of the TMC5130)
    "sixpoint": {4: "max_positioning_speed", 5: "max_acceleration", 15: "acceleration_a1", 16: "velocity_v1",
                 17: "max_deceleration", 18: "deceleration_d1", 19: "velocity_vstart", 20: "velocity_vstop",
                 21: "ramp_wait_time"},
    # PD28-1021: linear ramp in pps (AP4, AP5, AP130)
    "linear": {4: "max_positioning_speed", 5: "max_acceleration", 130: "minimum_speed"},
    # PD86-1180 manual 5: TMC429 parameters in internal units
    "tmc429": {4: "max_positioning_speed", 5: "max_acceleration", 130: "minimum_speed", 138: "ramp_mode",
               153: "ramp_divisor", 154: "pulse_divisor"},
}


def make_engine(kind: str) -> RampEngine:
    if kind == "sixpoint":
        from ..motion.sixpoint import SixPointRampEngine
        return SixPointRampEngine()
    if kind == "linear":
        from ..motion.linear import LinearRampEngine
        return LinearRampEngine()
    if kind == "tmc429":
        from ..motion.tmc429_engine import Tmc429Engine
        return Tmc429Engine()
    raise ValueError(f"unknown motion engine {kind!r}")
