"""Six-point ramp of the TMC5130 (TMCM-6212: one TMC5130 per axis).

TMCM-6212 firmware manual 4.1, axis parameters 4, 5 and 15-21; TMC5130
datasheet (docs/motion.md). In positioning mode the motor starts at VSTART, accelerates with
A1 up to V1 and with AMAX up to VMAX, decelerates with DMAX down to V1 and
with D1 down to VSTOP, then stops on the target; V1 = 0 disables the A1/D1
phases. Before a move starts (and before a reversal) the motor rests for the
ramp wait time (AP21, TZEROWAIT, units of 512 clocks). In velocity mode it
accelerates and decelerates with AMAX only (manual 4.1: A1, V1, D1, VSTART
and VSTOP are "in position mode only").

The model is exact: integer arithmetic on the 16 MHz tick clock, motion
stored as analytic constant-acceleration segments between whole ticks
(`segments.py`). Like the chip, every decision is taken on whole ticks: a
ramp phase ends on the last whole tick before its target speed, which is then
taken in one jump of less than one tick's acceleration; deceleration starts
on the first tick at which the remaining distance is at most the braking
distance. Model choices are listed
in docs/assumptions.md and docs/motion.md.

Cost per move (bench/run.py bench_6212): planning uses integer arithmetic
only (braking distances in closed form per parameter set, `Ramp.braking`),
moves from a standstill reuse the plan of an earlier move over the same
distance (`RestPlans`), and the per-event calls (advance, next_event,
position, position_reached) look at the first queued piece only. All of it
is bit-identical to planning from scratch (tests/motion/test_sixpoint_golden.py).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from fractions import Fraction
from numbers import Integral, Rational

from .base import CLOCK_HZ, Mode, RampEngine, Velocity
from .segments import (
    A_PER_PPS2,
    DEN,
    PSCALE,
    V_PER_PPS,
    Segment,
    SegmentQueue,
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


def _real(name: str, value: object) -> Fraction:
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


def plan_velocity(amax: int, t: int, p: int, v: int, rest: int | None, vt: int) -> list[Segment]:
    """Velocity-mode plan: ramp with AMAX from v to vt (through zero if the
    sign changes), then run at vt forever (engine units)."""
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
class SixPointRampEngine(RampEngine):
    """TMC5130-style ramp generator of one TMCM-6212 axis, in pps units.

    Keyword parameters (manual 4.1; pps, pps^2, ramp wait in 32 us units):
    max_positioning_speed (AP4), max_acceleration (AP5), acceleration_a1
    (AP15), velocity_v1 (AP16), max_deceleration (AP17), deceleration_d1
    (AP18), velocity_vstart (AP19), velocity_vstop (AP20), ramp_wait_time (AP21).
    Defaults are the TMCM-6212 profile defaults.
    """

    PARAMS: dict[str, int] = {
        "max_positioning_speed": 51200,
        "max_acceleration": 51200,
        "acceleration_a1": 51200,
        "velocity_v1": 0,
        "max_deceleration": 51200,
        "deceleration_d1": 51200,
        "velocity_vstart": 0,
        "velocity_vstop": 10,
        "ramp_wait_time": 0,
    }

    def __init__(self, **params: object) -> None:
        self.now = 0
        self._params: dict[str, Fraction] = {k: Fraction(v) for k, v in self.PARAMS.items()}
        self._params.update(self._checked(params))
        self._plan_sets: dict[Ramp, RestPlans] = {}
        self._set_ramp(self._make_ramp(self._params))
        self._mode = Mode.POSITION
        self._target = 0          # AP0, wrapped
        self._target_abs = 0      # the same, unwrapped (microsteps)
        self._vt_pps = Fraction(0)
        self._queue = SegmentQueue([Segment(0, None, 0, 0, 0, None)])
        self._read_at = -1                      # the lazy read (`_read`): tick, plan, values
        self._read_pieces: list[Segment] | None = None
        self._read_step = self._read_v = self._read_pos = 0

    # --- parameters -----------------------------------------------------
    def _checked(self, params: dict[str, object]) -> dict[str, Fraction]:
        out = {}
        for name, value in params.items():
            if name not in self.PARAMS:
                raise TypeError(f"{type(self).__name__} has no ramp parameter {name!r}")
            x = _real(name, value)
            if x < 0:
                raise RampParameterError(f"{name} must not be negative, got {value!r}")
            if name == "ramp_wait_time" and x.denominator != 1:
                raise RampParameterError(f"ramp_wait_time must be a whole number, got {value!r}")
            out[name] = x
        return out

    def _make_ramp(self, p: dict[str, Fraction]) -> Ramp:
        return Ramp.from_pps(
            vmax=p["max_positioning_speed"], amax=p["max_acceleration"], dmax=p["max_deceleration"],
            v1=p["velocity_v1"], a1=p["acceleration_a1"], d1=p["deceleration_d1"],
            vstart=p["velocity_vstart"], vstop=p["velocity_vstop"],
            wait_ticks=int(p["ramp_wait_time"]) * TZEROWAIT_CLOCKS)

    def _set_ramp(self, r: Ramp) -> None:
        """Use ramp `r`, with the plan cache of that parameter set (kept for a
        few sets: programs that switch between speeds keep their plans)."""
        self._ramp = r
        sets = self._plan_sets
        plans = sets.get(r)
        if plans is None:
            if len(sets) >= 8:
                sets.clear()
            plans = sets[r] = RestPlans(r)
        self._rest_plans = plans

    @property
    def params(self) -> dict[str, Fraction]:
        """Current ramp parameters (pps, pps^2, AP21 units)."""
        return dict(self._params)

    @property
    def ramp(self) -> Ramp:
        return self._ramp

    def configure(self, **params: object) -> None:
        """Change ramp parameters on the fly; the motion is re-planned from the
        present state (a deceleration in progress keeps its lateness)."""
        new = self._checked(params)
        if all(self._params[k] == v for k, v in new.items()):
            return
        seg, p, v = self._state()
        tol: Fraction | int = 0
        if self._mode is Mode.POSITION and v != 0:
            dist = sign(v) * (self._target_abs * PSCALE - p)
            if dist > 0:
                tol = max(Fraction(0), Fraction(*self._ramp.braking(abs(v))) - dist)
        self._params.update(new)
        self._set_ramp(self._make_ramp(self._params))
        self._replan(tol)

    # --- state at now ---------------------------------------------------
    def _seg(self) -> Segment:
        """The piece holding now: the first one, since advance() drops the
        past and every new queue starts at now (`at` covers the rest)."""
        seg = self._queue.pieces[0]
        k1 = seg.k1
        if k1 is not None and k1 <= self.now:
            return self._queue.at(self.now)
        return seg

    def _state(self) -> tuple[Segment, int, int]:
        """(piece, position, velocity) at now, in engine units."""
        seg = self._seg()
        if seg.v0 == 0 and seg.a == 0:
            return seg, seg.p0, 0
        return seg, seg.p_at(self.now), seg.v_at(self.now)

    def _read(self) -> None:
        """Evaluate the state at now (lazy reads): `advance` only stores the tick; the first
        read at a tick evaluates the closed form of the piece holding it (`Segment.step`,
        `Segment.v_at`, inlined) and keeps step counter, wrapped position and velocity for that
        tick and plan, so further reads at the same tick are two comparisons and a field
        access. The key is the tick and the queue's piece list, which every command and AP1
        overwrite replace (`advance` only drops pieces that ended)."""
        now = self.now
        queue = self._queue
        pieces = queue.pieces
        seg = pieces[0]
        k0, k1, p0, v0, a, _rest = seg
        if k1 is not None and k1 <= now:
            k0, k1, p0, v0, a, _rest = queue.at(now)
        if v0 == 0 and a == 0:
            q, v = p0 // PSCALE, 0
        else:
            dt = now - k0
            p = p0 + (2 * v0 + a * dt) * dt
            backwards = v0 < 0 if v0 else a < 0
            q, v = (-((-p) // PSCALE) if backwards else p // PSCALE), v0 + a * dt
        self._read_step, self._read_v = q, v
        self._read_pos = ((q + (1 << 31)) & 0xFFFF_FFFF) - (1 << 31)  # wrap32
        self._read_at, self._read_pieces = now, pieces

    def _step(self) -> int:
        if self._read_at != self.now or self._read_pieces is not self._queue.pieces:
            self._read()
        return self._read_step

    def _v(self) -> int:
        """Actual velocity at now in engine units (lazy, see `_read`)."""
        if self._read_at != self.now or self._read_pieces is not self._queue.pieces:
            self._read()
        return self._read_v

    @property
    def position(self) -> int:
        if self._read_at != self.now or self._read_pieces is not self._queue.pieces:
            self._read()
        return self._read_pos

    @property
    def velocity_exact(self) -> Fraction:
        """Actual signed velocity in pps, exact."""
        return Fraction(self._v() * CLOCK_HZ, DEN)

    @property
    def velocity(self) -> int:
        """Actual signed velocity (AP3) in pps, truncated towards zero."""
        n = self._v() * CLOCK_HZ
        return n // DEN if n >= 0 else -((-n) // DEN)

    @property
    def moving(self) -> bool:
        return self._v() != 0

    @property
    def target_position(self) -> int:
        return self._target

    @property
    def target_velocity(self) -> int | Fraction:
        v = self._vt_pps
        return int(v) if v.denominator == 1 else v

    @property
    def mode(self) -> Mode:
        return self._mode

    @property
    def position_reached(self) -> bool:
        """AP8: actual position equals target position and the motor stands. Polled after
        every event: a moving piece answers from its velocity alone, without the position."""
        now = self.now
        if self._read_at == now and self._read_pieces is self._queue.pieces:
            return self._read_v == 0 and self._read_pos == self._target
        seg = self._queue.pieces[0]
        k1 = seg.k1
        if k1 is not None and k1 <= now:
            seg = self._queue.at(now)
        if seg.v0 == 0 and seg.a == 0:
            p0 = seg.p0
            return p0 == self._target_abs * PSCALE or wrap32(p0 // PSCALE) == self._target
        return seg.v_at(now) == 0 and self.position == self._target

    @property
    def segments(self) -> tuple[Segment, ...]:
        """The planned motion from now on (read only; for the axis world)."""
        return tuple(self._queue.pieces)

    # --- commands -------------------------------------------------------
    def _replan(self, tol: Fraction | int = 0) -> None:
        seg, p, v = self._state()
        rest = seg.rest_since if v == 0 else None
        if self._mode is Mode.POSITION:
            if v == 0:  # from a standstill: cached per distance (identical to plan_position)
                pieces = self._rest_plans.plan(self.now, p, rest, self._target_abs * PSCALE)
            else:
                pieces = plan_position(self._ramp, self.now, p, v, rest, self._target_abs * PSCALE, tol)
        else:
            pieces = plan_velocity(self._ramp.amax, self.now, p, v, rest, velocity_units(self._vt_pps))
        self._queue = SegmentQueue(pieces)

    def move_to(self, target: int) -> None:
        """MVP (manual 3.6.4): positioning mode towards `target`; a distance
        beyond 2^31-1 microsteps goes the shorter way through the 32-bit wrap."""
        if type(target) is not int:
            if isinstance(target, bool) or not isinstance(target, Integral):
                raise TypeError(f"target position must be an integer, got {target!r}")
            target = int(target)
        target = ((target + (1 << 31)) & 0xFFFF_FFFF) - (1 << 31)  # wrap32
        here = self._step()
        target_abs = here + wrap32(target - here)
        if self._mode is Mode.POSITION and target_abs == self._target_abs and target == self._target:
            return
        self._mode = Mode.POSITION
        self._target, self._target_abs = target, target_abs
        self._replan()

    def rotate(self, velocity: int | float | Fraction) -> None:
        """ROR/ROL/MST (manual 3.6.1-3.6.3): velocity mode, AMAX ramps."""
        self._vt_pps = _real("velocity", velocity)
        self._mode = Mode.VELOCITY
        self._replan()

    def hold(self, velocity: int | float | Fraction) -> None:
        """AP3 written (PD86-1180 manual: actual speed RW, TMC429 hold mode;
        the PD28-1021 follows it): velocity mode at `velocity` pps at once,
        without a ramp."""
        self._vt_pps = _real("velocity", velocity)
        self._mode = Mode.VELOCITY
        seg, p, v = self._state()
        vt = velocity_units(self._vt_pps)
        if v != 0 and sign(vt) != sign(v):
            p = snap(p, sign(v))  # a run ends: keep the last whole microstep
        rest = (seg.rest_since if v == 0 else self.now) if vt == 0 else None
        self._queue = SegmentQueue([Segment(self.now, None, p, vt, 0, rest)])

    def hard_stop(self) -> None:
        here = self._step()
        self._queue = SegmentQueue([Segment(self.now, None, here * PSCALE, 0, 0, self.now)])
        self._target, self._target_abs = wrap32(here), here
        self._vt_pps = Fraction(0)

    def set_position(self, position: int) -> None:
        """AP1 overwrite: relabels the position counter. In positioning mode
        the target is relabelled with it, so the motion goes on unchanged."""
        if isinstance(position, bool) or not isinstance(position, Integral):
            raise TypeError(f"position must be an integer, got {position!r}")
        dp = wrap32(int(position)) - self.position
        if dp == 0:
            return
        self._queue.shift(dp)
        if self._mode is Mode.POSITION:
            self._target_abs += dp
            self._target = wrap32(self._target + dp)

    # --- time -----------------------------------------------------------
    def advance(self, until: int) -> None:
        if type(until) is not int:
            if isinstance(until, bool) or not isinstance(until, Integral):
                raise TypeError(f"tick must be an integer, got {until!r}")
            until = int(until)
        if until < self.now:
            raise ValueError(f"cannot go back in time: {until} < now {self.now}")
        self.now = until
        k1 = self._queue.pieces[0].k1
        if k1 is not None and k1 <= until:
            self._queue.drop_before(until)

    def next_event(self) -> int | None:
        k1 = self._queue.pieces[0].k1
        if k1 is not None and k1 > self.now:
            return k1
        return self._queue.next_boundary(self.now)

    @property
    def direction(self) -> int:
        v = self._v()
        return (v > 0) - (v < 0)

    @property
    def accelerating(self) -> bool:
        return self._queue.at(self.now).a != 0

    @property
    def plan_token(self) -> object:
        """Every command builds a new segment queue; mode and targets complete the plan."""
        return (self._queue, self._mode, self._target_abs, self._vt_pps)

    def time_at_speed(self, speed: Velocity) -> int | None:
        """First tick >= now at which |velocity| >= `speed` (pps), from the segment queue: the instant
        the speed crosses the stop-on-stall limit AP181 during an acceleration."""
        if speed <= 0:
            return None
        th = math.ceil(Fraction(speed) * V_PER_PPS)
        now = self.now
        for s in self._queue.pieces:
            if s.k1 is not None and s.k1 <= now:
                continue
            k0 = max(now, s.k0)
            if abs(s.v_at(k0)) >= th:
                return k0
            if s.a == 0:
                continue
            if s.a > 0:
                k = s.k0 - ((s.v0 - th) // s.a)           # ceil((th - v0) / a)
            else:
                k = s.k0 - ((s.v0 + th) // -s.a)          # ceil((th + v0) / -a)
            if k >= k0 and (s.k1 is None or k < s.k1):
                return k
        return None

    def time_at_position(self, position: int) -> int | None:
        """First tick >= now at which the counter reaches (or, at more than one
        microstep per tick, passes) `position`, following the 32-bit wrap."""
        return self._queue.first_tick_at(wrap32(int(position)), self.now, modulus=1 << 32)
