"""Runs of ramp ticks where the ramp_mode velocity follows its computed target (TMC4210 6.1.9).

"This calculation is done for each ramp step": on every ramp tick the target speed is
T(U) = min(V_MAX, max(V_MIN, isqrt(PMUL * U >> (3 + PDIV)))) for the U accumulator units still to
go, and the velocity moves towards T * 256 by at most A_MAX (6.1.9.2); each pulse tick adds
|V_ACTUAL| units (6.1.12.1). The square root has no closed form over many ticks, so such a
stretch is walked, but in runs computed by arithmetic (docs/motion-tmc429.md "Following the
target"):

* the target is at least n exactly while U >= L(n) = ceil(n^2 * 2^(3+PDIV) / PMUL) (`level_start`);
* once |v| is at or above its target the velocity never rises again (U only falls);
* with RAMP_DIV >= PULSE_DIV each ramp tick is followed by P = 2^(RAMP_DIV-PULSE_DIV) pulse ticks at
  the new velocity. Then one velocity level n (n * 256 <= |v| < n * 256 + 256) costs a few integer
  operations whatever its number of ticks (`_levels`, A_MAX < 256), and a tick at A_MAX >= 256
  needs a square root only when the velocity lands on its target (`_ticks`).

Other dividers, the stretch's ends and step lists use the general walk (`_step`). `walk` is
memoised by its start state relative to the tick clocks.
"""
from __future__ import annotations

from math import isqrt
from typing import NamedTuple

from .tmc429_arith import FOREVER, ceil_div, level_start, ramp_speed, toward

Steps = list[tuple[int, int]]
"""(cycle, +1 or -1) of each step made."""
Stretch = tuple[int, int, int, bool, int]
"""(cycle reached, |v| there, accumulator units added, a pulse tick saw |v| > 0, next event)."""

MEMO_SIZE = 4096
_MEMO: dict[tuple, tuple[int, int, int, bool, int]] = {}


def clear_memo() -> None:
    """Forget the memoised stretches."""
    _MEMO.clear()


class FollowRegisters(NamedTuple):
    """The registers a stretch reads: tick periods in cycles (6.1.12), A_MAX, PMUL, PDIV, V_MIN,
    V_MAX."""

    ramp_period: int
    pulse_period: int
    a_max: int
    pmul: int
    pdiv: int
    v_min: int
    v_max: int

    @property
    def floor(self) -> int:
        """The lowest target: reaching it (or 0) ends the stretch."""
        return min(self.v_min, self.v_max)

    def speed(self, units: int) -> int:
        return ramp_speed(units, self.pmul, self.pdiv, self.v_min, self.v_max)

    def level_start(self, n: int) -> int:
        return level_start(n, self.pmul, self.pdiv)


class Walk:
    """Pulse bookkeeping of one stretch: units towards the arrival step, the steps made."""

    __slots__ = ("units", "made0", "total", "s", "pulse_period", "steps")

    def __init__(self, units: int, made0: int, s: int, pulse_period: int,
                 steps: Steps | None) -> None:
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
            k = ceil_div(self.units - self.total, n)
            self._record(n, k - 1, first)
            self.total += (k - 1) * n
            return (first + k - 1) * self.pulse_period
        self._record(n, count, first)
        self.total += count * n
        return 0

    def _record(self, n: int, count: int, first: int) -> None:
        """Append (cycle, s) for each step of `count` pulses of n units from pulse index `first`."""
        if self.steps is None:
            return
        made = self.made0 + self.total
        m = made // 2048 + 1
        while m * 2048 <= made + count * n:
            self.steps.append(((first + ceil_div(m * 2048 - made, n) - 1) * self.pulse_period, self.s))
            m += 1


def walk(regs: FollowRegisters, t: int, w: int, units: int, limit: int | None,
         steps: Steps | None = None, made0: int = 0, s: int = 1) -> Stretch:
    """Follow the target from cycle t (|v| = w, `units` > 0 to the arrival step) up to `limit`,
    just before the arrival step, or through the tick that reaches the lowest target (V_MIN,
    or 0). Returns the state reached and the cycle to apply exactly next. `steps` collects the
    steps (direction s, `made0` units of the current step made at the start)."""
    if steps is not None:
        return _walk(regs, Walk(units, made0, s, regs.pulse_period, steps), t, w, limit)
    period = max(regs.ramp_period, regs.pulse_period)
    key = (units, w, t % period, None if limit is None else limit - t, regs)
    hit = _MEMO.get(key)
    if hit is not None:
        dt, w_end, total, moved, dev = hit
        return t + dt, w_end, total, moved, t + dev
    out = _walk(regs, Walk(units, 0, s, regs.pulse_period, None), t, w, limit)
    if len(_MEMO) >= MEMO_SIZE:
        _MEMO.clear()
    _MEMO[key] = (out[0] - t, out[1], out[2], out[3], out[4] - t)
    return out


def _walk(regs: FollowRegisters, wk: Walk, t: int, w: int, limit: int | None) -> Stretch:
    floor = regs.floor
    fast = (wk.steps is None and regs.ramp_period >= regs.pulse_period
            and regs.v_min <= regs.v_max)
    last = t + FOREVER if limit is None else limit
    moved = False
    event: int | None = None
    while event is None:
        if fast:
            t, w, ran = _fast(regs, wk, t, w, last)
            moved |= ran
        t, w, moved, event = _step(regs, wk, t, w, moved, limit, floor)
    return t, w, wk.total, moved, event


# --- the fast runs (RAMP_DIV >= PULSE_DIV, no step list) ---------------------------------------
def _fast(regs: FollowRegisters, wk: Walk, t: int, w: int, last: int) -> tuple[int, int, bool]:
    """As many ticks as the fast runs take from cycle t: (t, |v|, whether pulses with |v| > 0
    were added). Stops before anything the general walk must see (an arrival, `last`, the
    lowest target) and at once when the velocity is still below its target."""
    rp, pp = regs.ramp_period, regs.pulse_period
    c = (t // rp + 1) * rp                          # the next ramp tick
    ran = False
    if t != c - 1:                                  # the rest of this interval at |v|
        count = (c - 1) // pp - t // pp
        if c - 1 > last or count * (w >> 8) >= wk.left:
            return t, w, False
        wk.total += count * (w >> 8)
        ran = count > 0 and w > 0
        t = c - 1
    if regs.a_max == 0:                             # |v| never changes: up to arrival or last
        return _steady(regs, wk, t, w, last, ran)
    if _rising(regs, w, wk.left):
        return t, w, ran
    args = (wk.left, last + 1, rp // pp, rp, regs.a_max, regs.pmul, 3 + regs.pdiv)
    if regs.a_max < 256:
        c2, w, left = _levels(c, w, *args, regs.floor, regs.v_max)
    else:
        c2, w, left = _ticks(c, w, *args, regs.floor << 8, regs.v_max)
    wk.total = wk.units - left
    return c2 - 1, w, ran or c2 > c


def _rising(regs: FollowRegisters, w: int, left: int) -> bool:
    """The target for `left` units is above the level of |v| = w (the velocity may rise)."""
    n = w >> 8
    return n < regs.v_max and (n < regs.v_min or regs.pmul * left >> (3 + regs.pdiv) >= (n + 1) ** 2)


def _steady(regs: FollowRegisters, wk: Walk, t: int, w: int, last: int,
            ran: bool) -> tuple[int, int, bool]:
    """A_MAX = 0: |v| stays; pulses of |v| >> 8 units up to just before the arrival pulse or
    to `last` (the general walk then applies the arrival)."""
    pp, n = regs.pulse_period, w >> 8
    if n == 0 or w == regs.floor << 8:
        return t, w, ran
    count = min(last // pp - t // pp, (wk.left - 1) // n)
    if count <= 0:
        return t, w, ran
    wk.total += count * n
    end = last if count == last // pp - t // pp else (t // pp + count + 1) * pp - 1
    return end, w, True


def _levels(c: int, w: int, left: int, last1: int, period_ratio: int, rp: int, a: int, pm: int,
            sh: int, floor: int, vmax: int) -> tuple[int, int, int]:
    """Ramp ticks from tick c on (|v| = w at or above its target, `left` units to go), one
    velocity level per pass, 0 < A_MAX < 256 and P = period_ratio pulses per tick.

    In level m (w >> 8 = m): J = (w & 255) // A_MAX ticks keep |v| in the level, falling by
    A_MAX (the target is at most m). If U is still >= L(m) after them (in integers:
    PMUL * U >= m^2 * 2^(3+PDIV)), the next tick lands on m * 256 and the velocity stays there
    while U >= L(m): (PMUL * U - m^2 * 2^(3+PDIV)) // (PMUL * P * m) + 1 ticks in the level in
    all; else the level has the J ticks. Then one tick falls by A_MAX into level m - 1, adding
    P (m - 1) units. Levels above V_MAX only fall. Stops before a pass that would reach the
    arrival pulse, a cycle past last1 - 1 or level `floor`; returns (next ramp tick, |v|,
    units left) there."""
    m = w >> 8
    stop = floor                                # a pass at level m ends above (m - 1) * 256
    budget = (last1 - c) // rp                  # whole ticks before last1
    used = 0
    pm_p = pm * period_ratio
    while m > vmax and m > stop:                # V_MAX lowered below |v|: no target to land on
        k = (w & 255) // a + 1
        units = k * period_ratio * m - period_ratio
        if units >= left or used + k > budget:
            return c + used * rp, w, left
        left -= units
        used += k
        w -= k * a
        m -= 1
    while m > stop:
        x = pm * left - (m * m << sh)
        d = pm_p * m
        j = (w & 255) // a
        if x >= j * d:                          # lands on m * 256 after the J ticks
            k = x // d + 2
            nw = (m << 8) - a
        else:
            k = j + 1
            nw = w - k * a
        units = k * period_ratio * m - period_ratio
        if units >= left or used + k > budget:
            break
        left -= units
        used += k
        w = nw
        m -= 1
    return c + used * rp, w, left


def _ticks(c: int, w: int, left: int, last1: int, period_ratio: int, rp: int, a: int, pm: int,
           sh: int, low: int, vmax: int) -> tuple[int, int, int]:
    """Ramp ticks from tick c on at A_MAX >= 256 (|v| = w at or above its target). The tick
    lags (|v| - A_MAX, no square root) when the target is at most n = (|v| - A_MAX) >> 8:
    V_MAX <= n or PMUL * U >> (3 + PDIV) < (n + 1)^2; else |v| lands on the target. Stops
    before a tick that would reach the arrival pulse, a cycle past last1 - 1 or |v| <= `low`
    (V_MIN * 256); returns (next ramp tick, |v|, units left) there."""
    while True:
        nw = w - a
        if nw <= low:
            break
        n = nw >> 8
        x = pm * left >> sh
        if n >= vmax or x < (n + 1) * (n + 1):
            w1 = nw
        else:
            root = isqrt(x)
            w1 = (vmax if root > vmax else root) << 8
        units = period_ratio * (w1 >> 8)
        if units >= left or c + rp > last1:
            break
        left -= units
        c += rp
        w = w1
    return c, w, left


# --- the general walk --------------------------------------------------------------------------
def _step(regs: FollowRegisters, wk: Walk, t: int, w: int, moved: bool, limit: int | None,
          floor: int) -> tuple[int, int, bool, int | None]:
    """From cycle t (|v| = w) through the next ramp tick, or a run of them in one go:
    (t, w, moved, event), event None while the stretch goes on."""
    rp, pp, a = regs.ramp_period, wk.pulse_period, regs.a_max
    c = (t // rp + 1) * rp                         # next ramp tick
    n = w >> 8
    if n and w == regs.speed(wk.left) * 256 and floor * 256 < w:
        return _on_target_run(regs, wk, t, w, moved, limit)
    end = c - 1 if limit is None else min(c - 1, limit)
    count = end // pp - t // pp
    moved |= count > 0 and w > 0
    arrival = wk.pulses(count, n, t // pp + 1)
    if arrival:
        return arrival - 1, w, moved, arrival
    t = end
    if limit is not None and t >= limit:
        return t, w, moved, limit + 1
    ticks, count, n = _brake_run(regs, c, w, wk.left, limit)
    if ticks:                                      # falling by A_MAX at one pulse size
        moved |= count > 0
        wk.pulses(count, n, (c - 1) // pp + 1)
        return c + ticks * rp - 1, w - a * ticks, moved, None
    return _tick(regs, wk, c, w, moved, floor)


def _on_target_run(regs: FollowRegisters, wk: Walk, t: int, w: int, moved: bool,
                   limit: int | None) -> tuple[int, int, bool, int | None]:
    """|v| = w on its computed target: one velocity until the square-root term drops
    below it (6.1.9), pulses of w >> 8 units from cycle t; as `_step`."""
    pp, n = wk.pulse_period, w >> 8
    k = ceil_div(wk.left - regs.level_start(n) + 1, n)
    c_k = (t // pp + k) * pp
    if limit is not None and c_k > limit:
        moved |= limit // pp > t // pp
        wk.pulses(limit // pp - t // pp, n, t // pp + 1)
        return limit, w, moved, limit + 1
    arrival = wk.pulses(k, n, t // pp + 1)
    if arrival:
        return arrival - 1, w, True, arrival
    return c_k, w, True, None


def _tick(regs: FollowRegisters, wk: Walk, c: int, w: int, moved: bool,
          floor: int) -> tuple[int, int, bool, int | None]:
    """The ramp tick at c (|v| towards its computed target by A_MAX, 6.1.9.2) and its
    pulse if one falls on c; as `_step`."""
    pp = wk.pulse_period
    before = w
    w = toward(w, regs.speed(wk.left) * 256, regs.a_max)
    if c % pp == 0 and w > 0:
        moved = True
        if wk.pulses(1, w >> 8, c // pp):
            return c - 1, before, moved, c
    if w == floor * 256 or w == 0:
        return c, w, moved, c + 1
    return c, w, moved, None


def _brake_run(regs: FollowRegisters, c: int, w: int, left: int,
               limit: int | None) -> tuple[int, int, int]:
    """Ramp ticks from tick c on (pulses before c done, `left` units to go) over which |v|
    keeps falling by A_MAX above its target without crossing a multiple of 256 nor
    arriving nor passing `limit`: (ticks, pulse ticks among them, units per pulse).

    Within them w >> 8 = n is fixed, the target must stay below n + 1 (it only falls
    as `left` falls, so the first tick decides) and the pulses add n each."""
    a, rp, pp = regs.a_max, regs.ramp_period, regs.pulse_period
    w1 = w - a                                  # |v| after tick c
    if a == 0 or w1 <= 0 or w1 & 255 <= a:      # not even two ticks: walk it
        return 0, 0, 0
    n = w1 >> 8
    if regs.v_max > n and (regs.v_min > n or left >= regs.level_start(n + 1)):
        return 0, 0, 0                          # the target catches up at tick c
    ticks = ((w1 & 255) - 1) // a + 1           # ticks with |v| in (n*256, n*256+256)
    first = (c - 1) // pp                       # pulse ticks done before c
    if n:                                       # the arrival pulse stays outside
        last = first + ceil_div(left, n) - 1
        ticks = min(ticks, ((last + 1) * pp - c) // rp)
    if limit is not None:
        ticks = min(ticks, (limit + 1 - c) // rp)
    if ticks <= 0:
        return 0, 0, 0
    return ticks, (c + ticks * rp - 1) // pp - first, n


# --- how far the stretch surely goes -----------------------------------------------------------
def end_bound(regs: FollowRegisters, t: int, w: int, units: int) -> int:
    """A cycle > t at or before the stretch's event (docs/motion-tmc429.md "Events of a
    stretch"). |v| moves by at most A_MAX per ramp tick, so the lowest target V_MIN * 256 (or 0)
    is not reached before |w - V_MIN * 256| / A_MAX ticks. The arrival pulse comes no earlier
    than `units` / n_max pulses, n_max the larger of |v| and the present target (later targets
    are lower), nor, while |v| is at or above its target, before `_braking_bound`."""
    rp, pp, a = regs.ramp_period, regs.pulse_period, regs.a_max
    c = (t // rp + 1) * rp
    bound = t + FOREVER
    gap = abs(w - (regs.floor << 8))
    if a and gap:
        bound = c + (ceil_div(gap, a) - 1) * rp
    target = regs.speed(units) << 8
    n_max = max(w, target) >> 8
    if n_max == 0:
        return min(bound, c)
    arrival = (t // pp + ceil_div(units, n_max)) * pp
    if rp >= pp and w >= target:
        arrival = max(arrival, _braking_bound(regs, t, c, w, units))
    return min(bound, arrival)


def _braking_bound(regs: FollowRegisters, t: int, c: int, w: int, units: int) -> int:
    """A cycle at or before the arrival pulse of a stretch whose |v| = w is at or above its
    target, for RAMP_DIV >= PULSE_DIV and p' = PMUL / 2^(3+PDIV) at most the ideal
    A_MAX / (128 P) of 6.1.9.2 (P pulses per ramp tick); 0 when that does not hold.

    With C = 65536 p', E = |v|^2 - C U never exceeds E* = max(E at tick c, C P w / 256,
    (256 V_MIN)^2): a tick falling by A_MAX lowers it (C P / 256 <= 2 A_MAX), a tick landing on
    the target T <= sqrt(p' U) leaves at most C times its units. So each tick adds at most
    g(U) = P sqrt(C U + E*) / 256 units, the ticks before the arrival one number at least
    G(U0) - G(U1) with G(U) = 512 sqrt(C U + E*) / (P C), and the arrival tick starts with
    U1 <= P sqrt(E*) / 256 units left."""
    pp, a, pm, sh = regs.pulse_period, regs.a_max, regs.pmul, 3 + regs.pdiv
    ratio = regs.ramp_period // pp
    left = units - ((c - 1) // pp - t // pp) * (w >> 8)    # after the pulses before tick c
    if 128 * pm * ratio > a << sh or left <= 0:
        return 0
    cs = pm << 16                                           # C * 2^sh
    e = max((w * w << sh) - cs * left, 256 * pm * ratio * w, (regs.v_min << 8) ** 2 << sh)
    root_e = isqrt(ceil_div(e, 1 << sh)) + 1                # >= sqrt(E*)
    u1 = ceil_div(ratio * root_e, 256)
    hi = isqrt((cs * left + e) >> sh)                       # <= sqrt(C U0 + E*)
    lo = isqrt(ceil_div(cs * u1 + e, 1 << sh)) + 1          # >= sqrt(C U1 + E*)
    if hi <= lo:
        return 0
    return c + ((hi - lo) << sh) // (128 * ratio * pm) * regs.ramp_period
