"""The state of one TMC429/TMC4210 axis and the rules of one clock cycle (datasheet ch. 6.1).

`RampState` holds the registers and what the chip keeps between cycles: X_ACTUAL, the velocity
with its 8 hidden fractional bits, the pulse accumulator and the direction it counts in, and a
soft switch stop in progress. `cycle(c)` applies one cycle exactly as the per-tick oracle
(tests/motion/tmc429_reference.py) does: on a ramp tick the velocity moves towards the mode's
target by at most A_MAX (6.1.9.2, 6.1.10.1); on a pulse tick the accumulator adds |V_ACTUAL| and
an overflow is one step (6.1.12.1); the ramp generator acts first when both fire. Everything
faster (`motion/tmc429.py`) must agree with it.
"""
from __future__ import annotations

from dataclasses import dataclass

from .tmc429_arith import (
    HOLD_MODE,
    RAMP_MODE,
    SOFT_MODE,
    VELOCITY_MODE,
    ramp_speed,
    sign,
    soft_speed,
    toward,
)
from .tmc429_follow import FollowRegisters


@dataclass(slots=True)
class RampState:
    """Registers and state at cycle `now`; positions are unsigned, `modulus` = 2^position_bits."""

    modulus: int
    now: int = 0
    x: int = 0               # X_ACTUAL
    xt: int = 0              # X_TARGET
    v: int = 0               # signed velocity, 8 fractional bits
    acc: int = 0             # pulse accumulator
    acc_dir: int = 0         # direction `acc` counts in (0: no motion since power-on)
    stopping: bool = False   # soft switch stop in progress
    v_min: int = 0
    v_max: int = 0
    v_target: int = 0        # the register as written
    a_max: int = 0
    pmul: int = 128          # 6.1.9.1: the MSB of PMUL is fixed at 1
    pdiv: int = 0
    pulse_div: int = 0
    ramp_div: int = 0
    mode: int = RAMP_MODE

    @property
    def half(self) -> int:
        return self.modulus >> 1

    def dx(self) -> int:
        """X_TARGET - X_ACTUAL as a signed position (6.1.1)."""
        half = self.modulus >> 1
        return (self.xt - self.x + half) % self.modulus - half

    # --- targets ------------------------------------------------------------------------------
    def made(self, s: int) -> int:
        """Accumulator units of the current step made in direction s (one made the other way is
        walked back first, acc := 2047 - acc)."""
        return self.acc if self.acc_dir in (0, s) else 2047 - self.acc

    def remaining(self, s: int, d: int) -> int:
        """Accumulator units (1/2048 step) to add before X_ACTUAL reaches a target d steps away
        in direction s (the fraction made towards it counts)."""
        return d * 2048 - self.made(s)

    def speed(self, units: int) -> int:
        """ramp_mode target speed for `units` still to go (6.1.9)."""
        return ramp_speed(units, self.pmul, self.pdiv, self.v_min, self.v_max)

    def soft_speed(self, d: int) -> int:
        """soft_mode target speed for a target d steps away (6.1.10.1)."""
        return soft_speed(d, self.pmul, self.pdiv, self.v_min, self.v_max)

    def velocity_mode_target(self) -> int:
        return sign(self.v_target) * min(abs(self.v_target), self.v_max) * 256

    def position_target(self, s: int, d: int) -> int:
        """Target velocity (1/256 units) in ramp_mode or soft_mode, d > 0 steps away in direction s."""
        if self.mode == RAMP_MODE:
            return s * self.speed(self.remaining(s, d)) * 256
        return s * self.soft_speed(d) * 256

    def follow_registers(self) -> FollowRegisters:
        return FollowRegisters(32 << self.ramp_div, 32 << self.pulse_div, self.a_max, self.pmul,
                               self.pdiv, self.v_min, self.v_max)

    # --- one cycle ----------------------------------------------------------------------------
    def after_stop(self) -> None:
        """At standstill after a switch stop the motor stays (6.1.10.2)."""
        if self.mode in (RAMP_MODE, SOFT_MODE):
            self.xt = self.x
        elif self.mode == VELOCITY_MODE:
            self.v_target = 0

    def ramp_tick(self) -> None:
        if self.mode == HOLD_MODE:
            return
        if self.stopping:
            self.v = toward(self.v, 0, self.a_max)
            if self.v == 0:
                self.stopping = False
                self.after_stop()
            return
        if self.mode == VELOCITY_MODE:
            self.v = toward(self.v, self.velocity_mode_target(), self.a_max)
            return
        dx = self.dx()
        if dx == 0:
            self.v = 0 if abs(self.v) <= self.v_min * 256 else toward(self.v, 0, self.a_max)
            return
        self.v = toward(self.v, self.position_target(sign(dx), abs(dx)), self.a_max)

    def pulse_tick(self) -> int:
        direction = sign(self.v)
        if direction and direction != self.acc_dir:
            if self.acc_dir:                # reversal: walk back the fraction made
                self.acc = 2047 - self.acc
            self.acc_dir = direction
        self.acc += abs(self.v) >> 8
        if self.acc < 2048:
            return 0
        self.acc -= 2048
        self.x = (self.x + direction) % self.modulus
        if (self.mode in (RAMP_MODE, SOFT_MODE) and self.x == self.xt
                and abs(self.v) <= self.v_min * 256):
            self.v = 0                      # 6.1.3: stop at the target at or below V_MIN
        return direction

    def cycle(self, c: int) -> int:
        """Apply cycle c = now + 1 exactly; return the step made (-1, 0, +1)."""
        if c % (32 << self.ramp_div) == 0:
            self.ramp_tick()
        step = self.pulse_tick() if c % (32 << self.pulse_div) == 0 else 0
        self.now = c
        return step

    def settled(self, t: int, made: int, v: int, s: int,
                moved: bool) -> tuple[int, int, int, int, int]:
        """(cycle, X_ACTUAL, acc, acc_dir, velocity) after a stretch walked towards the target in
        direction s: `made` accumulator units counted from the last whole step before it,
        velocity v at cycle t; `moved`: a pulse tick saw a non-zero velocity (the accumulator
        counts in s now)."""
        steps, acc = divmod(made, 2048)
        acc_dir = self.acc_dir
        if moved:
            acc_dir = s
        elif acc_dir not in (0, s):         # no pulse yet: keep the old orientation
            acc = 2047 - acc
        return t, (self.x + s * steps) % self.modulus, acc, acc_dir, v

    def settle(self, t: int, made: int, v: int, s: int, moved: bool) -> None:
        """Take over the state `settled` gives."""
        self.now, self.x, self.acc, self.acc_dir, self.v = self.settled(t, made, v, s, moved)
