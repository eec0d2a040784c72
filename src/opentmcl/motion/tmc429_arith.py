"""Integer closed forms of the TMC429/TMC4210 ramp generator (TMC4210 datasheet ch. 6.1).

No state lives here, only the arithmetic the ramp core (`motion/tmc429.py`) plans with:

* the tick clocks: f_CLK / 32 / 2^RAMP_DIV for the ramp generator, f_CLK / 32 / 2^PULSE_DIV for the
  pulse generator (6.1.12), both counted from cycle 0;
* the velocity with 8 hidden fractional bits, moved by at most A_MAX per ramp tick (A_MAX/256 velocity
  units, 6.1.9.2): linear in the ramp tick index inside a phase (`LinearPhase`);
* the 11-bit pulse accumulator: each pulse tick adds |V_ACTUAL|, an overflow is one step (6.1.12.1),
  so the steps of a phase are a floor-sum of a linear function (`floor_sum`);
* the ramp_mode target velocity min(V_MAX, max(V_MIN, isqrt(PMUL * U >> (3 + PDIV)))) for U
  accumulator units still to go (6.1.9), and its level starts L(n) (`level_start`): the target is
  at least n exactly when U >= L(n).

docs/motion-tmc429.md derives the formulas.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from math import isqrt, sqrt

RAMP_MODE, SOFT_MODE, VELOCITY_MODE, HOLD_MODE = 0, 1, 2, 3
"""RAMP_MODE register values (6.1.10.1)."""

V_LIMIT = 2047
"""Largest |velocity| (V_MIN, V_MAX, |V_TARGET|, |V_ACTUAL|), datasheet 6.1.12.1."""
A_LIMIT = 2047
"""Largest A_MAX, datasheet 6.1.7."""
STEP_UNITS = 2048
"""Accumulator units of one step: the 11-bit pulse accumulator overflows (6.1.12.1)."""
FOREVER = 1 << 80
"""Cycles past any limit (a walk without one)."""


def sign(x: int) -> int:
    return (x > 0) - (x < 0)


def toward(v: int, target: int, step: int) -> int:
    """`v` moved by at most `step` towards `target`, never past it (6.1.9.2)."""
    if v < target:
        return min(v + step, target)
    if v > target:
        return max(v - step, target)
    return v


def ceil_div(a: int, b: int) -> int:
    return -(-a // b)


def min_opt(a: int | None, b: int | None) -> int | None:
    """The smaller of two optional cycles (None: never)."""
    if a is None:
        return b
    if b is None:
        return a
    return min(a, b)


def periods(ramp_div: int, pulse_div: int) -> tuple[int, int]:
    """(ramp tick period, pulse tick period) in f_CLK cycles (6.1.12)."""
    return 32 << ramp_div, 32 << pulse_div


# --- target velocities (6.1.9, 6.1.10.1) ---------------------------------------------------------
def ramp_speed(units: int, pmul: int, pdiv: int, v_min: int, v_max: int) -> int:
    """ramp_mode target speed for `units` accumulator units still to go: sqrt(2048 * p * D)
    within [V_MIN, V_MAX] (D = units / 2048, p = PMUL / 2^(3+PDIV))."""
    return min(v_max, max(v_min, isqrt(pmul * units >> (3 + pdiv))))


def soft_speed(d: int, pmul: int, pdiv: int, v_min: int, v_max: int) -> int:
    """soft_mode target speed p * |dx| within [V_MIN, V_MAX]."""
    return min(v_max, max(v_min, pmul * d >> (3 + pdiv)))


def level_start(n: int, pmul: int, pdiv: int) -> int:
    """L(n): the fewest units whose square-root term isqrt(PMUL * U >> (3 + PDIV)) is at least n."""
    return ceil_div(n * n << (3 + pdiv), pmul)


# --- floor sums --------------------------------------------------------------------------------
def floor_sum(n: int, m: int, a: int, b: int) -> int:
    """Sum of floor((a*i + b) / m) for i in 0..n-1 (n >= 0, m >= 1, a >= 0, b >= 0)."""
    total = 0
    while n > 0:
        if a >= m:
            total += (n - 1) * n // 2 * (a // m)
            a %= m
        if b >= m:
            total += n * (b // m)
            b %= m
        y_max = a * n + b
        if y_max < m:
            break
        n, b = divmod(y_max, m)
        m, a = a, m
    return total


def linear_floor_sum(count: int, start: int, slope: int) -> int:
    """Sum of floor((start + slope*t) / 256) for t in 0..count-1; all terms >= 0."""
    if count <= 0:
        return 0
    if slope >= 0:
        return floor_sum(count, 256, slope, start)
    last = start + slope * (count - 1)
    return floor_sum(count, 256, -slope, last)


def first_true(pred: Callable[[int], bool], lo: int, hi: int, period: int,
               guess: int | None = None) -> int | None:
    """Smallest j in lo..hi with pred(j) (pred monotone false..true), as cycle j*period. A
    `guess` near the answer is checked first and the search gallops from it."""
    if hi < lo or not pred(hi):
        return None
    if guess is not None and lo < guess < hi:
        lo, hi = _gallop(pred, lo, hi, guess)
    while lo < hi:
        mid = (lo + hi) // 2
        if pred(mid):
            hi = mid
        else:
            lo = mid + 1
    return lo * period


def _gallop(pred: Callable[[int], bool], lo: int, hi: int, guess: int) -> tuple[int, int]:
    """A narrower lo..hi around the first true j, probing guess, then 1, 2, 4 ... away."""
    step = 1
    if pred(guess):
        hi = guess
        while hi - step >= lo:
            if not pred(hi - step):
                return hi - step + 1, hi
            hi -= step
            step *= 2
        return lo, hi
    lo = guess + 1
    while lo + step - 1 < hi:
        if pred(lo + step - 1):
            return lo, lo + step - 1
        lo += step
        step *= 2
    return lo, hi


# --- a linear phase ----------------------------------------------------------------------------
@dataclass(slots=True)
class LinearPhase:
    """Closed form of the motion from cycle `t0` while the ramp target stays fixed: |v| after ramp
    tick j0 + k is w0 + delta * k (delta = +A_MAX, -A_MAX or 0), and the accumulator after pulse
    tick i is acc0 + the sum of (|v| >> 8) over the pulse ticks i0+1 .. i."""

    t0: int
    ramp_period: int
    pulse_period: int
    j0: int          # index of the last ramp tick at or before t0
    i0: int          # index of the last pulse tick at or before t0
    w0: int          # |v| at t0 (1/256 units)
    delta: int       # change of |v| per ramp tick (+a, -a or 0)
    direction: int   # sign of the velocity throughout the phase (0: no motion)
    acc0: int        # accumulator counting in `direction`, valid from pulse tick i_dir
    i_dir: int       # first pulse tick that may add to acc0 (a reversal flips acc there)

    def w(self, k: int) -> int:
        """|v| after ramp tick j0 + k (k >= 0)."""
        return self.w0 + self.delta * k

    def ramp_sum(self, k_start: int, stride: int, count: int) -> int:
        """Sum of (w(k) >> 8) for k = k_start + stride * t, t in 0..count-1."""
        return linear_floor_sum(count, self.w(k_start), self.delta * stride)

    def pulse_sum(self, i_hi: int) -> int:
        """Sum of the accumulator increments of pulse ticks i0+1 .. i_hi."""
        i_lo = self.i0 + 1
        if i_hi < i_lo:
            return 0
        if self.delta == 0:                      # constant velocity: every tick adds |v| >> 8
            return (i_hi - i_lo + 1) * (self.w0 >> 8)
        rp, pp = self.ramp_period, self.pulse_period
        if pp >= rp:
            m = pp // rp
            return self.ramp_sum(i_lo * m - self.j0, m, i_hi - i_lo + 1)
        m = rp // pp
        ja, jb = i_lo // m, i_hi // m
        if ja == jb:
            return (i_hi - i_lo + 1) * (self.w(ja - self.j0) >> 8)
        total = (ja * m + m - i_lo) * (self.w(ja - self.j0) >> 8)
        total += (i_hi - jb * m + 1) * (self.w(jb - self.j0) >> 8)
        total += m * self.ramp_sum(ja + 1 - self.j0, 1, jb - ja - 1)
        return total

    def shifted(self, shift: int) -> LinearPhase:
        """The same phase from t0 + shift (shift: a multiple of both tick periods)."""
        pp = self.pulse_period
        return LinearPhase(self.t0 + shift, self.ramp_period, pp, self.j0 + shift // self.ramp_period,
                           self.i0 + shift // pp, self.w0, self.delta, self.direction, self.acc0,
                           self.i_dir + shift // pp)

    def at(self, t: int) -> tuple[int | None, int]:
        """(accumulator total acc0 + increments, or None before i_dir; |v|) at cycle t."""
        i = t // self.pulse_period
        total = self.acc0 + self.pulse_sum(i) if i >= self.i_dir else None
        return total, self.w(t // self.ramp_period - self.j0)

    def nth_step_cycle(self, n: int, t_hi: int | None) -> int | None:
        """Cycle of the n-th step after t0 (n >= 1), if it happens by t_hi."""
        if self.direction == 0:
            return None
        need = n << 11
        if self.delta == 0:                      # constant velocity: closed form
            u = self.w0 >> 8
            if u == 0:
                return None
            i = self.i0 + ceil_div(need - self.acc0, u)
            if t_hi is not None and i * self.pulse_period > t_hi:
                return None
            return i * self.pulse_period
        if t_hi is None:
            raise AssertionError("unbounded search in a ramping phase")
        lo, hi = self.i0 + 1, t_hi // self.pulse_period
        return first_true(lambda i: self.acc0 + self.pulse_sum(i) >= need, lo, hi, self.pulse_period,
                          self._pulse_guess(need - self.acc0))

    def _pulse_guess(self, units: int) -> int | None:
        """The pulse tick where the accumulator would have added `units`, |v| taken as
        continuous from the first ramp tick on (its mean over each ramp period, less the half
        unit a pulse's floor loses on average); a float estimate for `first_true`."""
        c1, (u0, b) = self.smooth_start()
        alpha = self.delta / self.ramp_period
        disc = b * b + 512 * alpha * self.pulse_period * (units - u0)
        if disc < 0:
            return None
        return int((c1 + (sqrt(disc) - b) / alpha) // self.pulse_period)

    def smooth_start(self) -> tuple[int, tuple[float, float]]:
        """(first ramp tick c1 after t0, (units added before c1, mean |v| - 127.5 right after
        c1)): the start of the continuous model of `_pulse_guess`."""
        c1 = (self.j0 + 1) * self.ramp_period
        pulses = (c1 - 1) // self.pulse_period - self.i0
        return c1, (pulses * (self.w0 >> 8), self.w0 + self.delta / 2 - 127.5)

    def step_cycles(self, t_hi: int) -> list[int]:
        """Cycles of every step on cycles t0+1 .. t_hi, in order."""
        if self.direction == 0:
            return []
        if self.delta == 0:
            return self._steady_steps(t_hi)
        out = []
        k = 1
        while (t := self.nth_step_cycle(k, t_hi)) is not None:
            out.append(t)
            k += 1
        return out

    def _steady_steps(self, t_hi: int) -> list[int]:
        """`step_cycles` at constant velocity: one step every 2048 units, |v| >> 8 per pulse tick."""
        u = self.w0 >> 8
        if u == 0:
            return []
        pp, need = self.pulse_period, STEP_UNITS - self.acc0
        i, last = self.i0 + ceil_div(need, u), t_hi // pp
        out = []
        made = self.acc0 + (i - self.i0) * u
        while i <= last:
            out.append(i * pp)
            made -= STEP_UNITS
            gap = ceil_div(STEP_UNITS - made, u)
            i += gap
            made += gap * u
        return out
