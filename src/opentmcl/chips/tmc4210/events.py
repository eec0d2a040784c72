"""What the TMC4210 watches while time passes (datasheet 6.1.10.2, 6.1.11, 6.1.13, 6.1.14, 6.2.1.2, 7).

A mixin of `TMC4210`: after every register write, pin change and jump of virtual time the chip
compares its present state with the last one seen and raises the events the datasheet
names - switch edges, automatic stops, arrival, position compare, reference checks, the
position latch - and it plans the next jump so that no such event is jumped over.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

from . import registers as R

if TYPE_CHECKING:
    from ...motion.tmc429 import Tmc429Ramp
    from .stepdir import StepDirOutput

POS_BITS = 24
POS_MOD = 1 << POS_BITS
HOLD_MODE = 3
VELOCITY_MODE = 2


Observation = dict[str, int]
"""What `_observe` saw: the position ("x", "xt") and the conditions whose change raises an
event ("xeq", "comp", "zero", "ref_active", "ref_out", "tol", "ref_l", "ref_r": 0/1 or bool)."""


def s24(value: int) -> int:
    return R.to_signed(value, POS_BITS)


class ChipEvents:
    """Switches, interrupts, latch and the event-driven time loop of the TMC4210 model."""

    # The chip state this mixin works on; TMC4210 (chip.py) sets it in __init__ and reset().
    _ramp: Tmc429Ramp
    stepdir: StepDirOutput
    ref_conf: int           # REF_CONF (6.1.10.2)
    lp: int                 # position latch armed (6.1.14)
    int_mask: int           # INTERRUPT_MASK (6.1.11)
    int_flags: int          # INTERRUPT_FLAGS (6.1.11)
    dx_ref_tolerance: int   # DX_REF_TOLERANCE (6.1.13)
    x_latched: int          # X_LATCHED (6.1.14)
    pos_comp: int           # POS_COMP_4210 (6.2.1.1)
    pos_comp_m: int         # POS_COMP_INT_4210 mask and flag (6.2.1.2)
    pos_comp_i: int
    mot1r: int              # STEPPER MOTOR GLOBAL PARAMETER register bit (6.2.2)
    powered_down: bool      # POWER_DOWN (6.2.1.3)
    _windows: dict[str, list[tuple[int, int]]]  # switch windows per pin, in axis positions
    _axis_offset: int       # axis position = X_ACTUAL + _axis_offset
    _ext: int               # external time in CLK cycles
    _offset: int            # _ext - ramp time
    _seen: Observation
    _stopping: bool         # a soft stop at a switch is running

    if TYPE_CHECKING:  # defined by TMC4210 (chip.py)
        @property
        def x_actual(self) -> int: ...

        @property
        def x_target(self) -> int: ...

        def _active(self, pin: str) -> bool: ...

    def _ref_pin(self) -> str | None:
        """The reference switch chosen by ref_RnL (6.1.10.2)."""
        if self.ref_conf >> 3 & 1:
            return "ref_r" if self.mot1r else None
        return "ref_l"

    def _in_tolerance(self, x: int) -> bool:
        """Inside the DX_REF_TOLERANCE range around the origin (6.1.13)."""
        return abs(x) < self.dx_ref_tolerance

    def _observe(self) -> Observation:
        x = self.x_actual
        ref = self._ref_pin()
        ref_active = ref is not None and self._active(ref)
        return {
            "x": x,
            "ref_active": ref_active,
            "ref_out": ref_active and not self._in_tolerance(x),
            "xt": self.x_target,
            "xeq": x == self.x_target,
            "comp": x == self.pos_comp,
            "zero": x == 0,
            "tol": self._in_tolerance(x),
            "ref_l": self._active("ref_l"),
            "ref_r": self._active("ref_r") and bool(self.mot1r),
        }

    def _flag(self, name: str) -> None:
        bit = R.INT_BIT[name]
        if self.int_mask & bit:  # 6.1.11: flags are forced to 0 while masked
            self.int_flags |= bit

    def _blocked(self) -> set[int]:
        """Directions in which a stop switch forbids motion now (6.1.10.2, 6.1.13)."""
        out: set[int] = set()
        if self._in_tolerance(self.x_actual):
            return out
        if not self.ref_conf & 1 and self._active("ref_l"):
            out.add(-1)
        if self.mot1r and not self.ref_conf >> 1 & 1 and self._active("ref_r"):
            out.add(1)
        return out

    def _wanted_direction(self) -> int:
        r = self._ramp
        if r.v_internal:  # moving, or a velocity below one (6.1.6) still ramping
            return 1 if r.v_internal > 0 else -1
        if r.mode in (0, 1):
            dx = s24(r.x_target - r.x_actual)
            return (dx > 0) - (dx < 0)
        if r.mode == VELOCITY_MODE:
            return (r.v_target > 0) - (r.v_target < 0)
        return 0

    def _frozen(self) -> bool:
        """Held at a stop switch: velocity 0 and the ramp would move into the switch."""
        return self._ramp.v_internal == 0 and self._wanted_direction() in self._blocked()

    def _evaluate(self) -> None:
        """Compare the present state with the last one seen and raise the chip's events."""
        old, new = self._seen, self._observe()
        self._arrival_events(old, new)
        self._switch_events(old, new)
        self._seen = new
        self._automatic_stop()

    def _arrival_events(self, old: Observation, new: Observation) -> None:
        """Events of a motion onto a position: X_TARGET (pos_end, 6.1.11), POS_COMP_4210
        (6.2.1.2), the origin while the reference switch is off (ref_miss, 6.1.11). A register
        write that makes the position equal is no arrival: the position itself must change."""
        if new["x"] == old["x"]:
            return
        if new["xeq"] and not old["xeq"] and new["xt"] == old["xt"]:
            self._flag("pos_end")  # motion reached X_TARGET (not a switch stop moving X_TARGET)
        if new["comp"] and not old["comp"] and self.pos_comp_m:
            self.pos_comp_i = 1
        if new["zero"] and not old["zero"] and not new["ref_active"]:
            self._flag("ref_miss")

    def _switch_events(self, old: Observation, new: Observation) -> None:
        """Edges of REF_L / REF_R (stop_left/right_high/low, 6.1.11), the position latch on the
        reference switch's edge while moving (6.1.14), and ref_wrong: the reference switch
        active outside the DX_REF_TOLERANCE range (6.1.11)."""
        ref = self._ref_pin()
        moving = self._ramp.v_actual != 0
        for pin, side in (("ref_l", "left"), ("ref_r", "right")):
            if new[pin] != old[pin]:
                self._flag(f"stop_{side}_{'high' if new[pin] else 'low'}")
                if pin == ref and self.lp and moving:
                    self.x_latched = new["x"]  # 6.1.14
                    self.lp = 0
        if new["ref_out"] and not old["ref_out"]:
            self._flag("ref_wrong")

    def _automatic_stop(self) -> None:
        """Stop at an active stop switch in the direction of motion (6.1.10.2): hard, or soft
        when REF_CONF selects soft_stop (never in hold_mode)."""
        r = self._ramp
        v = r.v_actual
        direction = (v > 0) - (v < 0)
        if not direction or direction not in self._blocked():
            self._stopping = False
            return
        if not self._stopping:
            self._flag("stop")
            soft = bool(self.ref_conf >> 2 & 1) and r.mode != HOLD_MODE
            r.stop(soft=soft)
            self._stopping = soft and r.v_actual != 0

    # ------------------------------------------------------------------------------------
    def _position_events(self) -> list[int]:
        """Positions at which the chip must look again (24-bit signed); only those that
        can raise a flag or change a switch are watched."""
        m = self.int_mask
        pts: set[int] = set()
        if m & R.INT_BIT["pos_end"]:
            pts.add(self.x_target)
        if self.pos_comp_m:
            pts.add(self.pos_comp)
        if m & R.INT_BIT["ref_miss"]:
            pts.add(0)
        tol = self.dx_ref_tolerance
        if tol and (self._active("ref_l") or self._active("ref_r") or self._windows["ref_l"]
                    or self._windows["ref_r"]):
            pts.update((tol, -tol, tol - 1, 1 - tol))
        off = self._axis_offset
        for wins in self._windows.values():
            for lo, hi in wins:
                pts.update((lo - off, hi - off, lo - off - 1, hi - off + 1))
        x = self.x_actual
        out: list[int] = []
        for p in pts:
            p = s24(p)
            if p == x:  # look again when the motor leaves this position
                out.extend((s24(p + 1), s24(p - 1)))
            else:
                out.append(p)
        return out

    def _next_event(self, limit: int) -> int:
        """The next cycle (<= limit) at which the chip must look again.

        Position events are searched one ramp phase at a time (up to the core's next
        event), which keeps every search short even when a far target is watched in
        soft_mode, whose exponential approach consists of very many phases.
        """
        r = self._ramp
        best = limit
        if r.v_internal == 0 and self._wanted_direction() == 0 and not self._stopping:
            return max(best, r.now)
        points = self._position_events()
        if points or self._stopping or self._blocked():
            t = r.next_event()
            if t is not None and t < best:
                best = t
        # inside one phase the direction is fixed and at most one step is made per pulse
        # tick: only positions ahead and within reach need the (costly) exact search
        direction = self._wanted_direction()
        period = 32 << r.pulse_div
        ahead = sorted(((p - self.x_actual) * direction % POS_MOD, p) for p in points)
        for d, p in ahead:
            if d > (best - r.now) // period + 1:
                break
            t = r.time_at_position(p, max_phases=1)
            if t is not None and t < best:
                best = t
        return max(best, r.now)

    def _run(self, target_ext: int) -> None:
        r = self._ramp
        guard = 0
        while self._ext < target_ext:
            if self.powered_down or self._frozen():
                self._offset += target_ext - self._ext
                self._ext = target_ext
                break
            limit = target_ext - self._offset
            t = self._next_event(limit)
            if t <= r.now:
                guard += 1
                if guard > 4:  # no progress: let one cycle pass
                    t = r.now + 1
            else:
                guard = 0
            t = min(t, limit)
            self._move(t)
            self._ext = r.now + self._offset
            self._evaluate()

    def _move(self, t: int) -> None:
        r = self._ramp
        if self.stepdir.capture and self.stepdir.en_sd:
            off = self._offset
            for cycle, direction in r.step_events(t):
                self.stepdir.step(cycle + off, direction)
        else:
            r.advance(t)
