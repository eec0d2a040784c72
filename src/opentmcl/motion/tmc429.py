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
* ramp_mode: V_MAX until |V_ACTUAL| exceeds sqrt(2048 * p * |dx|), p =
  PMUL / 2^(3+PDIV) (6.1.9), then a deceleration with A_MAX down to V_MIN;
  soft_mode: target velocity p * |dx|; velocity_mode: V_TARGET; hold_mode: the
  velocity is left alone (6.1.10.1). At the target a velocity <= V_MIN stops (6.1.3).

Time `now` counts f_CLK cycles. `advance` jumps over whole ramp phases: inside a
phase the ramp target is fixed, the velocity is linear in the ramp tick index
(or constant), the step count is a floor-sum of it, and the first cycle where
something changes (end of a ramp, deceleration start, arrival, a soft-mode
target change) is found by binary search on those closed forms. That one
cycle is then applied exactly. The per-tick oracle in
tests/motion/tmc429_reference.py defines the behaviour this must reproduce.
"""
from __future__ import annotations

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


@dataclass
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

    def steps_until(self, t: int) -> int:
        """Steps made on cycles t0+1 .. t."""
        return (self.acc0 + self.pulse_sum(t // self.pulse_period)) >> 11

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
        self._braking = False    # ramp_mode deceleration towards V_MIN has begun
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
        self._cached_plan: tuple | None = None   # _plan(None) of the present state

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
        d = abs(dx)
        if self._mode == RAMP_MODE:
            raw = isqrt(self._pmul * d << 8 >> self._pdiv)
        else:
            raw = self._pmul * d >> (3 + self._pdiv)
        return _sign(dx) * min(self._v_max, max(self._v_min, raw))

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
        """A_ACTUAL (6.1.8), unsmoothed: A_MAX while the next ramp tick changes the
        velocity, else 0."""
        if self._mode == HOLD_MODE or self._a_max == 0:
            return 0
        vt = self._ramp_target()[0]
        if vt is None:  # dx == 0: stop or decelerate towards 0
            return 0 if abs(self._v) <= self._v_min * 256 else self._a_max
        return self._a_max if self._v != vt else 0

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
    def braking(self) -> bool:
        """ramp_mode: the deceleration towards V_MIN has begun (cleared when the
        target changes or the motion no longer heads for it)."""
        return self._braking and self._v * self.dx > 0

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
                self._braking = False
            elif name == "v_actual":
                if self._mode == HOLD_MODE:
                    self._v = value * 256
                    self._stopping = False
            elif name == "v_target":
                self._v_target = value
                self._stopping = False
            elif name == "mode":
                self._mode = value
                self._braking = False
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
        self._braking = False
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
            self._braking = False
            if abs(self._v) <= self._v_min * 256:
                self._v = 0
            else:
                self._v = _toward(self._v, 0, self._a_max)
            return
        s = _sign(dx)
        if self._v * s <= 0:
            self._braking = False
        if self._mode == RAMP_MODE and not self._braking and self._v * s > 0:
            if self._triggers(abs(self._v) >> 8, abs(dx)):
                self._braking = True
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
            self._braking = False
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

    def _triggers(self, n: int, d: int) -> bool:
        """ramp_mode deceleration start: sqrt(2048 * p * d) < n (6.1.9)."""
        return n * n << self._pdiv > self._pmul * d << 8

    def _soft_speed(self, d: int) -> int:
        return min(self._v_max, max(self._v_min, self._pmul * d >> (3 + self._pdiv)))

    def _position_target(self, s: int, d: int) -> int:
        if self._mode == RAMP_MODE:
            speed = min(self._v_min, self._v_max) if self._braking else self._v_max
        else:
            speed = self._soft_speed(d)
        return s * speed * 256

    def _ramp_target(self) -> tuple[int | None, bool]:
        """Target velocity (1/256 units) of the coming ramp ticks and the braking
        flag they will see; None when dx == 0 in ramp/soft_mode."""
        v = self._v
        if self._mode == HOLD_MODE:
            return v, self._braking
        if self._stopping:
            return 0, self._braking
        if self._mode == VELOCITY_MODE:
            return self._velocity_mode_target(), self._braking
        dx = self.dx
        if dx == 0:
            return None, False
        s = _sign(dx)
        braking = self._braking and v * s > 0
        saved, self._braking = self._braking, braking
        target = self._position_target(s, abs(dx))
        self._braking = saved
        return target, braking

    # ------------------------------------------------------------------ phases
    def _plan(self, until: int | None) -> tuple[int | None, int | None, _Phase]:
        """Closed form of the coming phase.

        Returns (event, clamp, phase): `event` is the first cycle > now that must
        be applied exactly (None: none ever), `clamp` the cycle where the ramp
        reaches its target (reported by next_event, also exact).
        """
        rp, pp = 32 << self._ramp_div, 32 << self._pulse_div
        v0, a = self._v, self._a_max
        vt, braking = self._ramp_target()
        self._braking = braking  # what the next ramp tick would do anyway
        dx_zero = vt is None
        if dx_zero:
            vt = 0
        mode = self._mode
        ramping = a > 0 and v0 != vt and mode != HOLD_MODE
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
        phase = _Phase(self.now, rp, pp, j0, i0, w0, delta, direction, acc0, i_dir)

        ramp_events: list[int] = []
        clamp = None
        if ramping:
            if _sign(vt) == direction or vt == 0:
                k_end = _ceil_div(abs(abs(vt) - w0), a)       # reaches vt (or 0)
            else:
                k_end = _ceil_div(w0, a)                       # changes sign
            clamp = (j0 + k_end) * rp
            ramp_events.append(clamp)
        if self._stopping and mode != HOLD_MODE and v0 == 0:
            ramp_events.append((j0 + 1) * rp)                  # release at once
        if dx_zero and not self._stopping and mode in (RAMP_MODE, SOFT_MODE):
            limit = self._v_min * 256
            if w0 <= limit:
                if v0 != 0:
                    ramp_events.append((j0 + 1) * rp)
            elif a > 0:
                ramp_events.append((j0 + _ceil_div(w0 - limit, a) + 1) * rp)
        first_ramp = min(ramp_events) if ramp_events else None

        bound = _min_opt(until, None if first_ramp is None else first_ramp - 1)
        # steps that change the ramp target (or stop the motor)
        n_steps = self._step_limit(direction, dx_zero)
        step_event = None
        if n_steps is not None and direction != 0:
            if bound is None and delta != 0:
                raise AssertionError("ramping phase without end")
            step_event = phase.nth_step_cycle(n_steps, bound)
        bound2 = _min_opt(bound, None if step_event is None else step_event - 1)
        trig = None
        if (mode == RAMP_MODE and not braking and not dx_zero and not self._stopping
                and direction == _sign(self.dx) and direction != 0):
            trig = self._find_trigger(phase, abs(self.dx), bound2)
        event = _min_opt(_min_opt(first_ramp, step_event), trig)
        return event, clamp, phase

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

    def _find_trigger(self, ph: _Phase, d0: int, t_hi: int | None) -> int | None:
        """First ramp tick (cycle) at which ramp_mode starts to decelerate."""
        rp = ph.ramp_period

        def fires(j: int) -> bool:
            n = ph.w(j - 1 - ph.j0) >> 8
            d = d0 - ph.steps_until(j * rp - 1)
            return self._triggers(n, d)

        j_lo = ph.j0 + 1
        if ph.delta == 0:
            # constant |V_ACTUAL| = n: fires once d <= D = ceil(n^2 2^PDIV / (256 PMUL)) - 1
            n = ph.w0 >> 8
            if n == 0:
                return None
            need = d0 - (_ceil_div(n * n << self._pdiv, self._pmul << 8) - 1)
            if need <= 0:
                j = j_lo
            else:
                c = ph.nth_step_cycle(need, t_hi)
                if c is None:
                    return None
                j = max(j_lo, _ceil_div(c + 1, rp))
            if t_hi is not None and j * rp > t_hi:
                return None
            return j * rp
        if t_hi is None:               # a ramping phase always ends at its clamp
            raise AssertionError("unbounded trigger search in a ramping phase")
        j_hi = t_hi // rp
        if j_hi < j_lo:
            return None
        if ph.delta >= 0:
            return _first_true(fires, j_lo, j_hi, rp)
        # decelerating towards a lower V_MAX: monotone only while |V_ACTUAL| holds
        j = j_lo
        while j <= j_hi:
            n = ph.w(j - 1 - ph.j0) >> 8
            # last tick whose preceding velocity still has integer part n
            k_last = (ph.w(j - 1 - ph.j0) - n * 256) // (-ph.delta) + (j - 1 - ph.j0)
            j_end = min(j_hi, k_last + 1 + ph.j0)
            found = _first_true(fires, j, j_end, rp)
            if found is not None:
                return found
            j = j_end + 1
        return None

    # ------------------------------------------------------------------ time
    def _jump(self, phase: _Phase, t: int) -> None:
        """Move the state to cycle t inside `phase` (closed form)."""
        if t <= self.now:
            return
        self._cached_plan = None
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

    def advance(self, until: int) -> None:
        """Jump to cycle `until` (>= now), exactly as the per-tick model would."""
        if until < self.now:
            raise ValueError(f"cannot go back in time: until={until} < now={self.now}")
        while self.now < until:
            if self._cached_plan is not None:
                event, _clamp, phase = self._cached_plan   # the first event, valid for any until
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
            self._cached_plan = self._plan(None)
        event, clamp, _phase = self._cached_plan
        return _min_opt(event, clamp)

    def step_events(self, until: int) -> list[tuple[int, int]]:
        """(cycle, +1 or -1) of each step on cycles now+1 .. until; advances to until."""
        if until < self.now:
            raise ValueError(f"cannot go back in time: until={until} < now={self.now}")
        out: list[tuple[int, int]] = []
        while self.now < until:
            if self._cached_plan is not None:
                event, _clamp, phase = self._cached_plan
            else:
                event, _clamp, phase = self._plan(until)
            end = until if event is None or event > until else event - 1
            if phase.direction != 0 and end > self.now:
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
            if phase.direction != 0:
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


def _first_true(pred, lo: int, hi: int, period: int) -> int | None:
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
