"""The six-point ramp's arithmetic and planners (TMC5130, TMCM-6212 firmware manual 4.1, axis
parameters 4, 5 and 15-21; TMC5130 datasheet, docs/motion.md): the ramp in engine units (`Ramp`),
its braking distances in closed form, and the planners that turn a move or a velocity change into
analytic constant-acceleration segments (`segments.py`) on whole ticks. The engine that keeps the
state and answers the reads is `sixpoint.SixPointRampEngine`.

Like the chip, every decision is taken on whole ticks: a ramp phase ends on the last whole tick
before its target speed, which is then taken in one jump of less than one tick's acceleration;
deceleration starts on the first tick at which the remaining distance is at most the braking
distance. Moves from a standstill reuse the plan of an earlier move over the same distance
(`RestPlans`), bit-identical to planning from scratch (tests/motion/test_sixpoint_golden.py).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from fractions import Fraction
from numbers import Rational

from .segments import (
    A_PER_PPS2,
    PSCALE,
    V_PER_PPS,
    Segment,
    ceil_div,
    first_integer,
    quadratic_guess,
    sign,
    snap,
)

_new = tuple.__new__
"""`_new(Segment, (k0, k1, p0, v0, a, rest_since))`: a Segment without the
keyword handling of its constructor (planners make many)."""

TZEROWAIT_CLOCKS = 512
"""Unit of the ramp wait time AP21: 512 clocks = 32 us at 16 MHz (manual 4.1: 0.000032 s)."""


def wrap32(x: int) -> int:
    """Two's complement 32-bit wrap of the position counter."""
    return ((x + (1 << 31)) & 0xFFFF_FFFF) - (1 << 31)


class RampParameterError(ValueError):
    """A ramp parameter value the engine cannot use (negative, not a number)."""


class PlanInvariantError(AssertionError):
    """A planner loop did not end where its invariant says it must (a bug, not bad input)."""


PLAN_ROUNDS = 16
"""Rounds a planner loop may take. Each round moves the speed into another band (below
V1, V1..VMAX, above VMAX: three at most) or holds it until the braking curve (one hold
per band), so a correct plan needs far fewer; more means the invariant broke."""


def _no_end(loop: str, run: _Run) -> PlanInvariantError:
    return PlanInvariantError(f"{loop}: no end after {PLAN_ROUNDS} rounds at tick {run.t}, speed "
                              f"{run.u}: a round moved the speed to no other band and the "
                              "motor not onto the braking curve")


def real_parameter(name: str, value: object) -> Fraction:
    if type(value) is int:  # the common case, without the numbers-ABC checks
        return Fraction(value)
    if isinstance(value, bool) or not isinstance(value, (Rational, float)):
        raise RampParameterError(f"{name} must be a number, got {value!r}")
    if isinstance(value, float) and not math.isfinite(value):
        raise RampParameterError(f"{name} must be finite, got {value!r}")
    return Fraction(value)


_V_PER_PPS = int(V_PER_PPS)    # both are whole numbers: DEN is a multiple of CLOCK_HZ^2
_A_PER_PPS2 = int(A_PER_PPS2)
assert _V_PER_PPS == V_PER_PPS and _A_PER_PPS2 == A_PER_PPS2


def _scaled(x, k: int) -> int:
    """Nearest engine unit to x * k (ties upwards; exact for every pps and
    internal-unit value), in integer arithmetic."""
    if type(x) is int:
        return x * k
    f = x if type(x) is Fraction else Fraction(x)
    n, d = f.numerator, f.denominator
    return (2 * n * k + d) // (2 * d)  # floor(n*k/d + 1/2)


def velocity_units(pps) -> int:
    """pps -> engine velocity units (1/DEN microsteps per tick)."""
    return _scaled(pps, _V_PER_PPS)


def acceleration_units(pps2) -> int:
    """pps^2 -> engine acceleration units (1/DEN microsteps per tick^2)."""
    return _scaled(pps2, _A_PER_PPS2)


@dataclass(frozen=True)
class Ramp:
    """Ramp parameters in engine units (segments.py): velocities in 1/DEN
    microsteps per tick, accelerations in 1/DEN microsteps per tick^2,
    `wait` in ticks."""

    vmax: int
    amax: int
    dmax: int
    v1: int = 0
    a1: int = 0
    d1: int = 0
    vstart: int = 0
    vstop: int = 0
    wait: int = 0
    # constants of `braking`, derived from the fields above (not part of the identity)
    _low_rate: int = field(init=False, repr=False, compare=False)
    _vstop2: int = field(init=False, repr=False, compare=False)
    _v1_2: int = field(init=False, repr=False, compare=False)
    _c1: int = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        # constants of `braking` (the band loop in closed form), set once per parameter set
        vstop2 = self.vstop * self.vstop
        v1 = self.v1
        object.__setattr__(self, "_low_rate", self.d1 if v1 > 0 else self.dmax)
        object.__setattr__(self, "_vstop2", vstop2)
        object.__setattr__(self, "_v1_2", v1 * v1)
        object.__setattr__(self, "_c1", v1 * v1 - vstop2)  # V1^2 - VSTOP^2 (D1 band), used if V1 > VSTOP

    @classmethod
    def from_pps(cls, *, vmax, amax, dmax, v1=0, a1=0, d1=0, vstart=0, vstop=0, wait_ticks=0) -> Ramp:
        v, a = velocity_units, acceleration_units
        return cls(v(vmax), a(amax), a(dmax), v(v1), a(a1), a(d1), v(vstart), v(vstop), int(wait_ticks))

    # --- bands (V1 splits both ramps; V1 = 0 disables A1/D1) ------------
    def accel_band(self, u: int) -> tuple[int, int]:
        """(rate, top) of the acceleration phase that starts at speed u < VMAX."""
        if self.v1 > 0 and u < self.v1:
            return self.a1, min(self.v1, self.vmax)
        return self.amax, self.vmax

    def decel_band(self, u: float, floor: int) -> tuple[int, int]:
        """(rate, low) of the deceleration phase from speed u > floor (an int, or a float
        in `braking_f`)."""
        if self.v1 > 0 and u > self.v1:
            return self.dmax, max(self.v1, floor)
        return (self.d1 if self.v1 > 0 else self.dmax), floor

    def braking(self, u: int) -> tuple[int, int]:
        """Distance (num, den) in position units from speed u down to VSTOP
        (DMAX above V1, D1 below). A band whose deceleration is 0 is skipped
        (no ramp there, see docs/assumptions.md).

        Closed form of `braking_loop` (the same pair, term for term)."""
        if u <= self.vstop:
            return 0, 1
        v1 = self.v1
        if v1 == 0 or u <= v1:  # one band: D1 (or DMAX without V1) down to VSTOP
            rate = self._low_rate
            return (u * u - self._vstop2, rate) if rate else (0, 1)
        dmax, d1 = self.dmax, self.d1
        if v1 <= self.vstop:  # the DMAX band reaches down to VSTOP
            return (u * u - self._vstop2, dmax) if dmax else (0, 1)
        if dmax:  # DMAX down to V1, then D1 down to VSTOP
            if d1:
                return (u * u - self._v1_2) * d1 + self._c1 * dmax, dmax * d1
            return u * u - self._v1_2, dmax
        return (self._c1, d1) if d1 else (0, 1)

    def braking_loop(self, u: int) -> tuple[int, int]:
        """`braking` band by band (the definition; kept as the test oracle)."""
        num, den = 0, 1
        while u > self.vstop:
            rate, low = self.decel_band(u, self.vstop)
            if rate:
                num, den = num * rate + (u * u - low * low) * den, den * rate
            u = low
        return num, den

    def braking_f(self, u: float) -> float:
        """Float twin of `braking` for root estimates."""
        b = 0.0
        uu = u
        while uu > self.vstop:
            rate, low = self.decel_band(uu, self.vstop)
            if rate:
                b += (uu * uu - float(low) ** 2) / rate
            uu = low
        return b


# --------------------------------------------------------------------------
# planners: pure functions from a state to a list of segments (integer units)
# --------------------------------------------------------------------------
class _Run:
    """Cursor of a planned run in direction s (+1/-1): tick t, position p,
    speed u >= 0."""

    __slots__ = ("t", "p", "u", "s", "rest", "out")

    def __init__(self, t: int, p: int, s: int, u: int, rest, out: list):
        self.t, self.p, self.s, self.u, self.rest, self.out = t, p, s, u, rest, out

    def emit(self, k1: int | None, alpha: int) -> None:
        """Append the piece [t, k1) accelerating at alpha along s and move the cursor to k1."""
        self.out.append(_new(Segment, (self.t, k1, self.p, self.s * self.u, self.s * alpha, self.rest)))
        if k1 is not None:
            dt = k1 - self.t
            self.p += self.s * (2 * self.u + alpha * dt) * dt
            self.u += alpha * dt
            self.t = k1

    def rest_here(self) -> None:
        """Come to a standstill at the last whole microstep and stay."""
        self.out.append(_new(Segment, (self.t, None, snap(self.p, self.s), 0, 0, self.t)))


def plan_position(r: Ramp, t: int, p: int, v: int, rest: int | None, target: int,
                  tol: Fraction | int = 0) -> list[Segment]:
    """Positioning-mode plan from (tick t, position p, velocity v) to `target`
    (all in engine units; target unwrapped). `tol` is braking distance a
    deceleration in progress already owes (on-the-fly parameter changes)."""
    out: list[Segment] = []
    if v == 0:
        _from_rest(r, t, p, rest, target, out)
        return out
    s = sign(v)
    run = _Run(t, p, s, abs(v), None, out)
    dist = s * (target - p)
    if dist > 0:
        num, den = r.braking(run.u)
        if (dist + tol) * den >= num:
            _drive(r, run, target)
            return out
    _stop_then(r, run, target)  # target behind, or too close to stop: stop, wait, come back
    return out


def _from_rest(r: Ramp, t: int, p: int, rest: int | None, target: int, out: list) -> None:
    dist = target - p
    u0 = min(r.vstart, r.vmax)
    if dist == 0 or (u0 == 0 and (r.vmax == 0 or r.accel_band(0)[0] == 0)):
        out.append(_new(Segment, (t, None, p, 0, 0, rest)))  # arrived, or cannot move
        return
    start = t if rest is None else max(t, rest + r.wait)
    if start > t:
        out.append(_new(Segment, (t, start, p, 0, 0, rest)))  # ramp wait time (TZEROWAIT)
    _drive(r, _Run(start, p, sign(dist), u0, rest, out), target)


def _drive(r: Ramp, run: _Run, target: int) -> None:
    """Accelerate / cruise (or slow to a lowered VMAX) until the first tick on
    which the remaining distance is at most the braking distance."""
    for _ in range(PLAN_ROUNDS):
        u = run.u
        top: int | None
        if u < r.vmax:
            alpha, top = r.accel_band(u)
            if alpha == 0:
                top = None
        elif u == r.vmax:
            alpha, top = 0, None
        else:
            rate, low = r.decel_band(u, r.vmax)
            if rate == 0:
                run.u = low  # a band without deceleration is skipped
                continue
            alpha, top = -rate, low
        if top is None and u == 0:
            run.rest_here()
            return
        n = None if top is None else abs(top - u) // abs(alpha)  # whole ticks, then a jump < alpha to top
        j = _decel_offset(r, run, target, alpha, n)
        if j is not None:
            if j:
                run.emit(run.t + j, alpha)
            _final(r, run, target)
            return
        if top is None:
            raise PlanInvariantError(f"_drive: a cruise at speed {u} never reaches the braking point")
        if n:
            run.emit(run.t + n, alpha)
        run.u = top
        if top == 0:  # slowed down to VMAX = 0 short of the target
            run.rest_here()
            return
    raise _no_end("_drive", run)


def _decel_offset(r: Ramp, run: _Run, target: int, alpha: int, n: int | None) -> int | None:
    """Smallest offset j in [0, n) at which remaining <= braking distance."""
    r0, u0 = run.s * (target - run.p), run.u

    def pred(j: int) -> bool:
        num, den = r.braking(u0 + alpha * j)
        return (r0 - (2 * u0 + alpha * j) * j) * den <= num

    # the float guess uses the braking band the speed moves into (above V1 once it rises past V1);
    # the predicate is monotone within a phase, so the guess only changes how fast the search ends
    rate, _ = r.decel_band(u0 + 1 if alpha > 0 else u0, r.vstop)
    k = 1.0 + (alpha / rate if rate else 0.0)
    guess = quadratic_guess(float(r0) - r.braking_f(u0), -2.0 * u0 * k, -float(alpha) * k)
    return first_integer(pred, 0, n, guess)


def _final(r: Ramp, run: _Run, target: int) -> None:
    """Decelerate (DMAX to V1, D1 to VSTOP) until the target is reached: the
    motor stops on the first tick whose position reaches the target."""
    s = run.s
    for _ in range(PLAN_ROUNDS):
        rem = s * (target - run.p)
        if rem <= 0:
            break
        u = run.u
        if u == 0:  # stopped short (only after on-the-fly changes): start again
            _from_rest(r, run.t, snap(run.p, s), run.t, target, run.out)
            return
        num, den = r.braking(u)
        if rem * den > num:  # ahead of the braking curve: hold the speed until on it
            run.emit(run.t + ceil_div(rem * den - num, 2 * u * den), 0)
            continue
        rate, low = r.decel_band(u, r.vstop)
        if rate == 0:
            run.u = low
            continue
        n = (u - low) // rate
        if n and (2 * u - rate * n) * n >= rem:  # the target is reached in this phase

            def reached(j: int, u=u, rate=rate, rem=rem) -> bool:
                return (2 * u - rate * j) * j >= rem

            j = first_integer(reached, 1, n + 1, quadratic_guess(-float(rem), 2.0 * u, -float(rate)))
            if j is None:
                raise PlanInvariantError(f"_final: the target is reached by tick {n} yet at no tick")
            run.emit(run.t + j, -rate)
            break
        if n:
            run.emit(run.t + n, -rate)
        if low == r.vstop:  # last band: less than one tick of deceleration left
            rem = s * (target - run.p)
            if rem > 0 and run.u == 0:
                _from_rest(r, run.t, snap(run.p, s), run.t, target, run.out)
                return
            if rem > 0:
                run.emit(run.t + ceil_div(rem, 2 * run.u), 0)
            break
        run.u = low  # V1 reached (jump < DMAX per tick)
    else:
        raise _no_end("_final", run)
    run.out.append(_new(Segment, (run.t, None, target, 0, 0, run.t)))  # arrival: stop on the target


def _stop_then(r: Ramp, run: _Run, target: int) -> None:
    """Ramp down to VSTOP, stop, wait, and start again towards the target."""
    for _ in range(PLAN_ROUNDS):
        if run.u <= r.vstop:
            break
        rate, low = r.decel_band(run.u, r.vstop)
        if rate:
            n = (run.u - low) // rate
            if n:
                run.emit(run.t + n, -rate)
        run.u = low
    else:
        raise _no_end("_stop_then", run)
    _from_rest(r, run.t, snap(run.p, run.s), run.t, target, run.out)


_REST = object()
"""Stands for "the tick the move started resting at" inside a cached plan."""


def _rest_template(r: Ramp, pm: int, dist: int) -> tuple:
    """The run of `_from_rest` after the ramp wait, planned once at tick 0 from
    position `pm` (< PSCALE) over `dist`: a tuple of (k0, k1, p0 - pm, v0, a,
    own_rest, rest). The planner only ever uses differences of ticks and
    positions (and `snap`, which commutes with whole-microstep shifts), so
    the plan of any move of the same distance from a position congruent to
    `pm` is this one moved in time and space (`RestPlans.plan`)."""
    out: list[Segment] = []
    _drive(r, _Run(0, pm, sign(dist), min(r.vstart, r.vmax), _REST, out), pm + dist)
    return tuple((s.k0, s.k1, s.p0 - pm, s.v0, s.a, s.rest_since is _REST,
                  None if s.rest_since is _REST else s.rest_since) for s in out)


class RestPlans:
    """Plans of moves from a standstill for one `Ramp`, cached by distance.

    A TMCL program (or host) moving back and forth repeats the same few
    distances; each repeat then costs a dictionary look-up and a handful of
    tuple creations instead of a full plan. The result is identical to
    `plan_position(r, t, p, 0, rest, target)`."""

    __slots__ = ("ramp", "stuck", "plans")
    LIMIT = 256

    def __init__(self, r: Ramp):
        self.ramp = r
        self.stuck = min(r.vstart, r.vmax) == 0 and (r.vmax == 0 or r.accel_band(0)[0] == 0)
        self.plans: dict[tuple[int, int], tuple | None] = {}   # None: seen once

    def plan(self, t: int, p: int, rest: int | None, target: int) -> list[Segment]:
        dist = target - p
        if dist == 0 or self.stuck:
            return [_new(Segment, (t, None, p, 0, 0, rest))]  # arrived, or cannot move
        pm = p % PSCALE
        key = (dist, pm)
        plans = self.plans
        tpl = plans.get(key)
        if tpl is None:  # a distance seen for the first time is planned directly, the second time cached
            if len(plans) >= self.LIMIT:
                plans.clear()
            if key not in plans:
                plans[key] = None
                out: list[Segment] = []
                _from_rest(self.ramp, t, p, rest, target, out)
                return out
            tpl = plans[key] = _rest_template(self.ramp, pm, dist)
        start = t if rest is None else max(t, rest + self.ramp.wait)
        out = [_new(Segment, (t, start, p, 0, 0, rest))] if start > t else []  # ramp wait (TZEROWAIT)
        append = out.append
        for k0, k1, dp, v0, a, own, rs in tpl:
            append(_new(Segment, (k0 + start, None if k1 is None else k1 + start, p + dp, v0, a,
                                  rest if own else (None if rs is None else rs + start))))
        return out


def plan_velocity(amax: int, t: int, p: int, v: int, rest: int | None, vt: int,
                  wait: int = 0) -> list[Segment]:
    """Velocity-mode plan: ramp with AMAX from v to vt (through zero if the
    sign changes), then run at vt forever (engine units). A motion that starts
    from rest, or turns after ramping down to zero, waits until rest + `wait`
    ticks (AP21: "before next movement or direction inversion can start")."""
    if amax == 0 or v == vt:
        return [_new(Segment, (t, None, p, v, 0, rest if v == 0 else None))]
    out: list[Segment] = []
    if v != 0 and sign(vt) != sign(v):
        n = abs(v) // amax
        if n:
            seg = _new(Segment, (t, t + n, p, v, -sign(v) * amax, None))
            out.append(seg)
            p = seg.p_at(t + n)
        p, t, rest = snap(p, sign(v)), t + n, t + n
        v = 0
        if vt == 0:
            out.append(_new(Segment, (t, None, p, 0, 0, rest)))
            return out
    if v == 0 and rest is not None and rest + wait > t:  # ramp wait time (TZEROWAIT)
        out.append(_new(Segment, (t, rest + wait, p, 0, 0, rest)))
        t = rest + wait
    n = abs(vt - v) // amax
    if n:
        seg = _new(Segment, (t, t + n, p, v, sign(vt - v) * amax, rest if v == 0 else None))
        out.append(seg)
        p, t = seg.p_at(t + n), t + n
    out.append(_new(Segment, (t, None, p, vt, 0, None)))
    return out


# --------------------------------------------------------------------------
# the engine
# --------------------------------------------------------------------------
