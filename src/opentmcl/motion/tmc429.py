"""TMC429/TMC4210 ramp generator, integer exact and event-driven.

One axis of the TMC429 (three-axis, inside the PD86-1180) / TMC4210 (one axis)
ramp generator, following the TMC4210 datasheet ch. 6.1 (see
docs/motion-tmc429.md for the model and its equations, docs/assumptions.md for
the choices where the datasheet is silent):

* f_CLK / 32 / 2^RAMP_DIV clocks the ramp generator, f_CLK / 32 / 2^PULSE_DIV
  the pulse generator (6.1.12); both divided clocks count from cycle 0 and the
  ramp generator acts first when both fire on one cycle.
* The velocity has 8 fractional bits; each ramp tick moves it by at most A_MAX
  (A_MAX/256 velocity units) towards the target velocity (6.1.9.2).
* Each pulse tick adds |V_ACTUAL| to an 11-bit accumulator; an overflow is one
  step, so R = f_CLK * |v| / (2^PULSE_DIV * 2048 * 32) (6.1.12.1). The pulse
  generator takes the signed velocity: on a reversal the fraction of a step
  already made is walked back first (acc := 2047 - acc), which lets the
  overshoot of a short move settle on the target.
* ramp_mode: on every ramp tick the target velocity is min(V_MAX, max(V_MIN,
  sqrt(2048 * p * D))), p = PMUL / 2^(3+PDIV), D the remaining distance with the
  accumulator's fraction of a step (6.1.9); the velocity follows it like
  velocity_mode follows V_TARGET. soft_mode: target velocity p * |dx|;
  velocity_mode: V_TARGET; hold_mode: the velocity is left alone (6.1.10.1). At
  the target a velocity <= V_MIN stops (6.1.3).

Time `now` counts f_CLK cycles. `advance` jumps over whole ramp phases: inside a
phase the ramp target is fixed, the velocity is linear in the ramp tick index
(or constant), the step count is a floor-sum of it, and the first cycle where
something changes (end of a ramp, the computed ramp_mode target binding,
arrival, a soft-mode target change) is found by binary search on those closed
forms. That one cycle is then applied exactly. Where the ramp_mode velocity
follows its computed target down the square-root curve (`_Follow`), runs on the
target (and the levels followed down one by one after them) and runs falling by
A_MAX inside one velocity level are jumped by arithmetic, the other ticks walked
(at most a few per velocity level). Follow stretches and the plans of
`next_event` are memoised by the state they start from, relative to `now`, so a
repeated move costs O(1) per phase (docs/motion-tmc429.md). The per-tick oracle in
tests/motion/tmc429_reference.py defines the behaviour this must reproduce.
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from math import isqrt

RAMP_MODE, SOFT_MODE, VELOCITY_MODE, HOLD_MODE = 0, 1, 2, 3

V_LIMIT = 2047
"""Largest |velocity| (V_MIN, V_MAX, |V_TARGET|, |V_ACTUAL|), datasheet 6.1.12.1."""
A_LIMIT = 2047
"""Largest A_MAX, datasheet 6.1.7."""

_REGISTERS = ("x_target", "x_actual", "v_min", "v_max", "v_target", "v_actual", "a_max",
              "pmul", "pdiv", "pulse_div", "ramp_div", "mode")


class Tmc429RegisterError(ValueError):
    """A register name that does not exist or a value outside its range."""


def _sign(x: int) -> int:
    return (x > 0) - (x < 0)


def _toward(v: int, target: int, step: int) -> int:
    if v < target:
        return min(v + step, target)
    if v > target:
        return max(v - step, target)
    return v


def _ceil_div(a: int, b: int) -> int:
    return -(-a // b)


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


def _linear_floor_sum(count: int, start: int, slope: int) -> int:
    """Sum of floor((start + slope*t) / 256) for t in 0..count-1; all terms >= 0."""
    if count <= 0:
        return 0
    if slope >= 0:
        return floor_sum(count, 256, slope, start)
    last = start + slope * (count - 1)
    return floor_sum(count, 256, -slope, last)


@dataclass(slots=True)
class _Follow:
    """A ramp_mode stretch following the computed target (`Tmc429Ramp._follow`), from t0."""

    t0: int
    event_offset: int   # cycle to apply exactly next, relative to t0
    end_offset: int     # where the stretch ends (event_offset - 1)
    total: int          # accumulator units added
    w_end: int          # |v| at the end
    moved: bool         # a pulse tick saw a non-zero velocity


    def shifted(self, shift: int) -> _Follow:
        """The same stretch from t0 + shift."""
        return _Follow(self.t0 + shift, self.event_offset, self.end_offset, self.total,
                       self.w_end, self.moved)


_FollowKey = tuple[int, int, int, int, int, int, int, int, int, int]
_PlanKey = tuple[int, ...]
_FOLLOW_MEMO_SIZE = 4096
_FOREVER = 1 << 80
"""Cycles past any `limit` (a walk without one)."""


_Steps = list[tuple[int, int]]
"""(cycle, +1 or -1) of each step made."""


class _Walk:
    """Pulse bookkeeping of one `Tmc429Ramp._follow` stretch."""

    __slots__ = ("units", "made0", "total", "s", "pulse_period", "steps")

    def __init__(self, units: int, made0: int, s: int, pulse_period: int,
                 steps: _Steps | None) -> None:
        self.units = units            # accumulator units still to add before the arrival step
        self.made0 = made0            # accumulator counting towards the target at the start
        self.total = 0                # units added in this stretch
        self.s = s                    # direction of the target
        self.pulse_period = pulse_period
        self.steps = steps

    @property
    def left(self) -> int:
        return self.units - self.total

    def pulses(self, count: int, n: int, first: int) -> int:
        """Add `count` pulses of n units from pulse index `first`. If the arrival step
        comes among them, stop just before it and return its cycle; else 0."""
        if count <= 0 or n == 0:
            return 0
        if self.total + count * n >= self.units:
            k = _ceil_div(self.units - self.total, n)
            self._record(n, k - 1, first)
            self.total += (k - 1) * n
            return (first + k - 1) * self.pulse_period
        self._record(n, count, first)
        self.total += count * n
        return 0

    def _record(self, n: int, count: int, first: int) -> None:
        """Append (cycle, s) for each step of `count` pulses of n units from pulse index
        `first`."""
        if self.steps is None:
            return
        made = self.made0 + self.total
        m = made // 2048 + 1
        while m * 2048 <= made + count * n:
            self.steps.append(((first + _ceil_div(m * 2048 - made, n) - 1) * self.pulse_period,
                               self.s))
            m += 1


@dataclass(slots=True)
class _Phase:
    """Closed form of the motion from `t0` while the ramp target stays `vt`."""

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
        return _linear_floor_sum(count, self.w(k_start), self.delta * stride)

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

    def shifted(self, shift: int) -> _Phase:
        """The same phase from t0 + shift (shift: a multiple of both tick periods)."""
        pp = self.pulse_period
        return _Phase(self.t0 + shift, self.ramp_period, pp, self.j0 + shift // self.ramp_period,
                      self.i0 + shift // pp, self.w0, self.delta, self.direction, self.acc0,
                      self.i_dir + shift // pp)

    def nth_step_cycle(self, n: int, t_hi: int | None) -> int | None:
        """Cycle of the n-th step after t0 (n >= 1), if it happens by t_hi."""
        if self.direction == 0:
            return None
        need = n << 11
        lo = self.i0 + 1
        if self.delta == 0:                      # constant velocity: closed form
            u = self.w0 >> 8
            if u == 0:
                return None
            i = self.i0 + _ceil_div(need - self.acc0, u)
            if t_hi is not None and i * self.pulse_period > t_hi:
                return None
            return i * self.pulse_period
        if t_hi is None:
            if self.delta != 0:
                raise AssertionError("unbounded search in a ramping phase")
            u = self.w0 >> 8
            if u == 0:
                return None
            hi = self.i0 + _ceil_div(need, u) + 1
        else:
            hi = t_hi // self.pulse_period
        if hi < lo or self.acc0 + self.pulse_sum(hi) < need:
            return None
        while lo < hi:
            mid = (lo + hi) // 2
            if self.acc0 + self.pulse_sum(mid) >= need:
                hi = mid
            else:
                lo = mid + 1
        return lo * self.pulse_period


def _lag_walk(c: int, w: int, left: int, a: int, low: int, pm: int, sh: int, rp: int,
              last: int) -> tuple[int, int, int]:
    """Lagging ramp ticks from tick c on at PULSE_DIV == RAMP_DIV: |v| falls by A_MAX with
    the computed target at or below it (6.1.9). With V_MIN <= V_MAX three integer tests on
    the new level n decide such a tick without a square root: |v| - A_MAX > V_MIN * 256,
    n < `left` (no arrival), PMUL * left >> (3 + PDIV) < (n + 1)^2 (the target is at most n).
    Returns (c, |v|, left) before the first other tick or past `last`."""
    nw = w - a
    n = nw >> 8
    while nw > low and n < left and pm * left >> sh < (n + 1) * (n + 1) and c <= last:
        left -= n
        c += rp
        nw -= a
        n = nw >> 8
    return c, nw + a, left


def _on_target(c: int, n: int, left: int, rp: int, last: int, a: int, pm: int, sh: int,
               floor: int) -> tuple[int, int, int]:
    """Ramp ticks from tick c on at PULSE_DIV == RAMP_DIV with |v| = n * 256 on its computed
    target (6.1.9), `left` > n units before the arrival step: the target stays n while left
    >= level start L(n) = ceil(n^2 * 2^(3+PDIV) / PMUL) and each pulse adds n. After that,
    as long as the target falls one level at a time (to m = n - 1 > V_MIN), |v| falls by
    A_MAX: 255 // A_MAX ticks strictly between the levels, then the one that lands on m * 256,
    each adding m, and the ticks on level m follow. Stops before an arrival, V_MIN and past
    `last`: (c, n, left) with |v| = n * 256 before tick c."""
    ln = -(-(n * n << sh) // pm)
    k = min((left - ln) // n + 1, (left - 1) // n, (last - c) // rp + 1)   # >= 1
    left -= k * n
    c += k * rp
    if left >= ln or a == 0:                    # stopped before an arrival or past `last`
        return c, n, left
    r = 255 // a
    fall = r * rp
    while n - 1 > floor:
        m = n - 1
        lm = -(-(m * m << sh) // pm)
        snap = left - r * m                     # left before the tick that lands on m * 256
        if snap < lm or lm <= m or c + fall > last:
            break                               # (lm > m: no arrival on level m)
        left = snap - m
        c += fall + rp
        n = m
        if left >= lm:                          # ticks on the target at level m
            k = (left - lm) // m + 1
            if c + (k - 1) * rp > last:
                k = (last - c) // rp + 1
            left -= k * m
            c += k * rp
    return c, n, left


def _lag_run(c: int, w: int, left: int, a: int, rp: int, last: int, pm: int, sh: int,
             vmin: int, vmax: int) -> tuple[int, int, int]:
    """Ramp ticks from tick c on at PULSE_DIV == RAMP_DIV and 0 < A_MAX < 32 over which |v|
    (w before tick c) falls by A_MAX above its computed target (tick c does, `left` > the
    units of its pulse), level by level: inside level n (n * 256 <= |v| < n * 256 + 256) each
    pulse adds n and, as `left` only falls, the level's first tick decides that the target
    stays at most n: V_MIN <= n and (V_MAX <= n or left < L(n + 1)). Stops before an arrival,
    before |v| lands on V_MIN * 256 and past `last`: (c, |v|, left) after the ticks done."""
    low = min(vmin, vmax) << 8
    while True:
        nw = w - a
        n = nw >> 8
        base = n << 8 if n << 8 > low else low + 1   # lowest |v| of the run in this level
        ticks = (nw - base) // a + 1
        cap = (left - 1) // n if n else ticks         # pulses before the arrival one
        room = (last - c) // rp + 1
        if ticks >= cap or ticks >= room or base > n << 8:
            ticks = min(ticks, cap, room)
            return c + ticks * rp, nw - a * (ticks - 1), left - ticks * n
        left -= ticks * n
        c += ticks * rp
        w = nw - a * (ticks - 1)
        m = n - 1
        if m < vmin or (vmax > m and left >= -(-(n * n << sh) // pm)):
            return c, w, left                       # the target catches up in level m


_Plan = tuple[int | None, int | None, _Phase | _Follow]
"""(event, clamp, phase) of `Tmc429Ramp._plan`."""


class _Memo:
    """Results by the state they start from, relative to `now`, so that a repeated move costs
    O(1): follow stretches (`Tmc429Ramp._follow_plan`) and whole plans of `next_event`
    (`Tmc429Ramp._memo_plan`), at most `_FOLLOW_MEMO_SIZE` of each (emptied when full)."""

    __slots__ = ("follow", "plans")

    def __init__(self) -> None:
        self.follow: dict[_FollowKey, tuple[int, int, int, int, bool]] = {}
        self.plans: dict[_PlanKey, tuple[int, _Plan]] = {}

    def clear(self) -> None:
        self.follow.clear()
        self.plans.clear()


_FOLLOW_MEMO = _Memo()


class Tmc429Ramp:
    """One axis of the TMC429/TMC4210 ramp generator, integer exact, event-driven.

    Time `now` counts clock cycles of the chip clock (f_CLK), from 0.
    Registers are read as attributes and written with `set()`.
    """

    def __init__(self, *, position_bits: int = 24) -> None:
        if not 2 <= position_bits <= 64:
            raise Tmc429RegisterError(f"position_bits {position_bits} out of range 2..64")
        self.position_bits = position_bits
        self._modulus = 1 << position_bits
        self._half = 1 << (position_bits - 1)
        self.now = 0
        self._x = 0
        self._xt = 0
        self._v = 0              # signed velocity, 8 fractional bits
        self._acc = 0            # pulse accumulator
        self._acc_dir = 0        # direction _acc counts in (0: no motion since power-on)
        self._stopping = False   # soft switch stop in progress
        self._v_min = 0
        self._v_max = 0
        self._v_target = 0
        self._a_max = 0
        self._pmul = 128         # 6.1.9.1: the MSB of PMUL is fixed at 1
        self._pdiv = 0
        self._pulse_div = 0
        self._ramp_div = 0
        self._mode = RAMP_MODE
        self._cached_plan: _Plan | None = None   # _plan(None) of the state at its phase's t0
        self._plan_base: tuple[_Phase, int, int, int, int] | None = None
        """(phase, x, acc, acc_dir, v) at the t0 of a cached linear phase `_jump_within` moved in."""

    # ------------------------------------------------------------------ registers
    @property
    def x_target(self) -> int:
        """X_TARGET, unsigned `position_bits` wide (6.1.1)."""
        return self._xt

    @property
    def x_actual(self) -> int:
        """X_ACTUAL, unsigned `position_bits` wide (6.1.2)."""
        return self._x

    @property
    def v_min(self) -> int:
        return self._v_min

    @property
    def v_max(self) -> int:
        return self._v_max

    @property
    def v_target(self) -> int:
        """V_TARGET (6.1.5): the written value in velocity_mode and hold_mode, the
        chip-computed target velocity in ramp_mode and soft_mode."""
        if self._mode in (VELOCITY_MODE, HOLD_MODE):
            return self._v_target
        dx = self.dx
        if dx == 0:
            return 0
        s, d = _sign(dx), abs(dx)
        if self._mode == RAMP_MODE:
            return s * self._speed(self._remaining(s, d))
        return s * self._soft_speed(d)

    @property
    def v_actual(self) -> int:
        """V_ACTUAL (6.1.6): the 11 integer bits of the velocity with its sign."""
        return _sign(self._v) * (abs(self._v) >> 8)

    @property
    def v_internal(self) -> int:
        """The velocity with its 8 hidden fractional bits (V_ACTUAL * 256 + fraction)."""
        return self._v

    @property
    def a_max(self) -> int:
        return self._a_max

    @property
    def a_actual(self) -> int:
        """A_ACTUAL (6.1.8), unsmoothed and signed (2.4): +A_MAX while the next ramp
        tick raises |velocity|, -A_MAX while it lowers it, else 0."""
        if self._mode == HOLD_MODE or self._a_max == 0:
            return 0
        probe = self.copy()
        probe._ramp_tick()
        change = abs(probe._v) - abs(self._v)
        return _sign(change) * self._a_max

    @property
    def pmul(self) -> int:
        return self._pmul

    @property
    def pdiv(self) -> int:
        return self._pdiv

    @property
    def pulse_div(self) -> int:
        return self._pulse_div

    @property
    def ramp_div(self) -> int:
        return self._ramp_div

    @property
    def mode(self) -> int:
        return self._mode

    @property
    def dx(self) -> int:
        """X_TARGET - X_ACTUAL as a signed `position_bits` number (6.1.1: |dx| < 2^23)."""
        return (self._xt - self._x + self._half) % self._modulus - self._half

    @property
    def stopping(self) -> bool:
        """A soft switch stop (`stop(soft=True)`) is in progress."""
        return self._stopping

    @property
    def position_reached(self) -> bool:
        """X_ACTUAL == X_TARGET in ramp_mode or soft_mode with the motor stopped."""
        return self._mode in (RAMP_MODE, SOFT_MODE) and self._x == self._xt and self._v == 0

    def set(self, **regs: int) -> None:
        """Write registers at `now` (6.1); the motion re-plans from the present state.

        x_target/x_actual take any integer (kept modulo 2^position_bits);
        v_actual is writable in hold_mode only (the hidden fraction is cleared,
        6.1.6) and ignored otherwise; v_target is stored in any mode but used
        by velocity_mode only; pmul gets its MSB forced to 1 (6.1.9.1).
        Raises Tmc429RegisterError for unknown names or out-of-range values;
        nothing is written then.
        """
        checked = {name: self._check(name, value) for name, value in regs.items()}
        self._cached_plan = None
        for name, value in checked.items():
            if name in ("x_target", "x_actual"):
                value %= self._modulus
                if name == "x_target":
                    self._xt = value
                    self._stopping = False
                else:
                    self._x = value
            elif name == "v_actual":
                if self._mode == HOLD_MODE:
                    self._v = value * 256
                    self._stopping = False
            elif name == "v_target":
                self._v_target = value
                self._stopping = False
            elif name == "mode":
                self._mode = value
                self._stopping = False
            elif name == "pmul":
                self._pmul = value | 0x80
            else:
                setattr(self, "_" + name, value)

    def _check(self, name: str, value: int) -> int:
        if name not in _REGISTERS:
            raise Tmc429RegisterError(f"unknown TMC429 register {name!r}")
        if isinstance(value, bool) or not isinstance(value, int):
            raise Tmc429RegisterError(f"{name} must be an integer, not {value!r}")
        if name in ("x_target", "x_actual"):
            lo, hi = -self._half, self._modulus - 1
        elif name in ("v_target", "v_actual"):
            lo, hi = -V_LIMIT, V_LIMIT
        elif name in ("v_min", "v_max"):
            lo, hi = 0, V_LIMIT
        elif name == "a_max":
            lo, hi = 0, A_LIMIT
        elif name == "pmul":
            lo, hi = 0, 255
        elif name in ("pdiv", "pulse_div", "ramp_div"):
            lo, hi = 0, 15
        else:
            lo, hi = 0, 3
        if not lo <= value <= hi:
            raise Tmc429RegisterError(f"{name}={value} out of range {lo}..{hi}")
        return value

    # ------------------------------------------------------------------ stops
    def stop(self, *, soft: bool) -> None:
        """Switch stop (6.1.10.2): hard sets V_ACTUAL to 0 at once; soft decelerates
        with A_MAX to 0. At standstill X_TARGET := X_ACTUAL (ramp/soft_mode) or
        V_TARGET := 0 (velocity_mode), so the motor stays. hold_mode stops hard."""
        self._cached_plan = None
        if soft and self._mode != HOLD_MODE:
            self._stopping = True
            return
        self._v = 0
        self._stopping = False
        self._after_stop()

    def _after_stop(self) -> None:
        if self._mode in (RAMP_MODE, SOFT_MODE):
            self._xt = self._x
        elif self._mode == VELOCITY_MODE:
            self._v_target = 0

    # ------------------------------------------------------------------ one cycle, exactly
    def _ramp_tick(self) -> None:
        if self._mode == HOLD_MODE:
            return
        if self._stopping:
            self._v = _toward(self._v, 0, self._a_max)
            if self._v == 0:
                self._stopping = False
                self._after_stop()
            return
        if self._mode == VELOCITY_MODE:
            self._v = _toward(self._v, self._velocity_mode_target(), self._a_max)
            return
        dx = self.dx
        if dx == 0:
            if abs(self._v) <= self._v_min * 256:
                self._v = 0
            else:
                self._v = _toward(self._v, 0, self._a_max)
            return
        s = _sign(dx)
        self._v = _toward(self._v, self._position_target(s, abs(dx)), self._a_max)

    def _pulse_tick(self) -> int:
        direction = _sign(self._v)
        if direction and direction != self._acc_dir:
            if self._acc_dir:               # reversal: walk back the fraction made
                self._acc = 2047 - self._acc
            self._acc_dir = direction
        self._acc += abs(self._v) >> 8
        if self._acc < 2048:
            return 0
        self._acc -= 2048
        self._x = (self._x + direction) % self._modulus
        if (self._mode in (RAMP_MODE, SOFT_MODE) and self._x == self._xt
                and abs(self._v) <= self._v_min * 256):
            self._v = 0
        return direction

    def _cycle(self, c: int) -> int:
        """Apply cycle c = now + 1 exactly; return the step made (-1, 0, +1)."""
        self._cached_plan = None
        if c % (32 << self._ramp_div) == 0:
            self._ramp_tick()
        step = self._pulse_tick() if c % (32 << self._pulse_div) == 0 else 0
        self.now = c
        return step

    # ------------------------------------------------------------------ targets
    def _velocity_mode_target(self) -> int:
        return _sign(self._v_target) * min(abs(self._v_target), self._v_max) * 256

    def _made(self, s: int) -> int:
        """Accumulator units of the current step made in direction s (one made the other
        way is walked back first, acc := 2047 - acc)."""
        return self._acc if self._acc_dir in (0, s) else 2047 - self._acc

    def _remaining(self, s: int, d: int) -> int:
        """Accumulator units (1/2048 step) to add before X_ACTUAL reaches a target d
        steps away in direction s (the fraction made towards it counts)."""
        return d * 2048 - self._made(s)

    def _speed(self, units: int) -> int:
        """ramp_mode target speed for `units` still to go: sqrt(2048 * p * D) within
        [V_MIN, V_MAX] (6.1.9; D = units / 2048, p = PMUL / 2^(3+PDIV))."""
        return min(self._v_max, max(self._v_min, isqrt(self._pmul * units >> (3 + self._pdiv))))

    def _level_start(self, n: int) -> int:
        """Smallest `units` whose sqrt term is at least n."""
        return _ceil_div(n * n << (3 + self._pdiv), self._pmul)

    def _soft_speed(self, d: int) -> int:
        return min(self._v_max, max(self._v_min, self._pmul * d >> (3 + self._pdiv)))

    def _position_target(self, s: int, d: int) -> int:
        if self._mode == RAMP_MODE:
            speed = self._speed(self._remaining(s, d))
        else:
            speed = self._soft_speed(d)
        return s * speed * 256

    def _ramp_target(self) -> tuple[int | None, bool]:
        """Target velocity (1/256 units) of a linear phase from now and whether the
        ramp_mode target may bind during it (then `_find_trigger` looks for the
        tick); None when dx == 0 in ramp/soft_mode."""
        v = self._v
        if self._mode == HOLD_MODE:
            return v, False
        if self._stopping:
            return 0, False
        if self._mode == VELOCITY_MODE:
            return self._velocity_mode_target(), False
        dx = self.dx
        if dx == 0:
            return None, False
        s, d = _sign(dx), abs(dx)
        if self._mode == SOFT_MODE:
            return self._position_target(s, d), False
        speed = self._speed(self._remaining(s, d))
        if v * s < 0:            # heading away: +-A_MAX per tick until the sign changes
            return s * speed * 256, False
        floor = min(self._v_min, self._v_max)
        if speed == floor and abs(v) == floor * 256:
            return s * floor * 256, False    # at V_MIN: the target cannot fall further
        return s * self._v_max * 256, True

    # ------------------------------------------------------------------ phases
    def _plan(self, until: int | None) -> _Plan:
        """Closed form of the coming phase.

        Returns (event, clamp, phase): `event` is the first cycle > now that must
        be applied exactly (None: none ever), `clamp` the cycle where the ramp
        reaches its target (reported by next_event, also exact).
        """
        target, binds = self._ramp_target()
        dx_zero = target is None
        vt = 0 if target is None else target
        phase = self._linear_phase(vt)
        units0 = 0
        if binds and phase.direction != 0:
            dx = self.dx
            units0 = self._remaining(_sign(dx), abs(dx))
            if self._fires(phase, units0, phase.j0 + 1):   # the computed target binds now
                return self._follow_plan(until)
        first_ramp, clamp = self._ramp_events(phase, vt, dx_zero)
        bound = _min_opt(until, None if first_ramp is None else first_ramp - 1)
        step_event = self._step_event(phase, dx_zero, bound)
        trig = None
        if binds and phase.direction != 0:
            bound2 = _min_opt(bound, None if step_event is None else step_event - 1)
            trig = self._find_trigger(phase, units0, bound2)
        event = _min_opt(_min_opt(first_ramp, step_event), trig)
        return event, clamp, phase

    def _linear_phase(self, vt: int) -> _Phase:
        """The phase from now in which |v| moves by A_MAX per ramp tick towards `vt`
        (or stays, in hold_mode, at A_MAX = 0 or on the target), 6.1.9.2."""
        rp, pp = 32 << self._ramp_div, 32 << self._pulse_div
        v0, a = self._v, self._a_max
        ramping = a > 0 and v0 != vt and self._mode != HOLD_MODE
        direction = _sign(v0) if v0 != 0 else (_sign(vt) if ramping else 0)
        w0 = abs(v0)
        if not ramping:
            delta = 0
        elif _sign(vt) == direction and abs(vt) > w0:
            delta = a
        else:
            delta = -a
        j0, i0 = self.now // rp, self.now // pp
        acc0, i_dir = self._acc, i0 + 1
        if direction != 0 and direction != self._acc_dir:
            if self._acc_dir:
                acc0 = 2047 - acc0
            if v0 == 0:                     # v turns non-zero at the next ramp tick
                i_dir = _ceil_div((j0 + 1) * rp, pp)
        return _Phase(self.now, rp, pp, j0, i0, w0, delta, direction, acc0, i_dir)

    def _ramp_events(self, phase: _Phase, vt: int, dx_zero: bool) -> tuple[int | None, int | None]:
        """(first ramp tick that changes the phase, clamp): the tick where |v| reaches
        `vt` or changes sign, the release of a soft stop at standstill (6.1.10.2) and the
        stop at the target once |v| <= V_MIN (6.1.3)."""
        rp, a, j0, w0 = phase.ramp_period, self._a_max, phase.j0, phase.w0
        events: list[int] = []
        clamp = None
        if phase.delta != 0:
            if _sign(vt) == phase.direction or vt == 0:
                k_end = _ceil_div(abs(abs(vt) - w0), a)       # reaches vt (or 0)
            else:
                k_end = _ceil_div(w0, a)                       # changes sign
            clamp = (j0 + k_end) * rp
            events.append(clamp)
        if self._stopping and self._mode != HOLD_MODE and w0 == 0:
            events.append((j0 + 1) * rp)                       # release at once
        if dx_zero and not self._stopping and self._mode in (RAMP_MODE, SOFT_MODE):
            limit = self._v_min * 256
            if w0 <= limit:
                if w0 != 0:
                    events.append((j0 + 1) * rp)
            elif a > 0:
                events.append((j0 + _ceil_div(w0 - limit, a) + 1) * rp)
        return (min(events) if events else None), clamp

    def _step_event(self, phase: _Phase, dx_zero: bool, bound: int | None) -> int | None:
        """Cycle of the step, by `bound`, after which the ramp target changes or the
        motor stops (`_step_limit`); None: none by then."""
        n_steps = self._step_limit(phase.direction, dx_zero)
        if n_steps is None or phase.direction == 0:
            return None
        if bound is None and phase.delta != 0:
            raise AssertionError("ramping phase without end")
        return phase.nth_step_cycle(n_steps, bound)

    def _step_limit(self, direction: int, dx_zero: bool) -> int | None:
        """Number of steps after which the ramp target may change (None: never)."""
        mode = self._mode
        if mode not in (RAMP_MODE, SOFT_MODE) or direction == 0:
            return None
        if dx_zero:
            return 1
        dx = self.dx
        s, d = _sign(dx), abs(dx)
        if self._stopping:          # only the stop at the target matters now
            return (self._xt - self._x) * direction % self._modulus or self._modulus
        if direction == s:
            limit = d                                          # arrival
            if mode == SOFT_MODE:
                speed = self._soft_speed(d)
                lo, hi = 1, d                                  # smallest d' with the same speed
                while lo < hi:
                    mid = (lo + hi) // 2
                    if self._soft_speed(mid) == speed:
                        hi = mid
                    else:
                        lo = mid + 1
                limit = min(limit, d - lo + 1)
            return limit
        # moving away: dx grows until it wraps to the other sign
        flip = self._half - d + (1 if s < 0 else 0)
        limit = flip
        if mode == SOFT_MODE:
            speed = self._soft_speed(d)
            if speed < self._v_max:
                lo, hi = d, d + flip                           # largest d' with the same speed
                while lo < hi:
                    mid = (lo + hi + 1) // 2
                    if self._soft_speed(mid) == speed:
                        lo = mid
                    else:
                        hi = mid - 1
                limit = min(limit, lo - d + 1)
        return limit

    def _fires(self, ph: _Phase, units0: int, j: int) -> bool:
        """ramp_mode: does ramp tick j of the linear phase `ph` (towards V_MAX) see a
        computed target that binds, i.e. gives another velocity than the phase?"""
        units = units0 - ph.pulse_sum((j * ph.ramp_period - 1) // ph.pulse_period)
        if units <= 0:                  # arrives before tick j: the step event comes first
            return False
        speed = self._speed(units)
        if ph.delta > 0:
            return speed * 256 < min(self._v_max * 256, ph.w(j - 1 - ph.j0) + self._a_max)
        return speed < self._v_max

    def _find_trigger(self, ph: _Phase, units0: int, t_hi: int | None) -> int | None:
        """First ramp tick (cycle) of `ph` at which the computed ramp_mode target binds
        (monotone: the remaining distance only falls, the velocity only rises)."""
        rp, pp = ph.ramp_period, ph.pulse_period
        j_lo = ph.j0 + 1
        if ph.delta == 0:
            # |v| = V_MAX * 256 held: binds once units < level_start(V_MAX)
            u = ph.w0 >> 8
            if u == 0 or self._v_max == 0:
                return None
            need = units0 - self._level_start(self._v_max) + 1
            if need <= 0:
                j = j_lo
            else:
                i = ph.i0 + _ceil_div(need, u)
                if t_hi is not None and i * pp > t_hi:
                    return None
                j = max(j_lo, i * pp // rp + 1)
            if t_hi is not None and j * rp > t_hi:
                return None
            return j * rp
        if t_hi is None:               # a ramping phase always ends at its clamp
            raise AssertionError("unbounded trigger search in a ramping phase")
        return _first_true(lambda j: self._fires(ph, units0, j), j_lo, t_hi // rp, rp)

    # ------------------------------------------------------------------ following the target
    def _follow_plan(self, until: int | None) -> tuple[int, None, _Follow]:
        """Plan of a stretch where the ramp_mode velocity follows its computed target:
        walked on a copy up to `until` (None: to its end, memoised by the start state)."""
        key = self._follow_key()
        memo = _FOLLOW_MEMO.follow
        hit = memo.get(key)
        if hit is not None:
            seg = _Follow(self.now, *hit)
            return self.now + seg.event_offset, None, seg
        probe = self.copy()
        event = probe._follow(until, None)
        hit = (event - self.now, probe.now - self.now, probe._units_made, abs(probe._v),
               probe._moved)
        if until is None or event <= until:           # the whole stretch: remember it
            if len(memo) >= _FOLLOW_MEMO_SIZE:
                memo.clear()
            memo[key] = hit
        seg = _Follow(self.now, *hit)
        return event, None, seg

    def _follow_key(self) -> _FollowKey:
        dx = self.dx
        s, d = _sign(dx), abs(dx)
        period = max(32 << self._ramp_div, 32 << self._pulse_div)
        return (self._remaining(s, d), abs(self._v), self.now % period, self._ramp_div,
                self._pulse_div, self._a_max, self._v_min, self._v_max, self._pmul, self._pdiv)

    def _follow(self, limit: int | None, steps: _Steps | None) -> int:
        """Go through ramp_mode from now while the velocity heads for the target (6.1.9), tick
        by tick but runs of one velocity or of one level falling by A_MAX in one go. Stops at
        `limit`, just before the arrival step, or after the tick that reaches V_MIN (or 0);
        returns the cycle to apply exactly next. `steps` collects (cycle, direction) of
        each step made."""
        s = _sign(self.dx)
        if self._ramp_div == self._pulse_div and steps is None:
            t, w, total, moved, event = self._follow_fast(limit)
        else:
            t, w, total, moved, event = self._follow_walk(limit, steps)
        self._units_made, self._moved = total, moved
        self._settle(t, self._made(s) + total, s * w, s, moved)
        return event

    def _follow_walk(self, limit: int | None,
                     steps: _Steps | None) -> tuple[int, int, int, bool, int]:
        """`_follow` for any dividers, the steps recorded: (t, |v|, units added, moved,
        event)."""
        dx = self.dx
        s, d = _sign(dx), abs(dx)
        units = self._remaining(s, d)
        walk = _Walk(units, d * 2048 - units, s, 32 << self._pulse_div, steps)
        w = abs(self._v)
        floor = min(self._v_min, self._v_max)
        t = self.now
        moved = False
        event: int | None = None
        while event is None:
            t, w, moved, event = self._follow_step(walk, t, w, moved, limit, floor)
        return t, w, walk.total, moved, event

    def _follow_step(self, walk: _Walk, t: int, w: int, moved: bool, limit: int | None,
                     floor: int) -> tuple[int, int, bool, int | None]:
        """From cycle t (|v| = w) through the next ramp tick, or a run of them in one go:
        (t, w, moved, event), event None while the stretch goes on."""
        rp, pp, a = 32 << self._ramp_div, walk.pulse_period, self._a_max
        c = (t // rp + 1) * rp                         # next ramp tick
        n = w >> 8
        if n and w == self._speed(walk.left) * 256 and floor * 256 < w:
            return self._on_target_run(walk, t, w, moved, limit)
        end = c - 1 if limit is None else min(c - 1, limit)
        count = end // pp - t // pp
        moved |= count > 0 and w > 0
        arrival = walk.pulses(count, n, t // pp + 1)
        if arrival:
            return arrival - 1, w, moved, arrival
        t = end
        if limit is not None and t >= limit:
            return t, w, moved, limit + 1
        ticks, count, n = self._brake_run(c, w, walk.left, limit)
        if ticks:                                      # falling by A_MAX at one pulse size
            moved |= count > 0
            walk.pulses(count, n, (c - 1) // pp + 1)
            return c + ticks * rp - 1, w - a * ticks, moved, None
        return self._follow_tick(walk, c, w, moved, floor)

    def _on_target_run(self, walk: _Walk, t: int, w: int, moved: bool,
                       limit: int | None) -> tuple[int, int, bool, int | None]:
        """|v| = w on its computed target: one velocity until the square-root term drops
        below it (6.1.9), pulses of w >> 8 units from cycle t; as `_follow_step`."""
        pp, n = walk.pulse_period, w >> 8
        k = _ceil_div(walk.left - self._level_start(n) + 1, n)
        c_k = (t // pp + k) * pp
        if limit is not None and c_k > limit:
            moved |= limit // pp > t // pp
            walk.pulses(limit // pp - t // pp, n, t // pp + 1)
            return limit, w, moved, limit + 1
        arrival = walk.pulses(k, n, t // pp + 1)
        if arrival:
            return arrival - 1, w, True, arrival
        return c_k, w, True, None

    def _follow_tick(self, walk: _Walk, c: int, w: int, moved: bool,
                     floor: int) -> tuple[int, int, bool, int | None]:
        """The ramp tick at c (|v| towards its computed target by A_MAX, 6.1.9.2) and its
        pulse if one falls on c; as `_follow_step`."""
        pp = walk.pulse_period
        before = w
        w = _toward(w, self._speed(walk.left) * 256, self._a_max)
        if c % pp == 0 and w > 0:
            moved = True
            if walk.pulses(1, w >> 8, c // pp):
                return c - 1, before, moved, c
        if w == floor * 256 or w == 0:
            return c, w, moved, c + 1
        return c, w, moved, None

    def _follow_fast(self, limit: int | None) -> tuple[int, int, int, bool, int]:
        """`_follow` for PULSE_DIV == RAMP_DIV, where a pulse follows each ramp tick: |v| moves
        towards the computed target by at most A_MAX (6.1.9.2), then the pulse adds |v| >> 8
        units (6.1.12.1). The per-tick rules run on locals; lagging ticks are walked by
        `_lag_walk` (A_MAX >= 32) or `_lag_run` (level by level, 0 < A_MAX < 32), runs on the
        target by `_on_target`. Returns (t, |v|, units added, moved, event)."""
        rp, a = 32 << self._ramp_div, self._a_max
        pm, sh, vmax, vmin = self._pmul, 3 + self._pdiv, self._v_max, self._v_min
        floor = min(vmin, vmax)
        low = floor << 8                        # |v| reaching it ends the stretch (so does 0,
        lag_walk = a >= 32 and vmin <= vmax     # which only a zero floor lets |v| reach)
        lag_run = 0 < a < 32
        dx = self.dx
        units = left = self._remaining(_sign(dx), abs(dx))   # left >= 1 throughout
        w = abs(self._v)
        c = c0 = (self.now // rp + 1) * rp     # the next ramp tick
        last = c + _FOREVER if limit is None else limit
        while c <= last:
            if lag_walk:
                c, w, left = _lag_walk(c, w, left, a, low, pm, sh, rp, last)
                if c > last:
                    break
            sp = isqrt(pm * left >> sh)
            sp = vmax if sp > vmax else (vmin if sp < vmin else sp)
            tgt = sp << 8
            if w == tgt and sp > floor and left > sp:
                c, sp, left = _on_target(c, sp, left, rp, last, a, pm, sh, floor)
                w = sp << 8
                continue
            if w <= tgt:
                nw = w + a if w + a < tgt else tgt
            elif w - a > tgt and lag_run and left > (w - a) >> 8:
                c, w, left = _lag_run(c, w, left, a, rp, last, pm, sh, vmin, vmax)
                continue
            else:
                nw = w - a if w - a > tgt else tgt
            n = nw >> 8
            if n >= left:                       # the arrival step at c
                return c - 1, w, units - left, c > c0, c
            w = nw
            left -= n
            if w == low:
                return c, w, units - left, c > c0 or w > 0, c + 1
            c += rp
        return last, w, units - left, c > c0, last + 1

    def _brake_run(self, c: int, w: int, left: int, limit: int | None) -> tuple[int, int, int]:
        """Ramp ticks from tick c on (pulses before c done, `left` units to go) over which |v|
        keeps falling by A_MAX above its target without crossing a multiple of 256 nor
        arriving nor passing `limit`: (ticks, pulse ticks among them, units per pulse).

        Within them w >> 8 = n is fixed, the target must stay below n + 1 (it only falls
        as `left` falls, so the first tick decides) and the pulses add n each."""
        a, rp, pp = self._a_max, 32 << self._ramp_div, 32 << self._pulse_div
        w1 = w - a                                  # |v| after tick c
        if a == 0 or w1 <= 0 or w1 & 255 <= a:      # not even two ticks: walk it
            return 0, 0, 0
        n = w1 >> 8
        if self._v_max > n and (self._v_min > n or left >= self._level_start(n + 1)):
            return 0, 0, 0                          # the target catches up at tick c
        ticks = ((w1 & 255) - 1) // a + 1           # ticks with |v| in (n*256, n*256+256)
        first = (c - 1) // pp                       # pulse ticks done before c
        if n:                                       # the arrival pulse stays outside
            last = first + _ceil_div(left, n) - 1
            ticks = min(ticks, ((last + 1) * pp - c) // rp)
        if limit is not None:
            ticks = min(ticks, (limit + 1 - c) // rp)
        if ticks <= 0:
            return 0, 0, 0
        return ticks, (c + ticks * rp - 1) // pp - first, n

    def _settle(self, t: int, made: int, v: int, s: int, moved: bool) -> None:
        """Set the state after a stretch of `_follow` (made: accumulator units towards the
        target, counted from the last whole step before the stretch)."""
        self._cached_plan = None
        steps, self._acc = divmod(made, 2048)
        self._x = (self._x + s * steps) % self._modulus
        if moved:
            self._acc_dir = s
        elif self._acc_dir not in (0, s):      # no pulse yet: keep the old orientation
            self._acc = 2047 - self._acc
        self._v = v
        self.now = t

    def _follow_end(self, seg: _Follow) -> None:
        """Jump to the end of a planned `_follow` stretch (memoised result)."""
        s = _sign(self.dx)
        self._settle(seg.t0 + seg.end_offset, self._made(s) + seg.total, s * seg.w_end, s, seg.moved)

    # ------------------------------------------------------------------ time
    def _jump(self, phase: _Phase | _Follow, t: int) -> None:
        """Move the state to cycle t inside `phase` (closed form)."""
        if t <= self.now:
            return
        self._cached_plan = None
        if isinstance(phase, _Follow):
            if t == phase.t0 + phase.end_offset:
                self._follow_end(phase)
            else:
                self._follow(t, None)
            return
        base = self._plan_base
        if base is not None and base[0] is phase:   # moved on by `_jump_within`: back to t0
            _phase, self._x, self._acc, self._acc_dir, self._v = base
        i = t // phase.pulse_period
        if i >= phase.i_dir:
            total = phase.acc0 + phase.pulse_sum(i)
            steps, self._acc = total >> 11, total & 2047
            self._x = (self._x + phase.direction * steps) % self._modulus
            if phase.direction:
                self._acc_dir = phase.direction
        k = t // phase.ramp_period - phase.j0
        if phase.delta != 0:
            self._v = phase.direction * phase.w(k)
        self.now = t

    def _jump_within(self, phase: _Phase, t: int) -> None:
        """`_jump` inside the linear phase of the cached plan, keeping the plan: the phase is the
        closed form of the motion from its t0 up to its event, read at any cycle, so the state is
        evaluated from the state at t0 (`_plan_base`, kept on the first such jump) and the next
        advance or next_event needs no planning (docs/motion.md "Lazy reads")."""
        if t <= self.now:
            return
        base = self._plan_base
        if base is None or base[0] is not phase:    # the state is still at t0
            base = self._plan_base = (phase, self._x, self._acc, self._acc_dir, self._v)
        _phase, x, acc, acc_dir, v = base
        i = t // phase.pulse_period
        if i >= phase.i_dir:
            total = phase.acc0 + phase.pulse_sum(i)
            steps, acc = total >> 11, total & 2047
            x = (x + phase.direction * steps) % self._modulus
            if phase.direction:
                acc_dir = phase.direction
        if phase.delta != 0:
            v = phase.direction * phase.w(t // phase.ramp_period - phase.j0)
        self._x, self._acc, self._acc_dir, self._v = x, acc, acc_dir, v
        self.now = t

    def advance(self, until: int) -> None:
        """Jump to cycle `until` (>= now), exactly as the per-tick model would."""
        if until < self.now:
            raise ValueError(f"cannot go back in time: until={until} < now={self.now}")
        while self.now < until:
            cached = self._cached_plan
            if cached is not None:
                event, _clamp, phase = cached   # the first event, valid for any until
                if (event is None or event > until) and type(phase) is _Phase:
                    self._jump_within(phase, until)
                    return
            else:
                event, _clamp, phase = self._plan(until)
            if event is None or event > until:
                self._jump(phase, until)
                return
            self._jump(phase, event - 1)
            self._cycle(event)

    def next_event(self) -> int | None:
        """Next cycle where the ramp phase changes or the target is reached
        (None: nothing changes without a new register write)."""
        if self._cached_plan is None:
            self._cached_plan = self._memo_plan()
        event, clamp, _phase = self._cached_plan
        return _min_opt(event, clamp)

    def _memo_plan(self) -> _Plan:
        """`_plan(None)`, memoised by the whole state relative to now (`_Memo`): the
        registers, dx, the velocity, the accumulator and the phase of the tick clocks."""
        key = (self.dx, self._v, self._acc, self._acc_dir, self._stopping, self._mode,
               self.now % (32 << max(self._ramp_div, self._pulse_div)), self._v_min,
               self._v_max, self._v_target, self._a_max, self._pmul, self._pdiv,
               self._pulse_div, self._ramp_div, self._modulus)
        memo = _FOLLOW_MEMO.plans
        hit = memo.get(key)
        if hit is None:
            plan = self._plan(None)
            if len(memo) >= _FOLLOW_MEMO_SIZE:
                memo.clear()
            memo[key] = (self.now, plan)
            return plan
        now0, (event, clamp, phase) = hit
        shift = self.now - now0
        return (None if event is None else event + shift,
                None if clamp is None else clamp + shift, phase.shifted(shift))

    def step_events(self, until: int) -> list[tuple[int, int]]:
        """(cycle, +1 or -1) of each step on cycles now+1 .. until; advances to until."""
        if until < self.now:
            raise ValueError(f"cannot go back in time: until={until} < now={self.now}")
        out: list[tuple[int, int]] = []
        if self._cached_plan is not None and self._cached_plan[2].t0 != self.now:
            self._cached_plan = None     # its steps count from t0: list only those after now
        while self.now < until:
            if self._cached_plan is not None:
                event, _clamp, phase = self._cached_plan
            else:
                event, _clamp, phase = self._plan(until)
            end = until if event is None or event > until else event - 1
            if isinstance(phase, _Follow):
                if end > self.now:
                    self._follow(end, out)
            elif phase.direction != 0 and end > self.now:
                k = 1
                while (t := phase.nth_step_cycle(k, end)) is not None:
                    out.append((t, phase.direction))
                    k += 1
            self._jump(phase, end)
            if end < until:
                step = self._cycle(end + 1)
                if step:
                    out.append((end + 1, step))
        return out

    def time_at_position(self, position: int, *, max_phases: int = 1000) -> int | None:
        """First cycle >= now where X_ACTUAL == position if nothing is written, else None.

        Looks ahead at most `max_phases` ramp phases (a ramp_mode move has about
        four); None then also means "not within that horizon" (only misconfigured
        ramps, e.g. V_MIN = 0 hopping towards a target, need more), so callers that
        re-plan at every next_event() see every pass.
        """
        target = position % self._modulus
        if self._x == target:
            return self.now
        probe = self.copy()
        for _ in range(max_phases):
            event, _clamp, phase = probe._plan(None)
            if isinstance(phase, _Follow):
                if event is None:
                    raise AssertionError("a follow stretch always ends")
                steps: _Steps = []
                probe.copy()._follow(event - 1, steps)
                need = (target - probe._x) * _sign(probe.dx) % probe._modulus
                if 0 < need <= len(steps):
                    return steps[need - 1][0]
            elif phase.direction != 0:
                need = (target - probe._x) * phase.direction % probe._modulus
                end = None if event is None else event - 1
                if end is None or end > probe.now:
                    t = phase.nth_step_cycle(need, end)
                    if t is not None:
                        return t
            if event is None:
                return None
            probe._jump(phase, event - 1)
            probe._cycle(event)
            if probe._x == target:
                return probe.now
        return None

    def copy(self) -> Tmc429Ramp:
        clone = Tmc429Ramp.__new__(Tmc429Ramp)
        clone.__dict__.update(self.__dict__)
        return clone


def _min_opt(a: int | None, b: int | None) -> int | None:
    if a is None:
        return b
    if b is None:
        return a
    return min(a, b)


def _first_true(pred: Callable[[int], bool], lo: int, hi: int, period: int) -> int | None:
    """Smallest j in lo..hi with pred(j) (pred monotone false..true), as cycle j*period."""
    if hi < lo or not pred(hi):
        return None
    while lo < hi:
        mid = (lo + hi) // 2
        if pred(mid):
            hi = mid
        else:
            lo = mid + 1
    return lo * period
