"""TMC429/TMC4210 ramp generator: one axis, integer exact and event-driven.

One axis of the TMC429 (three-axis, inside the PD86-1180) / TMC4210 (one axis) ramp generator,
following the TMC4210 datasheet ch. 6.1 (docs/motion-tmc429.md for the model, docs/assumptions.md
for the choices where the datasheet is silent). The rooms:

* `tmc429_arith.py`: the integer closed forms (floor sums, target velocities, level starts, the
  linear phase);
* `tmc429_state.py`: registers, state and the rules of one clock cycle;
* `tmc429_plan.py`: the coming linear phase and the cycle where it ends;
* `tmc429_follow.py`: the stretches where the ramp_mode velocity follows its computed target;
* here: `Tmc429Ramp`, the registers as the chip shows them, switch stops, and time: `advance`
  jumps over whole phases and applies each event cycle exactly, `next_event` says when the next
  one comes. The per-tick oracle in tests/motion/tmc429_reference.py defines the behaviour.
"""
from __future__ import annotations

from dataclasses import replace

from . import tmc429_follow
from .tmc429_arith import (
    A_LIMIT,
    HOLD_MODE,
    RAMP_MODE,
    SOFT_MODE,
    V_LIMIT,
    VELOCITY_MODE,
    LinearPhase,
    min_opt,
    sign,
)
from .tmc429_follow import Steps, end_bound
from .tmc429_plan import FollowPhase, LinearPlan, Plan, plan_linear
from .tmc429_state import RampState

__all__ = ["A_LIMIT", "HOLD_MODE", "RAMP_MODE", "SOFT_MODE", "V_LIMIT", "VELOCITY_MODE",
           "Tmc429Ramp", "Tmc429RegisterError", "clear_memos"]

_REGISTERS = ("x_target", "x_actual", "v_min", "v_max", "v_target", "v_actual", "a_max",
              "pmul", "pdiv", "pulse_div", "ramp_div", "mode")
_RANGES = {"v_target": (-V_LIMIT, V_LIMIT), "v_actual": (-V_LIMIT, V_LIMIT), "v_min": (0, V_LIMIT),
           "v_max": (0, V_LIMIT), "a_max": (0, A_LIMIT), "pmul": (0, 255), "pdiv": (0, 15),
           "pulse_div": (0, 15), "ramp_div": (0, 15), "mode": (0, 3)}

NEAR_END = 1 << 20
"""next_event walks a follow stretch to its end once the end may be this few cycles away
(65 ms at 16 MHz); farther ends are reported as a cycle surely before them
(`tmc429_follow.end_bound`), docs/motion-tmc429.md "Events of a stretch"."""
NEAR_SPAN = 4 * NEAR_END
"""How far that walk goes at most; a longer stretch is reported at the cycle it reached."""
MEMO_SIZE = 4096
FollowRel = tuple[int, tuple[int, int, int, bool] | None]
"""A follow stretch relative to now: (event - now, (cycle - now, units added, |v|, moved) of
the state just before the event, or None when not walked)."""
_PLANS: dict[tuple, tuple[int, LinearPlan | None, FollowRel | None]] = {}


def clear_memos() -> None:
    """Forget the memoised plans and follow stretches (benchmarks, cost tests)."""
    _PLANS.clear()
    tmc429_follow.clear_memo()


class Tmc429RegisterError(ValueError):
    """A register name that does not exist or a value outside its range."""


class Tmc429Ramp:
    """One axis of the TMC429/TMC4210 ramp generator, integer exact, event-driven.

    Time `now` counts clock cycles of the chip clock (f_CLK), from 0.
    Registers are read as attributes and written with `set()`.
    """

    def __init__(self, *, position_bits: int = 24) -> None:
        if not 2 <= position_bits <= 64:
            raise Tmc429RegisterError(f"position_bits {position_bits} out of range 2..64")
        self.position_bits = position_bits
        self._st = RampState(1 << position_bits)
        self._plan: Plan | None = None     # next_event's plan of the state at its phase's t0
        self._base: tuple[LinearPhase, int, int, int, int] | None = None
        """(phase, x, acc, acc_dir, v) at the t0 of the cached linear phase `_jump_within` moved in."""

    # ------------------------------------------------------------------ registers
    @property
    def now(self) -> int:
        return self._st.now

    @property
    def x_target(self) -> int:
        """X_TARGET, unsigned `position_bits` wide (6.1.1)."""
        return self._st.xt

    @property
    def x_actual(self) -> int:
        """X_ACTUAL, unsigned `position_bits` wide (6.1.2)."""
        return self._st.x

    @property
    def v_min(self) -> int:
        return self._st.v_min

    @property
    def v_max(self) -> int:
        return self._st.v_max

    @property
    def v_target(self) -> int:
        """V_TARGET (6.1.5): the written value in velocity_mode and hold_mode, the chip-computed
        target velocity in ramp_mode and soft_mode."""
        st = self._st
        if st.mode in (VELOCITY_MODE, HOLD_MODE):
            return st.v_target
        dx = st.dx()
        if dx == 0:
            return 0
        return st.position_target(sign(dx), abs(dx)) // 256

    @property
    def v_actual(self) -> int:
        """V_ACTUAL (6.1.6): the 11 integer bits of the velocity with its sign."""
        v = self._st.v
        return sign(v) * (abs(v) >> 8)

    @property
    def v_internal(self) -> int:
        """The velocity with its 8 hidden fractional bits (V_ACTUAL * 256 + fraction)."""
        return self._st.v

    @property
    def pulse_accumulator(self) -> tuple[int, int]:
        """(the 11-bit pulse accumulator, the direction it counts in; 0 before any motion),
        6.1.12.1. Not a chip register: for tests and traces."""
        return self._st.acc, self._st.acc_dir

    @property
    def a_max(self) -> int:
        return self._st.a_max

    @property
    def a_actual(self) -> int:
        """A_ACTUAL (6.1.8), unsmoothed and signed (2.4): +A_MAX while the next ramp tick raises
        |velocity|, -A_MAX while it lowers it, else 0."""
        st = self._st
        if st.mode == HOLD_MODE or st.a_max == 0:
            return 0
        probe = replace(st)
        probe.ramp_tick()
        return sign(abs(probe.v) - abs(st.v)) * st.a_max

    @property
    def pmul(self) -> int:
        return self._st.pmul

    @property
    def pdiv(self) -> int:
        return self._st.pdiv

    @property
    def pulse_div(self) -> int:
        return self._st.pulse_div

    @property
    def ramp_div(self) -> int:
        return self._st.ramp_div

    @property
    def mode(self) -> int:
        return self._st.mode

    @property
    def dx(self) -> int:
        """X_TARGET - X_ACTUAL as a signed `position_bits` number (6.1.1: |dx| < 2^23)."""
        return self._st.dx()

    @property
    def stopping(self) -> bool:
        """A soft switch stop (`stop(soft=True)`) is in progress."""
        return self._st.stopping

    @property
    def position_reached(self) -> bool:
        """X_ACTUAL == X_TARGET in ramp_mode or soft_mode with the motor stopped."""
        st = self._st
        return st.mode in (RAMP_MODE, SOFT_MODE) and st.x == st.xt and st.v == 0

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
        self._plan = None
        st = self._st
        for name, value in checked.items():
            if name == "x_target":
                st.xt = value % st.modulus
                st.stopping = False
            elif name == "x_actual":
                st.x = value % st.modulus
            elif name == "v_actual":
                if st.mode == HOLD_MODE:
                    st.v = value * 256
                    st.stopping = False
            elif name == "pmul":
                st.pmul = value | 0x80
            else:                   # v_min, v_max, v_target, a_max, pdiv, pulse_div, ramp_div, mode
                setattr(st, name, value)
                if name in ("v_target", "mode"):
                    st.stopping = False

    def _check(self, name: str, value: int) -> int:
        if name not in _REGISTERS:
            raise Tmc429RegisterError(f"unknown TMC429 register {name!r}")
        if isinstance(value, bool) or not isinstance(value, int):
            raise Tmc429RegisterError(f"{name} must be an integer, not {value!r}")
        lo, hi = _RANGES.get(name, (-self._st.half, self._st.modulus - 1))
        if not lo <= value <= hi:
            raise Tmc429RegisterError(f"{name}={value} out of range {lo}..{hi}")
        return value

    # ------------------------------------------------------------------ stops
    def stop(self, *, soft: bool) -> None:
        """Switch stop (6.1.10.2): hard sets V_ACTUAL to 0 at once; soft decelerates
        with A_MAX to 0. At standstill X_TARGET := X_ACTUAL (ramp/soft_mode) or
        V_TARGET := 0 (velocity_mode), so the motor stays. hold_mode stops hard."""
        self._plan = None
        st = self._st
        if soft and st.mode != HOLD_MODE:
            st.stopping = True
            return
        st.v = 0
        st.stopping = False
        st.after_stop()

    def _cycle(self, c: int) -> int:
        """Apply cycle c = now + 1 exactly; return the step made (-1, 0, +1)."""
        self._plan = None
        return self._st.cycle(c)

    # ------------------------------------------------------------------ planning
    def _plan_for(self, until: int | None) -> Plan:
        """The coming phase, looked at up to `until`; a follow stretch is walked on demand."""
        plan = plan_linear(self._st, until)
        return (None, None, FollowPhase(self._st.now)) if plan is None else plan

    def _next_plan(self) -> Plan:
        """The plan of next_event, memoised by the whole state relative to now (the registers,
        dx, the velocity, the accumulator and the phase of the tick clocks), so that a repeated
        move costs O(1) per phase: a linear plan, or a follow stretch as `_follow_event` gives it."""
        st = self._st
        key = (st.dx(), st.v, st.acc, st.acc_dir, st.stopping, st.mode,
               st.now % (32 << max(st.ramp_div, st.pulse_div)), st.v_min, st.v_max, st.v_target,
               st.a_max, st.pmul, st.pdiv, st.pulse_div, st.ramp_div, st.modulus)
        hit = _PLANS.get(key)
        if hit is None:
            plan = plan_linear(st, None)
            rel = self._follow_event() if plan is None else None
            if len(_PLANS) >= MEMO_SIZE:
                _PLANS.clear()
            _PLANS[key] = (st.now, plan, rel)
            shift = 0
        else:
            now0, plan, rel = hit
            shift = st.now - now0
        if plan is None:
            assert rel is not None
            return self._follow_phase(rel)
        return _shifted(plan, shift) if shift else plan

    def _follow_event(self) -> FollowRel:
        """A follow stretch for next_event, relative to now: (event - now, None) with the event a
        cycle surely before its end (`end_bound`) when that may be more than NEAR_END cycles away,
        else (event - now, (cycle - now, units added, |v|, moved)) for the state just before
        its end, walked (or before the cycle NEAR_SPAN on, if it goes on longer)."""
        st = self._st
        _s, units = self._towards()
        regs = st.follow_registers()
        w = abs(st.v)
        bound = end_bound(regs, st.now, w, units)
        if bound - st.now > NEAR_END:
            return bound - st.now, None
        t, w_end, total, moved, event = tmc429_follow.walk(regs, st.now, w, units,
                                                           st.now + NEAR_SPAN)
        return event - st.now, (t - st.now, total, w_end, moved)

    def _follow_phase(self, rel: FollowRel) -> Plan:
        """The plan of a follow stretch from `_follow_event`'s answer, at now."""
        st = self._st
        offset, walked = rel
        if walked is None:
            return st.now + offset, None, FollowPhase(st.now, st.now + offset)
        dt, total, w_end, moved = walked
        s, _units = self._towards()
        end = st.settled(st.now + dt, st.made(s) + total, s * w_end, s, moved)
        return st.now + offset, None, FollowPhase(st.now, st.now + offset, end)

    def _towards(self) -> tuple[int, int]:
        """(direction of the target, accumulator units before the arrival step)."""
        dx = self._st.dx()
        s = sign(dx)
        return s, self._st.remaining(s, abs(dx))

    # ------------------------------------------------------------------ following the target
    def _follow(self, limit: int, steps: Steps | None = None) -> int:
        """Walk the follow stretch from now up to `limit`, or just before its arrival step, or
        through the tick that reaches V_MIN (or 0); return the cycle to apply exactly next.
        `steps` collects (cycle, direction) of each step made."""
        st = self._st
        s, units = self._towards()
        t, w, total, moved, event = tmc429_follow.walk(st.follow_registers(), st.now, abs(st.v),
                                                       units, limit, steps, st.made(s), s)
        st.settle(t, st.made(s) + total, s * w, s, moved)
        return event

    def _follow_to(self, phase: FollowPhase, stop: int, steps: Steps | None = None) -> int:
        """`_follow` up to `stop` inside `phase`; a walked end is taken over as it is."""
        end = phase.end
        if end is not None and end[0] == stop and steps is None:
            st = self._st
            st.now, st.x, st.acc, st.acc_dir, st.v = end
            return phase.event if phase.event is not None else stop + 1
        return self._follow(stop, steps)

    # ------------------------------------------------------------------ time
    def _jump(self, phase: LinearPhase, t: int) -> None:
        """Move the state to cycle t inside the linear `phase` (closed form)."""
        if t <= self._st.now:
            return
        self._plan = None
        base = self._base
        st = self._st
        if base is not None and base[0] is phase:   # moved on by `_jump_within`: back to t0
            _phase, st.x, st.acc, st.acc_dir, st.v = base
        self._place(phase, t, st.x, st.acc, st.acc_dir, st.v)

    def _jump_within(self, phase: LinearPhase, t: int) -> None:
        """`_jump` inside the linear phase of the cached plan, keeping the plan: the phase is the
        closed form of the motion from its t0 up to its event, read at any cycle, so the state is
        evaluated from the state at t0 (`_base`, kept on the first such jump) and the next advance
        or next_event needs no planning (docs/motion-tmc429.md "Lazy reads")."""
        if t <= self._st.now:
            return
        base = self._base
        if base is None or base[0] is not phase:    # the state is still at t0
            st = self._st
            base = self._base = (phase, st.x, st.acc, st.acc_dir, st.v)
        _phase, x, acc, acc_dir, v = base
        self._place(phase, t, x, acc, acc_dir, v)

    def _place(self, phase: LinearPhase, t: int, x: int, acc: int, acc_dir: int, v: int) -> None:
        """The state at cycle t of `phase`, from (x, acc, acc_dir, v) at its t0."""
        st = self._st
        total, w = phase.at(t)
        if total is not None:
            steps, acc = total >> 11, total & 2047
            x = (x + phase.direction * steps) % st.modulus
            if phase.direction:
                acc_dir = phase.direction
        if phase.delta != 0:
            v = phase.direction * w
        st.x, st.acc, st.acc_dir, st.v = x, acc, acc_dir, v
        st.now = t

    def advance(self, until: int) -> None:
        """Jump to cycle `until` (>= now), exactly as the per-tick model would."""
        if until < self._st.now:
            raise ValueError(f"cannot go back in time: until={until} < now={self._st.now}")
        while self._st.now < until:
            cached = self._plan
            event, _clamp, phase = cached if cached is not None else self._plan_for(until)
            if isinstance(phase, FollowPhase):
                event = self._follow_to(phase, until if event is None or event > until else event - 1)
                if event > until:
                    return                          # inside the stretch: a cached plan stays
            elif event is None or event > until:
                if cached is not None:
                    self._jump_within(phase, until)
                else:
                    self._jump(phase, until)
                return
            else:
                self._jump(phase, event - 1)
            self._cycle(event)

    def next_event(self) -> int | None:
        """Next cycle where the ramp phase changes, the target is reached, or (inside a long
        stretch following the computed target) a cycle surely before its end (None: nothing
        changes without a new register write)."""
        if self._plan is None:
            self._plan = self._next_plan()
            self._base = None
        event, clamp, _phase = self._plan
        return min_opt(event, clamp)

    def step_events(self, until: int) -> list[tuple[int, int]]:
        """(cycle, +1 or -1) of each step on cycles now+1 .. until; advances to until."""
        if until < self._st.now:
            raise ValueError(f"cannot go back in time: until={until} < now={self._st.now}")
        out: list[tuple[int, int]] = []
        if self._plan is not None and self._plan[2].t0 != self._st.now:
            self._plan = None    # a linear phase lists its steps from t0: re-plan from now
        while self._st.now < until:
            event = self._steps_to(until, out)
            if event > until:
                break
            step = self._cycle(event)
            if step:
                out.append((event, step))
        return out

    def _steps_to(self, until: int, out: Steps) -> int:
        """Go through the coming phase up to `until` or its event, listing its steps in `out`;
        return the event (> until: none by then)."""
        event, _clamp, phase = self._plan if self._plan is not None else self._plan_for(until)
        end = until if event is None or event > until else event - 1
        if isinstance(phase, FollowPhase):
            return self._follow_to(phase, end, out)
        if end > self._st.now:
            out.extend((t, phase.direction) for t in phase.step_cycles(end))
        self._jump(phase, end)
        return until + 1 if event is None or end == until else event

    def time_at_position(self, position: int, *, max_phases: int = 1000) -> int | None:
        """First cycle >= now where X_ACTUAL == position if nothing is written, else None.

        Looks ahead at most `max_phases` phases as next_event reports them (a ramp_mode move has
        about four, and a long stretch following the computed target a few more); None then
        also means "not within that horizon" (only misconfigured ramps, e.g. V_MIN = 0 hopping
        towards a target, need more), so callers that re-plan at every next_event() see every
        pass.
        """
        target = position % self._st.modulus
        if self._st.x == target:
            return self._st.now
        probe = self.copy()
        probe._plan = None
        for _ in range(max_phases):
            event, _clamp, phase = probe._next_plan()
            found = probe._pass(phase, event, target)
            if found is not None:
                return found
            if event is None:
                return None
            if isinstance(phase, LinearPhase):
                probe._jump(phase, event - 1)
            probe._cycle(event)
            if probe._st.x == target:
                return probe._st.now
        return None

    def _pass(self, phase: LinearPhase | FollowPhase, event: int | None, target: int) -> int | None:
        """The cycle before `event` at which X_ACTUAL first equals `target` in `phase`; a follow
        stretch is walked up to there on the way."""
        st = self._st
        if isinstance(phase, FollowPhase):
            if event is None:
                raise AssertionError("a follow stretch always ends")
            steps: Steps = []
            s = sign(st.dx())
            x0 = st.x
            self._follow(event - 1, steps)
            need = (target - x0) * s % st.modulus
            return steps[need - 1][0] if 0 < need <= len(steps) else None
        if phase.direction == 0:
            return None
        need = (target - st.x) * phase.direction % st.modulus
        end = None if event is None else event - 1
        if end is None or end > st.now:
            return phase.nth_step_cycle(need, end)
        return None

    def copy(self) -> Tmc429Ramp:
        clone = Tmc429Ramp.__new__(Tmc429Ramp)
        clone.position_bits = self.position_bits
        clone._st = replace(self._st)
        clone._plan = self._plan
        clone._base = self._base
        return clone


def _shifted(plan: LinearPlan, shift: int) -> LinearPlan:
    """A memoised linear plan moved `shift` cycles later (a multiple of both tick periods)."""
    event, clamp, phase = plan
    return (None if event is None else event + shift, None if clamp is None else clamp + shift,
            phase.shifted(shift))
