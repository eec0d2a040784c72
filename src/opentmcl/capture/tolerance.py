"""What a replay may forgive, and the error for a replay that cannot start (docs/capture.md "Replay").

Tolerances only widen the ranges a captured value is compared with: the twins' runs do not
depend on them (the time tolerance widens every sampling interval, capture/twin.py).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

DEFAULT_LATENCY = 0.05
"""Seconds a command-138 event may take from the module's arrival to the wire (tolerance `latency`)."""
TOLERANCE_KEYS = ("time", "position", "velocity", "load", "timer", "latency")


class ReplayError(ValueError):
    """Replay cannot start: bad capture, module, initial state or tolerance (one line)."""


@dataclass
class Tolerance:
    """`time`: seconds added at both ends of every sampling interval; `position`, `velocity`,
    `load`, `timer`: absolute value differences (timer None = not compared: a capture does not
    start at power-up); `latency`: seconds a command-138 event may take to reach the wire."""

    time: float = 0.0
    position: float = 0
    velocity: float = 0
    load: float = 0
    timer: float | None = None
    latency: float = DEFAULT_LATENCY

    @classmethod
    def parse(cls, specs) -> Tolerance:
        """From "KEY=VALUE" strings (also comma-separated), e.g. ["position=20", "time=0.2,load=50"]."""
        out = cls()
        for spec in specs or ():
            for item in str(spec).split(","):
                key, value = _item(item)
                setattr(out, key, value)
        return out

    def of(self, klass: str | None) -> float | None:
        """The absolute tolerance of a value class (0 for flags and settings, None: not compared)."""
        if klass in ("position", "velocity", "load", "timer"):
            return getattr(self, klass)
        return 0


def _item(item: str) -> tuple[str, float]:
    """One "KEY=VALUE": the key and a finite value >= 0, else ReplayError."""
    key, sep, text = item.strip().partition("=")
    if not sep or key not in TOLERANCE_KEYS:
        raise ReplayError(f"bad tolerance {item!r}; use KEY=VALUE with KEY one of {', '.join(TOLERANCE_KEYS)}")
    try:
        value = float(text)
    except ValueError:
        raise ReplayError(f"bad tolerance value in {item!r}") from None
    if not 0 <= value < math.inf:
        raise ReplayError(f"tolerance {key} must be a finite number >= 0, got {text}")
    return key, value


def as_tolerance(tolerance: Tolerance | dict | list | None) -> Tolerance:
    """A Tolerance from itself, a {key: value} dict or "KEY=VALUE" strings (default: None)."""
    if isinstance(tolerance, dict):
        return Tolerance.parse([f"{k}={v}" for k, v in tolerance.items()])
    if isinstance(tolerance, Tolerance):
        return tolerance
    return Tolerance.parse(tolerance)
