"""The mechanics around one axis, as data (docs/world.md): switches on a stage,
load torque, and time signals for inputs.

Positions are physical microsteps of the stage (the position counter's unit
while no step is lost). A linear stage has a left and a right limit switch
and a home switch; a circular stage has one home switch and wraps every
`steps_per_turn` microsteps. Everything here is pure data with closed forms:
the firmware world asks "which state at position p" and "at which positions
can the state change next", never steps through positions.
"""
from __future__ import annotations

import bisect
import math
from dataclasses import dataclass, field

FAR = 1 << 40
"""Stands for 'no end' of a limit switch's active region (beyond any 32-bit position)."""


@dataclass(frozen=True)
class Switch:
    """A cam switch active on [lo, hi] (inclusive). With `hysteresis` h an active
    switch only releases outside [lo - h, hi + h] (docs/world.md)."""

    lo: int
    hi: int
    hysteresis: int = 0
    inverted: bool = False     # normally closed: the input reads 0 while the switch is actuated

    @property
    def centre(self) -> float:
        return (self.lo + self.hi) / 2

    def active(self, p: int, was: bool = False) -> bool:
        h = self.hysteresis if was else 0
        return self.lo - h <= p <= self.hi + h

    def edges(self, was: bool) -> tuple[int, ...]:
        """Positions whose reaching changes the state, given the present state."""
        if was:
            h = self.hysteresis
            out = (self.lo - h - 1, self.hi + h + 1)
        else:
            out = (self.lo, self.hi)
        return tuple(x for x in out if -FAR < x < FAR)


def left_switch(position: int, width: int | None = None, hysteresis: int = 0, inverted: bool = False) -> Switch:
    """Left limit switch: switching point `position`, active from there leftwards (`width` microsteps)."""
    return Switch(-FAR if width is None else position - width, position, hysteresis, inverted)


def right_switch(position: int, width: int | None = None, hysteresis: int = 0, inverted: bool = False) -> Switch:
    """Right limit switch: switching point `position`, active from there rightwards."""
    return Switch(position, FAR if width is None else position + width, hysteresis, inverted)


def home_switch(position: int, width: int, hysteresis: int = 0, inverted: bool = False) -> Switch:
    """Home switch centred on `position`: active on [position - width//2, position + width//2]."""
    return Switch(position - width // 2, position + width // 2, hysteresis, inverted)


@dataclass
class Stage:
    """Geometry of one axis. `steps_per_turn` set: circular axis (home switch only)."""

    left: Switch | None = None
    right: Switch | None = None
    home: Switch | None = None
    steps_per_turn: int | None = None
    start: int = 0          # physical position at first power-up (position counter 0)
    ends: tuple[int | None, int | None] = (None, None)   # mechanical hard stops
    _switches: tuple[Switch | None, Switch | None, Switch | None, dict[str, Switch]] | None = \
        field(default=None, init=False, repr=False, compare=False)   # `switches`, kept

    def active(self, sw: Switch, p: int, was: bool) -> bool:
        """State of `sw` at position `p` (a circular axis repeats every turn)."""
        n = self.steps_per_turn
        if n is None:
            return sw.active(p, was)
        q = p % n
        return sw.active(q, was) or sw.active(q - n, was) or sw.active(q + n, was)

    def switches(self) -> dict[str, Switch]:
        """The switches the stage has, by name (left, right, home); do not change the dict. Kept
        while the three fields stay the same objects (asked at every check)."""
        left, right, home = self.left, self.right, self.home
        kept = self._switches
        if kept is None or kept[0] is not left or kept[1] is not right or kept[2] is not home:
            found = {n: s for n, s in (("left", left), ("right", right), ("home", home)) if s}
            kept = self._switches = (left, right, home, found)
        return kept[3]

    def local(self, p: int) -> int:
        """Position on the stage (modulo one turn on a circular axis)."""
        return p if self.steps_per_turn is None else p % self.steps_per_turn

    def edge_candidates(self, p: int, sw: Switch, was: bool) -> list[int]:
        """Absolute positions (in the frame of `p`) where `sw` can change state next."""
        out = []
        n = self.steps_per_turn
        for e in sw.edges(was):
            if n is not None:
                base = p - p % n + e % n
                out += [base - n, base, base + n]
            else:
                out.append(e)
        return [x for x in out if x != p]


class Profile:
    """A number as a function of position or time, piecewise constant or piecewise linear.

    `points` is a sorted list of (x, value). kind "steps": value of the last point
    with x <= at (`before` ahead of the first); kind "ramp": linear interpolation,
    held constant outside the points.
    """

    def __init__(self, points: list[tuple[float, float]], kind: str = "steps", before: float = 0.0):
        if kind not in ("steps", "ramp"):
            raise ValueError(f"unknown profile kind {kind!r}")
        self.points = sorted((float(x), float(v)) for x, v in points)
        self.kind = kind
        self.before = float(before)
        self._xs = [x for x, _ in self.points]

    @classmethod
    def constant(cls, value: float) -> Profile:
        return cls([], "steps", value)

    @property
    def is_constant(self) -> bool:
        return not self.points

    def at(self, x: float) -> float:
        pts = self.points
        if not pts:
            return self.before
        i = bisect.bisect_right(self._xs, x)
        if self.kind == "steps" or i == 0 or i == len(pts):
            if i == 0:
                return self.before if self.kind == "steps" else pts[0][1]
            return pts[i - 1][1]
        (x0, v0), (x1, v1) = pts[i - 1], pts[i]
        return v0 + (v1 - v0) * (x - x0) / (x1 - x0) if x1 != x0 else v1

    def breakpoints(self) -> list[float]:
        return list(self._xs)

    def next_crossing(self, x: float, level: int) -> float | None:
        """Smallest x' > x at which `round(at(x')) >= level` differs from its truth at x: when a
        reading that only tells "at least `level`" (a digital input, a threshold) changes."""
        above = round(self.at(x)) >= level
        if self.kind == "steps":
            for bx in self._xs:
                if bx > x and (round(self.at(bx)) >= level) != above:
                    return bx
            return None
        edge = level - 0.5
        for i in range(1, len(self.points)):
            (x0, v0), (x1, v1) = self.points[i - 1], self.points[i]
            if x1 <= x or v1 == v0 or (v1 > v0) == above:
                continue  # before x, flat, or moving away from the edge
            t = x0 + (edge - v0) * (x1 - x0) / (v1 - v0)
            if t > x1:
                continue
            lo = max(x, x0)
            return t if t > lo else math.nextafter(lo, math.inf)  # at the edge (round() ties): just after
        return None

    def next_integer_change(self, x: float) -> float | None:
        """Smallest x' > x at which round(at(x')) differs from round(at(x)) (inputs)."""
        now = round(self.at(x))
        if self.kind == "steps":
            for bx in self._xs:
                if bx > x and round(self.at(bx)) != now:
                    return bx
            return None
        for i in range(1, len(self.points)):
            (x0, v0), (x1, v1) = self.points[i - 1], self.points[i]
            if x1 <= x or v1 == v0:
                continue
            lo = max(x, x0)
            slope = (v1 - v0) / (x1 - x0)
            target = now + (0.5 if slope > 0 else -0.5)
            t = x0 + (target - v0) / slope
            if x0 <= t <= lo < x1:  # at the half-way point (round() keeps an even n there): just after it
                return math.nextafter(lo, math.inf)
            if lo < t <= x1:
                return t
            if round(v1) != now:
                return x1
        return None


@dataclass
class Load:
    """Load torque on the axis, as a fraction of the torque the motor makes at 100 %
    current (docs/world.md). `by` is "position" (physical microsteps) or "time" (seconds)."""

    profile: Profile = field(default_factory=lambda: Profile.constant(0.0))
    by: str = "position"

    def at(self, position: int, seconds: float) -> float:
        return self.profile.at(position if self.by == "position" else seconds)


def ceil_ticks(seconds: float, clock_hz: int) -> int:
    return math.ceil(seconds * clock_hz - 1e-9)
