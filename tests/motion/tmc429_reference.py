"""Slow per-tick reference model of the TMC429/TMC4210 ramp generator (the oracle).

This is the *definition* the fast event-driven core (`opentmcl.motion.tmc429`)
must reproduce exactly. It walks every clock cycle on which a divided clock
fires and applies the datasheet's rules literally (TMC4210 datasheet ch. 6.1;
choices where the datasheet is silent: docs/assumptions.md):

* 6.1.12: f_CLK is divided by 32, then by 2^RAMP_DIV (ramp generator clock) and
  by 2^PULSE_DIV (pulse generator clock). Both dividers run from cycle 0; on a
  cycle where both fire, the ramp generator acts first.
* 6.1.9.2: the velocity is held with 8 fractional bits (11+8 bits plus sign);
  each ramp tick moves it by at most A_MAX (= A_MAX/256 velocity units)
  towards the ramp generator's target velocity, and stops at that target.
* 6.1.12.1: each pulse tick adds |V_ACTUAL| (the 11 integer bits) to an 11-bit
  accumulator; its overflow (>= 2048) is one step in the direction of the
  velocity's sign. The pulse generator takes the signed velocity ("Range
  +-2047"): the accumulator holds the fraction of a step made in the direction
  of the last motion, and when the motion reverses that fraction is walked back
  first (acc := 2047 - acc), so X_ACTUAL * 2048 + fraction is an up/down count.
* ramp_mode (6.1.9, docs/sources.md "TMC429 ramp generator"): on every ramp
  tick the chip computes the velocity from which a deceleration at A_MAX
  just ends on target, v_stop^2 = 2048 * p * D with p = PMUL / 2^(3+PDIV) and D the remaining
  distance in steps *including the fraction of a step already in the pulse
  accumulator* (D * 2048 = the accumulator units still to add before
  X_ACTUAL == X_TARGET). The ramp target is V_TARGET = s * min(V_MAX,
  max(V_MIN, floor(v_stop))); the velocity moves towards it by at most A_MAX
  per tick, up or down, as in velocity_mode. No latched braking state.
* soft_mode (6.1.10.1): the target velocity is p * |dx| (clamped to
  [V_MIN, V_MAX]), which approaches the target exponentially.
* velocity_mode: the target velocity is V_TARGET limited to +-V_MAX.
* hold_mode: the ramp generator leaves V_ACTUAL alone.
* 6.1.3: at the target position a velocity of at most V_MIN (all 19 bits:
  |v| <= V_MIN * 256) stops abruptly, on the pulse tick of the arrival step
  and on any ramp tick that finds X_ACTUAL == X_TARGET.
"""
from __future__ import annotations

from math import isqrt

RAMP_MODE, SOFT_MODE, VELOCITY_MODE, HOLD_MODE = 0, 1, 2, 3


def _toward(v: int, target: int, step: int) -> int:
    """Move `v` by at most `step` towards `target` (never past it)."""
    if v < target:
        return min(v + step, target)
    if v > target:
        return max(v - step, target)
    return v


def _sign(x: int) -> int:
    return (x > 0) - (x < 0)


class ReferenceRamp:
    """Per-cycle TMC429 ramp; same register names and units as Tmc429Ramp."""

    def __init__(self, *, position_bits: int = 24) -> None:
        self.bits = position_bits
        self.now = 0
        self.x_actual = 0
        self.x_target = 0
        self.v = 0                # signed velocity, 1/256 units (8 fractional bits)
        self.acc = 0              # pulse accumulator, 0..2047
        self.acc_dir = 0          # direction `acc` counts in (0: no motion since power-on)
        self.stopping = False     # soft switch stop in progress
        self.v_min = 0
        self.v_max = 0
        self.v_target = 0         # register value written by the user
        self.a_max = 0
        self.pmul = 128
        self.pdiv = 0
        self.pulse_div = 0
        self.ramp_div = 0
        self.mode = RAMP_MODE

    # --- register writes (same semantics as Tmc429Ramp.set) ----------------
    def set(self, **regs: int) -> None:
        for name, value in regs.items():
            if name in ("x_target", "x_actual"):
                setattr(self, name, value % (1 << self.bits))
                if name == "x_target":
                    self.stopping = False
            elif name == "v_actual":
                if self.mode == HOLD_MODE:
                    self.v = value * 256
                    self.stopping = False
            elif name == "v_target":
                self.v_target = value
                self.stopping = False
            elif name == "mode":
                self.mode = value
                self.stopping = False
            elif name == "pmul":
                self.pmul = value | 0x80
            else:
                setattr(self, name, value)

    def stop(self, *, soft: bool) -> None:
        if soft and self.mode != HOLD_MODE:
            self.stopping = True
            return
        self.v = 0
        self.stopping = False
        self._after_stop()

    def _after_stop(self) -> None:
        if self.mode in (RAMP_MODE, SOFT_MODE):
            self.x_target = self.x_actual
        elif self.mode == VELOCITY_MODE:
            self.v_target = 0

    # --- readouts -----------------------------------------------------------
    @property
    def v_actual(self) -> int:
        return _sign(self.v) * (abs(self.v) >> 8)

    def dx(self) -> int:
        """X_TARGET - X_ACTUAL as a signed number of `bits` bits."""
        half = 1 << (self.bits - 1)
        return (self.x_target - self.x_actual + half) % (1 << self.bits) - half

    def remaining(self, s: int, d: int) -> int:
        """Accumulator units (1/2048 step) still to add before X_ACTUAL reaches a target d
        steps away in direction s: the fraction already made towards it counts, one made
        away from it is walked back first (acc := 2047 - acc on the reversal)."""
        made = self.acc if self.acc_dir in (0, s) else 2047 - self.acc
        return d * 2048 - made

    # --- the clock ----------------------------------------------------------
    def advance(self, until: int) -> None:
        """Apply every ramp and pulse tick on cycles now+1 .. until."""
        ramp_period = 32 << self.ramp_div
        pulse_period = 32 << self.pulse_div
        base = min(ramp_period, pulse_period)
        c = (self.now // base + 1) * base
        while c <= until:
            if c % ramp_period == 0:
                self.ramp_tick()
            if c % pulse_period == 0:
                self.pulse_tick(c)
            c += base
        self.now = until

    def ramp_tick(self) -> None:
        if self.mode == HOLD_MODE:
            return
        if self.stopping:
            self.v = _toward(self.v, 0, self.a_max)
            if self.v == 0:
                self.stopping = False
                self._after_stop()
            return
        if self.mode == VELOCITY_MODE:
            limit = min(abs(self.v_target), self.v_max)
            self.v = _toward(self.v, _sign(self.v_target) * limit * 256, self.a_max)
            return
        dx = self.dx()
        if dx == 0:
            if abs(self.v) <= self.v_min * 256:
                self.v = 0
            else:
                self.v = _toward(self.v, 0, self.a_max)
            return
        s = _sign(dx)
        d = abs(dx)
        if self.mode == RAMP_MODE:
            speed = min(self.v_max, max(self.v_min, isqrt(self.pmul * self.remaining(s, d) >> (3 + self.pdiv))))
        else:                            # soft_mode: p * |dx|
            speed = min(self.v_max, max(self.v_min, self.pmul * d >> (3 + self.pdiv)))
        self.v = _toward(self.v, s * speed * 256, self.a_max)

    def pulse_tick(self, cycle: int) -> None:
        direction = _sign(self.v)
        if direction and direction != self.acc_dir:
            if self.acc_dir:                 # reversal: walk back the fraction made
                self.acc = 2047 - self.acc
            self.acc_dir = direction
        self.acc += abs(self.v) >> 8
        if self.acc >= 2048:
            self.acc -= 2048
            self.x_actual = (self.x_actual + direction) % (1 << self.bits)
            self.on_step(cycle, direction)
            if (self.mode in (RAMP_MODE, SOFT_MODE) and self.x_actual == self.x_target
                    and abs(self.v) <= self.v_min * 256):
                self.v = 0

    def on_step(self, cycle: int, direction: int) -> None:
        """Hook for tests that record step events."""
