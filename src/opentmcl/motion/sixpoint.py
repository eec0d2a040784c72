"""Six-point ramp of the TMC5130 (TMCM-6212: one TMC5130 per axis).

TMCM-6212 firmware manual 4.1, axis parameters 4, 5 and 15-21; TMC5130
datasheet (docs/motion.md). In positioning mode the motor starts at VSTART, accelerates with
A1 up to V1 and with AMAX up to VMAX, decelerates with DMAX down to V1 and
with D1 down to VSTOP, then stops on the target; V1 = 0 disables the A1/D1
phases. Before a move starts (and before a reversal) the motor rests for the
ramp wait time (AP21, TZEROWAIT, units of 512 clocks), in velocity mode too
(manual 4.1 AP21: "before next movement or direction inversion can start"). In
velocity mode it accelerates and decelerates with AMAX only (manual 4.1: A1, V1,
D1, VSTART and VSTOP are "in position mode only").

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
from fractions import Fraction
from numbers import Integral

from .base import CLOCK_HZ, Mode, RampEngine, Velocity
from .segments import DEN, PSCALE, V_PER_PPS, Segment, SegmentQueue, sign, snap
from .sixpoint_plan import (  # noqa: F401  (the planner's names, as they were imported from here)
    TZEROWAIT_CLOCKS,
    PlanInvariantError,
    Ramp,
    RampParameterError,
    RestPlans,
    acceleration_units,
    plan_position,
    plan_velocity,
    real_parameter,
    velocity_units,
    wrap32,
)

_STEP_UNITS = DEN // CLOCK_HZ
"""Velocity units (DEN per tick) per pps: a whole number, so a velocity in pps is one division."""
assert _STEP_UNITS * CLOCK_HZ == DEN


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
            x = real_parameter(name, value)
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
        read at a tick evaluates the piece holding it (`Segment.state`) and keeps step counter,
        wrapped position and velocity for that tick and plan, so further reads at the same tick
        are two comparisons and a field access. The key is the tick and the queue's piece list,
        which every command and AP1 overwrite replace (`advance` only drops pieces that ended)."""
        now = self.now
        queue = self._queue
        pieces = queue.pieces
        seg = pieces[0]
        k1 = seg.k1
        if k1 is not None and k1 <= now:
            seg = queue.at(now)
        q, v = seg.state(now)
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
        if self._read_at != self.now or self._read_pieces is not self._queue.pieces:
            self._read()
        v = self._read_v  # v * CLOCK_HZ / DEN = v / _STEP_UNITS, truncated towards zero
        return v // _STEP_UNITS if v >= 0 else -((-v) // _STEP_UNITS)

    @property
    def moving(self) -> bool:
        if self._read_at != self.now or self._read_pieces is not self._queue.pieces:
            self._read()
        return self._read_v != 0

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
            pieces = plan_velocity(self._ramp.amax, self.now, p, v, rest, velocity_units(self._vt_pps),
                                   self._ramp.wait)
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
        self._vt_pps = real_parameter("velocity", velocity)
        self._mode = Mode.VELOCITY
        self._replan()

    def hold(self, velocity: int | float | Fraction) -> None:
        """AP3 written (PD86-1180 manual: actual speed RW, TMC429 hold mode;
        the PD28-1021 follows it): velocity mode at `velocity` pps at once,
        without a ramp."""
        self._vt_pps = real_parameter("velocity", velocity)
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
        if self._read_at != self.now or self._read_pieces is not self._queue.pieces:
            self._read()
        v = self._read_v
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
