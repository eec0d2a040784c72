"""Ramp generators and the physical world of an axis."""
from .base import CLOCK_HZ, Mode, RampEngine

__all__ = ["CLOCK_HZ", "Mode", "RampEngine"]
