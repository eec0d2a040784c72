"""The coming ramp phase of a TMC429/TMC4210 axis and its end, in closed form (datasheet 6.1).

From a `RampState` the ramp target is fixed until something changes, so the velocity moves by
A_MAX per ramp tick towards it (or stays) and the steps are a floor-sum (`LinearPhase`). The phase
ends at the first of: the ramp reaching its target or changing sign, the release of a soft stop,
the stop at the target at or below V_MIN (6.1.3), the step after which the target changes (the
arrival, a new soft_mode speed, the far side of the position range) and, in ramp_mode, the first
ramp tick where the computed target V_TARGET binds (6.1.9); from there the velocity follows it
(`motion/tmc429_follow.py`). `plan_linear` returns the phase and that cycle.
"""
from __future__ import annotations

from dataclasses import dataclass
from math import sqrt

from .tmc429_arith import (
    HOLD_MODE,
    RAMP_MODE,
    SOFT_MODE,
    VELOCITY_MODE,
    LinearPhase,
    ceil_div,
    first_true,
    min_opt,
    sign,
)
from .tmc429_state import RampState


@dataclass(slots=True)
class FollowPhase:
    """A stretch where the ramp_mode velocity follows its computed target, from cycle t0.

    `event` is the cycle to apply exactly next: the stretch's end or a cycle at or before it
    (None: as far as asked). `end` is the state just before `event`, (cycle, X_ACTUAL, acc,
    acc_dir, velocity), when the stretch was walked that far."""

    t0: int
    event: int | None = None
    end: tuple[int, int, int, int, int] | None = None


Plan = tuple[int | None, int | None, LinearPhase | FollowPhase]
"""(event, clamp, phase): the first cycle > now to apply exactly (None: none ever) and the cycle
where the ramp reaches its target (reported by next_event, also exact)."""
LinearPlan = tuple[int | None, int | None, LinearPhase]


def ramp_target(st: RampState) -> tuple[int | None, bool]:
    """Target velocity (1/256 units) of a linear phase from now and whether the ramp_mode
    target may bind during it; None when dx == 0 in ramp/soft_mode."""
    v = st.v
    if st.mode == HOLD_MODE:
        return v, False
    if st.stopping:
        return 0, False
    if st.mode == VELOCITY_MODE:
        return st.velocity_mode_target(), False
    dx = st.dx()
    if dx == 0:
        return None, False
    s, d = sign(dx), abs(dx)
    if st.mode == SOFT_MODE:
        return st.position_target(s, d), False
    speed = st.speed(st.remaining(s, d))
    if v * s < 0:            # heading away: +-A_MAX per tick until the sign changes
        return s * speed * 256, False
    floor = min(st.v_min, st.v_max)
    if speed == floor and abs(v) == floor * 256:
        return s * floor * 256, False    # at V_MIN: the target cannot fall further
    return s * st.v_max * 256, True


def linear_phase(st: RampState, vt: int) -> LinearPhase:
    """The phase from now in which |v| moves by A_MAX per ramp tick towards `vt` (or stays, in
    hold_mode, at A_MAX = 0 or on the target), 6.1.9.2."""
    rp, pp = 32 << st.ramp_div, 32 << st.pulse_div
    v0 = st.v
    ramping = st.a_max > 0 and v0 != vt and st.mode != HOLD_MODE
    direction = sign(v0) if v0 != 0 else (sign(vt) if ramping else 0)
    w0 = abs(v0)
    delta = _delta(st.a_max, ramping, direction, vt, w0)
    j0, i0 = st.now // rp, st.now // pp
    acc0, i_dir = st.acc, i0 + 1
    if direction != 0 and direction != st.acc_dir:
        if st.acc_dir:
            acc0 = 2047 - acc0
        if v0 == 0:                     # v turns non-zero at the next ramp tick
            i_dir = ceil_div((j0 + 1) * rp, pp)
    return LinearPhase(st.now, rp, pp, j0, i0, w0, delta, direction, acc0, i_dir)


def _delta(a: int, ramping: bool, direction: int, vt: int, w0: int) -> int:
    """Change of |v| per ramp tick: +A_MAX towards a higher |vt| in the same direction,
    -A_MAX otherwise, 0 without a ramp."""
    if not ramping:
        return 0
    return a if sign(vt) == direction and abs(vt) > w0 else -a


def plan_linear(st: RampState, until: int | None) -> LinearPlan | None:
    """The linear phase from now and its end (looked for up to `until`), or None when the
    computed ramp_mode target binds at the next ramp tick (a follow stretch starts)."""
    target, binds = ramp_target(st)
    dx_zero = target is None
    vt = 0 if target is None else target
    phase = linear_phase(st, vt)
    binds = binds and phase.direction != 0
    units0 = 0
    if binds:
        dx = st.dx()
        units0 = st.remaining(sign(dx), abs(dx))
        if _fires(st, phase, units0, phase.j0 + 1):
            return None
    first_ramp, clamp = _ramp_events(st, phase, vt, dx_zero)
    bound = min_opt(until, None if first_ramp is None else first_ramp - 1)
    step_event = _step_event(st, phase, dx_zero, bound)
    trig = None
    if binds:
        bound2 = min_opt(bound, None if step_event is None else step_event - 1)
        trig = _find_trigger(st, phase, units0, bound2)
    return min_opt(min_opt(first_ramp, step_event), trig), clamp, phase


def _ramp_events(st: RampState, phase: LinearPhase, vt: int,
                 dx_zero: bool) -> tuple[int | None, int | None]:
    """(first ramp tick that changes the phase, clamp): the tick where |v| reaches `vt` or
    changes sign, the release of a soft stop at standstill (6.1.10.2) and the stop at the target
    once |v| <= V_MIN (6.1.3)."""
    rp, j0, w0 = phase.ramp_period, phase.j0, phase.w0
    clamp = _clamp(st, phase, vt)
    events = [] if clamp is None else [clamp]
    if st.stopping and st.mode != HOLD_MODE and w0 == 0:
        events.append((j0 + 1) * rp)                          # release at once
    if dx_zero and not st.stopping and st.mode in (RAMP_MODE, SOFT_MODE):
        stop = _stop_at_target(st, phase)
        if stop is not None:
            events.append(stop)
    return (min(events) if events else None), clamp


def _clamp(st: RampState, phase: LinearPhase, vt: int) -> int | None:
    """The ramp tick where a ramping |v| reaches `vt` (or 0, or changes sign)."""
    if phase.delta == 0:
        return None
    if sign(vt) == phase.direction or vt == 0:
        k_end = ceil_div(abs(abs(vt) - phase.w0), st.a_max)   # reaches vt (or 0)
    else:
        k_end = ceil_div(phase.w0, st.a_max)                  # changes sign
    return (phase.j0 + k_end) * phase.ramp_period


def _stop_at_target(st: RampState, phase: LinearPhase) -> int | None:
    """At the target: the ramp tick that stops the motor once |v| <= V_MIN * 256 (6.1.3)."""
    limit, w0, j0 = st.v_min * 256, phase.w0, phase.j0
    if w0 <= limit:
        return (j0 + 1) * phase.ramp_period if w0 != 0 else None
    if st.a_max > 0:
        return (j0 + ceil_div(w0 - limit, st.a_max) + 1) * phase.ramp_period
    return None


def _step_event(st: RampState, phase: LinearPhase, dx_zero: bool, bound: int | None) -> int | None:
    """Cycle of the step, by `bound`, after which the ramp target changes or the motor stops
    (`_step_limit`); None: none by then."""
    n_steps = _step_limit(st, phase.direction, dx_zero)
    if n_steps is None or phase.direction == 0:
        return None
    if bound is None and phase.delta != 0:
        raise AssertionError("ramping phase without end")
    return phase.nth_step_cycle(n_steps, bound)


def _step_limit(st: RampState, direction: int, dx_zero: bool) -> int | None:
    """Number of steps after which the ramp target may change (None: never)."""
    if st.mode not in (RAMP_MODE, SOFT_MODE) or direction == 0:
        return None
    if dx_zero:
        return 1
    if st.stopping:          # only the stop at the target matters now
        return (st.xt - st.x) * direction % st.modulus or st.modulus
    dx = st.dx()
    s, d = sign(dx), abs(dx)
    if direction == s:                                     # towards the target: arrival
        return min(d, d - _soft_first(st, d) + 1) if st.mode == SOFT_MODE else d
    return _away_limit(st, s, d)


def _away_limit(st: RampState, s: int, d: int) -> int:
    """Steps away from a target d steps off in direction s until dx wraps to the other sign (or,
    in soft_mode, until the speed for the growing distance changes)."""
    flip = st.half - d + (1 if s < 0 else 0)
    if st.mode == SOFT_MODE and st.soft_speed(d) < st.v_max:
        return min(flip, _soft_last(st, d, d + flip) - d + 1)
    return flip


def _soft_first(st: RampState, d: int) -> int:
    """Smallest d' in 1..d with the soft_mode speed of d."""
    speed = st.soft_speed(d)
    lo, hi = 1, d
    while lo < hi:
        mid = (lo + hi) // 2
        if st.soft_speed(mid) == speed:
            hi = mid
        else:
            lo = mid + 1
    return lo


def _soft_last(st: RampState, d: int, hi: int) -> int:
    """Largest d' in d..hi with the soft_mode speed of d."""
    speed = st.soft_speed(d)
    lo = d
    while lo < hi:
        mid = (lo + hi + 1) // 2
        if st.soft_speed(mid) == speed:
            lo = mid
        else:
            hi = mid - 1
    return lo


def _fires(st: RampState, ph: LinearPhase, units0: int, j: int) -> bool:
    """ramp_mode: does ramp tick j of the linear phase `ph` (towards V_MAX) see a computed target
    that binds, i.e. gives another velocity than the phase?"""
    units = units0 - ph.pulse_sum((j * ph.ramp_period - 1) // ph.pulse_period)
    if units <= 0:                  # arrives before tick j: the step event comes first
        return False
    speed = st.speed(units)
    if ph.delta > 0:
        return speed * 256 < min(st.v_max * 256, ph.w(j - 1 - ph.j0) + st.a_max)
    return speed < st.v_max


def _trigger_guess(st: RampState, ph: LinearPhase, units0: int) -> int | None:
    """Where `_find_trigger` starts looking in a ramping phase: the ramp tick where |v| + A_MAX
    meets 256 sqrt(p' U) (less half a level for the square root's floor), |v| and U taken as
    continuous as in `LinearPhase._pulse_guess`; a float estimate only."""
    rp, pp = ph.ramp_period, ph.pulse_period
    c1, (u0, b) = ph.smooth_start()
    k = 65536.0 * st.pmul / (1 << (3 + st.pdiv))
    alpha = ph.delta / rp
    beta = ph.w0 + st.a_max + 128
    qa = alpha * alpha + k * alpha / (512 * pp)
    qb = 2 * alpha * beta + k * b / (256 * pp)
    disc = qb * qb - 4 * qa * (beta * beta - k * (units0 - u0))
    if qa <= 0 or disc < 0:
        return None
    return int((c1 + (sqrt(disc) - qb) / (2 * qa)) // rp)


def _find_trigger(st: RampState, ph: LinearPhase, units0: int, t_hi: int | None) -> int | None:
    """First ramp tick (cycle) of `ph` at which the computed ramp_mode target binds (monotone:
    the remaining distance only falls, the velocity only rises)."""
    rp, pp = ph.ramp_period, ph.pulse_period
    j_lo = ph.j0 + 1
    if ph.delta != 0:
        if t_hi is None:               # a ramping phase always ends at its clamp
            raise AssertionError("unbounded trigger search in a ramping phase")
        return first_true(lambda j: _fires(st, ph, units0, j), j_lo, t_hi // rp, rp,
                          _trigger_guess(st, ph, units0))
    # |v| = V_MAX * 256 held: binds once units < level_start(V_MAX)
    u = ph.w0 >> 8
    if u == 0 or st.v_max == 0:
        return None
    need = units0 - ceil_div(st.v_max * st.v_max << (3 + st.pdiv), st.pmul) + 1
    if need <= 0:
        j = j_lo
    else:
        i = ph.i0 + ceil_div(need, u)
        if t_hi is not None and i * pp > t_hi:
            return None
        j = max(j_lo, i * pp // rp + 1)
    if t_hi is not None and j * rp > t_hi:
        return None
    return j * rp
