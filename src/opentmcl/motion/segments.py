"""Analytic motion segments (docs/architecture.md "Time", the Klipper `trapq` idea).

A `Segment` is one constant-acceleration piece of an axis's motion between
two whole ticks of the 16 MHz clock, in exact integer units:

    velocity      V  in 1/DEN microsteps per tick
    acceleration  A  in 1/DEN microsteps per tick^2
    position      P  in 1/(2*DEN) microsteps  (= PSCALE)

    P(k) = P0 + 2*V0*(k - k0) + A*(k - k0)^2        for k0 <= k < k1
    V(k) = V0 + A*(k - k0)

DEN = 2^41 * 5^12 is the least common multiple of the TMC5130's internal
units (v/2^24 microsteps per tick, a/2^41 microsteps per tick^2) and of pps
and pps^2 (1/f_CLK and 1/f_CLK^2 with f_CLK = 2^10 * 5^6 Hz): every pps or
internal-unit value is an exact integer here, so positions are exact and
evaluating one costs a few integer operations (no rounding, no Fractions).

The integer step counter (the chip's XACTUAL) is the last whole microstep
passed: floor while moving forwards, ceil while moving backwards. Planners
start every run on a whole microstep (`snap`), so the counter never jumps
backwards.

`SegmentQueue` is the per-axis queue: `at(k)` finds the piece holding tick k,
`drop_before(k)` forgets the past, `first_tick_at(y, start)` answers "when
does the step counter first reach y" in closed form -- the building block of
switch-edge searches (a switch at position y triggers at that tick).
"""
from __future__ import annotations

import math
from collections.abc import Callable
from fractions import Fraction
from typing import NamedTuple

from .base import CLOCK_HZ

DEN = 2**41 * 5**12
"""Velocity / acceleration unit: 1/DEN microsteps per tick (per tick^2)."""
PSCALE = 2 * DEN
"""Position unit: 1/PSCALE microsteps."""
V_PER_PPS = Fraction(DEN, CLOCK_HZ)
"""Velocity units per pps."""
A_PER_PPS2 = Fraction(DEN, CLOCK_HZ * CLOCK_HZ)
"""Acceleration units per pps^2."""

_SEARCH_CAP = 1 << 90


def sign(x: int) -> int:
    return (x > 0) - (x < 0)


def ceil_div(a: int, b: int) -> int:
    """ceil(a / b) for integers, b > 0."""
    return -((-a) // b)


def first_integer(pred: Callable[[int], bool], lo: int, hi: int | None, guess: float | None = None) -> int | None:
    """Smallest integer k in [lo, hi) with pred(k) true, for a monotone predicate
    (false ... false true ... true); None if there is none. `hi` None means
    unbounded. `guess` (a float estimate) makes the search gallop out from it,
    so a good guess costs a handful of exact evaluations.
    """
    if hi is not None and lo >= hi:
        return None
    top = (hi - 1) if hi is not None else lo + _SEARCH_CAP
    g = lo if guess is None or not math.isfinite(guess) else min(max(int(guess), lo), top)
    if pred(g):
        true_at, step = g, 1
        while True:
            c = true_at - step
            if c <= lo:
                if pred(lo):
                    return lo
                false_at = lo
                break
            if pred(c):
                true_at, step = c, step * 2
            else:
                false_at = c
                break
    else:
        false_at, step = g, 1
        while True:
            c = false_at + step
            if c >= top:
                if top <= false_at or not pred(top):
                    return None
                true_at = top
                break
            if pred(c):
                true_at = c
                break
            false_at, step = c, step * 2
    while true_at - false_at > 1:  # pred(false_at) is false, pred(true_at) is true
        mid = (true_at + false_at) // 2
        if pred(mid):
            true_at = mid
        else:
            false_at = mid
    return true_at


def quadratic_guess(c0: float, c1: float, c2: float) -> float:
    """Smallest x >= 0 with c0 + c1*x + c2*x^2 = 0 (float estimate; 0 if none)."""
    if c2 == 0:
        return -c0 / c1 if c1 else 0.0
    disc = c1 * c1 - 4 * c2 * c0
    if disc < 0:
        return max(-c1 / (2 * c2), 0.0)
    r = math.sqrt(disc)
    x1, x2 = (-c1 - r) / (2 * c2), (-c1 + r) / (2 * c2)
    if x1 >= 0:  # the smaller root that is >= 0 (NaNs compare false and are skipped)
        return x2 if 0 <= x2 < x1 else x1
    return x2 if x2 >= 0 else 0.0


def snap(p: int, direction: int) -> int:
    """Whole microstep (in P units) at which a run in `direction` ending at p rests."""
    q = (-((-p) // PSCALE)) if direction < 0 else p // PSCALE
    return q * PSCALE


class Segment(NamedTuple):
    """One constant-acceleration piece on ticks [k0, k1) (k1 None: forever).

    `rest_since` is the tick at which the motor last came to a standstill
    before (or, for a standing piece, at) this piece; None means "long ago".
    Ramp engines use it for the ramp wait time (TZEROWAIT).

    An immutable named tuple: planners build many of them per move, and a
    tuple is several times cheaper to create than a frozen dataclass.
    """

    k0: int
    k1: int | None
    p0: int
    v0: int
    a: int = 0
    rest_since: int | None = None

    # --- closed forms (integer units) -------------------------------------
    def p_at(self, k: int) -> int:
        dt = k - self.k0
        return self.p0 + (2 * self.v0 + self.a * dt) * dt

    def v_at(self, k: int) -> int:
        return self.v0 + self.a * (k - self.k0)

    # --- in microsteps ------------------------------------------------------
    def position(self, k: int) -> Fraction:
        """Exact position in microsteps at tick k."""
        return Fraction(self.p_at(k), PSCALE)

    def velocity(self, k: int) -> Fraction:
        """Exact velocity in microsteps per tick at tick k."""
        return Fraction(self.v_at(k), DEN)

    @property
    def direction(self) -> int:
        """+1 / -1 while moving forwards / backwards, 0 when standing."""
        return sign(self.v0) or sign(self.a)

    @property
    def standing(self) -> bool:
        return self.v0 == 0 and self.a == 0

    def state(self, k: int) -> tuple[int, int]:
        """(step counter, velocity) at tick k: the last whole microstep passed in the direction of
        motion, and the velocity in 1/DEN microsteps per tick. The one evaluation of a piece at a
        tick that the engines' reads use."""
        p0, v0, a = self.p0, self.v0, self.a
        if v0 == 0 and a == 0:
            return p0 // PSCALE, 0
        dt = k - self.k0
        p = p0 + (2 * v0 + a * dt) * dt
        backwards = v0 < 0 if v0 else a < 0
        return (-((-p) // PSCALE) if backwards else p // PSCALE), v0 + a * dt

    def step(self, k: int) -> int:
        """The integer step counter at tick k (last whole microstep passed)."""
        return self.state(k)[0]

    def shifted(self, steps: int) -> Segment:
        """The same motion relabelled by `steps` microsteps (AP1 overwrite)."""
        return self._replace(p0=self.p0 + steps * PSCALE)

    # --- searches ---------------------------------------------------------
    def first_tick_at(self, y: int, start: int) -> int | None:
        """First tick k in [max(start, k0), k1) at which the step counter has
        reached or passed microstep `y` in the direction of motion; None if
        not within this piece."""
        lo = max(start, self.k0)
        hi = self.k1
        if hi is not None and lo >= hi:
            return None
        d = self.direction
        py = y * PSCALE
        if d == 0:
            return lo if self.p0 == py else None
        if hi is None and self.a != 0:
            return None  # planners only leave standing or cruising pieces endless
        if d > 0:
            def pred(k: int) -> bool:
                return self.p_at(k) >= py
        else:
            def pred(k: int) -> bool:
                return self.p_at(k) <= py
        guess = self.k0 + quadratic_guess(float(self.p0 - py), 2.0 * self.v0, float(self.a))
        return first_integer(pred, lo, hi, guess)


class SegmentQueue:
    """The planned motion of one axis from `now` on (the last piece is endless)."""

    __slots__ = ("pieces",)

    def __init__(self, pieces: list[Segment]):
        if not pieces or pieces[-1].k1 is not None:
            raise ValueError("a plan must end with an endless segment")
        self.pieces = pieces

    def at(self, k: int) -> Segment:
        s = self.pieces[0]  # after drop_before(now) the first piece holds now
        k1 = s.k1
        if k1 is None or k < k1:
            return s
        for s in self.pieces:
            if s.k1 is None or k < s.k1:
                return s
        raise AssertionError("unreachable: last piece is endless")

    def drop_before(self, k: int) -> None:
        """Forget every piece that ended at or before tick k."""
        pieces = self.pieces
        i = 0
        while (k1 := pieces[i].k1) is not None and k1 <= k:
            i += 1
        if i:
            del pieces[:i]

    def next_boundary(self, k: int) -> int | None:
        for s in self.pieces:
            if s.k1 is not None and s.k1 > k:
                return s.k1
        return None

    def shift(self, steps: int) -> None:
        self.pieces = [s.shifted(steps) for s in self.pieces]

    def first_tick_at(self, y: int, start: int, modulus: int | None = None) -> int | None:
        """First tick >= start at which the step counter reaches or passes `y`.
        With `modulus` (2**32 for a wrapped counter) any y' = y (mod modulus)
        counts: the nearest one in the direction of motion."""
        for s in self.pieces:
            if s.k1 is not None and s.k1 <= start:
                continue
            k0 = max(start, s.k0)
            here = s.step(k0)
            d = s.direction
            if modulus is not None:
                if (here - y) % modulus == 0:
                    return k0
                if d == 0:
                    continue
                target = here + d * ((d * (y - here)) % modulus)
            else:
                if here == y:
                    return k0
                if d == 0 or d * (y - here) < 0:
                    continue
                target = y
            k = s.first_tick_at(target, k0)
            if k is not None:
                return k
        return None
