"""The ramp engine factory: `[module] engine` of a profile names the engine of its axes. Which
axis parameters configure it is profile data (the `engine` field of an axis parameter,
ModuleProfile.engine_params; docs/profiles.md)."""
from __future__ import annotations

from ..motion import RampEngine


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
