"""PD86-1180 / TMCM-1180 motion engine: the module's TMC429 axis behind the
RampEngine interface (PD86-1180 firmware manual ch. 4.6 and 5).

How the firmware maps its axis parameters onto the TMC429 (manual ch. 5):

* AP0 target position -> X_TARGET, AP1 actual position -> X_ACTUAL. The manual
  gives both (and MVP, 4.6.4) a 32-bit signed range and says a move longer than
  2^31-1 runs the shorter way round, so the firmware exposes 32-bit positions:
  this engine runs the ramp core with a 32-bit position counter.
* AP2 target speed -> V_TARGET in velocity mode; in position mode the manual
  says it is "set by hardware: to the maximum speed during acceleration, and to
  zero during deceleration and rest".
* AP3 actual speed <- V_ACTUAL; AP4 maximum positioning speed -> V_MAX;
  AP5 maximum acceleration -> A_MAX (PMUL/PDIV recomputed, 6.1.9.2);
  AP130 minimum speed -> V_MIN; AP138 ramp mode -> RAMP_MODE (0 position,
  1 soft, 2 velocity); AP153 ramp divisor -> RAMP_DIV, AP154 pulse divisor ->
  PULSE_DIV (PMUL/PDIV recomputed); AP8 <- position reached.
* The clock is 16 MHz, the VM tick (motion.base.CLOCK_HZ); velocities are in
  TMC429 internal units (0..2047).
Choices the manual leaves open are listed in docs/assumptions.md.
"""
from __future__ import annotations

from .base import Mode, RampEngine, Velocity
from .pmulpdiv import registers_for
from .tmc429 import HOLD_MODE, RAMP_MODE, SOFT_MODE, V_LIMIT, VELOCITY_MODE, Tmc429Ramp

POSITION_BITS = 32
"""PD86-1180 manual ch. 5 AP0/AP1 and 4.6.4 MVP: positions are 32-bit signed."""

AP138_MODES = {0: RAMP_MODE, 1: SOFT_MODE, 2: VELOCITY_MODE}
"""PD86-1180 manual ch. 5, AP138: 0 position mode, 1 soft mode, 2 velocity mode."""

_RANGES = {
    "max_positioning_speed": (0, V_LIMIT),   # AP4
    "max_acceleration": (0, 2047),            # AP5
    "minimum_speed": (0, V_LIMIT),            # AP130
    "ramp_mode": (0, 2),                      # AP138
    "ramp_divisor": (0, 13),                  # AP153
    "pulse_divisor": (0, 13),                 # AP154
}


_DIRECT = {"max_acceleration": "a_max", "minimum_speed": "v_min", "ramp_divisor": "ramp_div",
           "pulse_divisor": "pulse_div"}
"""Parameters written to one register as they are (AP5, AP130, AP153, AP154)."""


class Tmc429ConfigError(ValueError):
    """An unknown engine parameter or a value outside the manual's range."""


def _checked(name: str, value: object) -> int:
    """`value` of the parameter `name` as an integer within the manual's range."""
    if name not in _RANGES:
        raise Tmc429ConfigError(f"unknown TMC429 engine parameter {name!r}")
    lo, hi = _RANGES[name]
    if isinstance(value, bool) or not isinstance(value, (int, float)) or value != int(value):
        raise Tmc429ConfigError(f"{name} must be an integer, not {value!r}")
    if not lo <= int(value) <= hi:
        raise Tmc429ConfigError(f"{name}={value} out of range {lo}..{hi}")
    return int(value)


def _s32(x: int) -> int:
    return (x + (1 << 31)) % (1 << 32) - (1 << 31)


class Tmc429Engine(RampEngine):
    """The PD86-1180's ramp generator: a 32-bit-position TMC429 axis.

    Defaults follow the manual's power-on values where it gives them (AP130
    minimum speed = 1); the profile's defaults are applied by the VM through
    `configure`.
    """

    def __init__(self, *, p_reduction: float = 0.01) -> None:
        self.ramp = Tmc429Ramp(position_bits=POSITION_BITS)
        self.p_reduction = p_reduction
        self._params = {"max_positioning_speed": 0, "max_acceleration": 0, "minimum_speed": 1,
                        "ramp_mode": 0, "ramp_divisor": 0, "pulse_divisor": 0}
        self.ramp.set(v_min=1)
        self._recompute_p()

    # --- clock --------------------------------------------------------------------
    @property
    def now(self) -> int:
        return self.ramp.now

    @now.setter
    def now(self, value: int) -> None:  # RampEngine declares `now` as a plain attribute
        if value != self.ramp.now:
            self.ramp.advance(value)

    def advance(self, until: int) -> None:
        self.ramp.advance(until)

    def next_event(self) -> int | None:
        return self.ramp.next_event()

    def time_at_position(self, position: int) -> int | None:
        return self.ramp.time_at_position(position)

    # --- state --------------------------------------------------------------------
    @property
    def position(self) -> int:
        return _s32(self.ramp.x_actual)

    @property
    def velocity(self) -> int:
        return self.ramp.v_actual

    @property
    def moving(self) -> bool:
        """True while the velocity, hidden fraction included, is not zero (datasheet
        6.1.6: V_ACTUAL = 0 may mean a velocity between zero and one)."""
        return self.ramp.v_internal != 0

    @property
    def target_position(self) -> int:
        return _s32(self.ramp.x_target)

    @property
    def target_velocity(self) -> int:
        """AP2: V_TARGET in velocity mode; in position mode V_MAX (with the sign of
        the motion) while accelerating or cruising, 0 while decelerating and at rest
        (PD86-1180 manual ch. 5, AP2)."""
        r = self.ramp
        if r.mode in (VELOCITY_MODE, HOLD_MODE):
            return r.v_target
        dx = r.dx
        if dx == 0 or r.stopping:
            return 0
        computed = abs(r.v_target)     # the ramp's own target (TMC4210 6.1.9)
        if r.v_internal * dx > 0 and computed < r.v_max and abs(r.v_internal) >= computed * 256:
            return 0                   # following the target down: decelerating
        return r.v_max if dx > 0 else -r.v_max

    @property
    def actual_acceleration(self) -> int:
        """AP135: A_ACTUAL of the chip (unsmoothed, see Tmc429Ramp.a_actual)."""
        return self.ramp.a_actual

    @property
    def mode(self) -> Mode:
        return Mode.VELOCITY if self.ramp.mode in (VELOCITY_MODE, HOLD_MODE) else Mode.POSITION

    @property
    def ramp_mode(self) -> int:
        """AP138 as read back: 0 position, 1 soft, 2 velocity."""
        return {RAMP_MODE: 0, SOFT_MODE: 1, VELOCITY_MODE: 2, HOLD_MODE: 2}[self.ramp.mode]

    @property
    def position_reached(self) -> bool:
        """AP8: "Indicates that the actual position equals the target position" (PD86-1180 manual
        ch. 5), with the motor at rest, in every ramp mode: after MST (velocity mode) a motor that
        stands on X_TARGET reads 1, as on the other modules (docs/assumptions.md). The chip's own
        flag (`Tmc429Ramp.position_reached`) is set in ramp_mode and soft_mode only."""
        r = self.ramp
        return r.v_internal == 0 and r.dx == 0

    @property
    def pmul(self) -> int:
        return self.ramp.pmul

    @property
    def pdiv(self) -> int:
        return self.ramp.pdiv

    # --- commands -----------------------------------------------------------------
    def _position_mode(self) -> int:
        return SOFT_MODE if self._params["ramp_mode"] == 1 else RAMP_MODE

    def move_to(self, target: int) -> None:
        """MVP (4.6.4): position mode (soft mode if AP138 = 1), X_TARGET := target."""
        mode = self._position_mode()
        regs = {"x_target": _s32(target), "v_max": self._params["max_positioning_speed"]}
        if self.ramp.mode != mode:
            regs = {"mode": mode, **regs}
            self._params["ramp_mode"] = 1 if mode == SOFT_MODE else 0
        self.ramp.set(**regs)

    def rotate(self, velocity: Velocity) -> None:
        """ROR/ROL/MST (4.6.1-4.6.3): velocity mode, V_TARGET := velocity.
        V_MAX is opened to 2047 so that AP4 (the *positioning* speed) does not
        limit ROR/ROL (docs/assumptions.md)."""
        v = int(velocity)
        if not -V_LIMIT <= v <= V_LIMIT:
            raise Tmc429ConfigError(f"velocity {velocity} out of range -2047..2047")
        if self.ramp.mode != VELOCITY_MODE:
            self.ramp.set(mode=VELOCITY_MODE)
        self.ramp.set(v_max=V_LIMIT, v_target=v)
        self._params["ramp_mode"] = 2

    @property
    def direction(self) -> int:
        v = self.ramp.v_internal
        return (v > 0) - (v < 0)

    @property
    def accelerating(self) -> bool:
        return self.actual_acceleration != 0

    @property
    def plan_token(self) -> object:
        r = self.ramp
        return (r.mode, r.x_target, r.v_target, r.v_internal, r.v_max, r.a_max, r.pulse_div, r.ramp_div)

    def hold(self, velocity: int) -> None:
        """AP3 write: hold_mode, V_ACTUAL := velocity at once (TMC4210 datasheet: hold_mode
        takes V_ACTUAL as written, without ramp or limits)."""
        v = int(velocity)
        if not -V_LIMIT <= v <= V_LIMIT:
            raise Tmc429ConfigError(f"velocity {velocity} out of range -2047..2047")
        if self.ramp.mode != HOLD_MODE:
            self.ramp.set(mode=HOLD_MODE)
        self.ramp.set(v_actual=v)
        self._params["ramp_mode"] = 2

    def hard_stop(self) -> None:
        """Velocity 0 at once; the target becomes the actual position."""
        self.ramp.stop(soft=False)

    def set_position(self, position: int) -> None:
        """AP1 (manual ch. 5: "should only be overwritten for reference point
        setting"). At rest in position mode X_TARGET follows, so that the motor
        stays (datasheet 6.1.4 homing procedure); while moving in position mode
        the chip drives to X_TARGET from the new X_ACTUAL (6.1.2)."""
        r = self.ramp
        if r.mode in (RAMP_MODE, SOFT_MODE) and r.v_internal == 0:
            r.set(x_actual=_s32(position), x_target=_s32(position))
        else:
            r.set(x_actual=_s32(position))

    def configure(self, **params: object) -> None:
        """Set AP4, AP5, AP130, AP138, AP153, AP154 by name (see module doc).
        A change of AP5, AP153 or AP154 recomputes PMUL/PDIV (datasheet 6.1.9.2)."""
        checked = {name: _checked(name, value) for name, value in params.items()}
        self._params.update(checked)
        regs = self._registers(checked)
        if regs:
            self.ramp.set(**regs)
        if {"max_acceleration", "ramp_divisor", "pulse_divisor"} & checked.keys():
            self._recompute_p()

    def _registers(self, checked: dict[str, int]) -> dict[str, int]:
        """The TMC429 registers the checked parameters write (module doc)."""
        r = self.ramp
        regs: dict[str, int] = {}
        if "max_positioning_speed" in checked and r.mode in (RAMP_MODE, SOFT_MODE):
            regs["v_max"] = checked["max_positioning_speed"]
        for name, register in _DIRECT.items():
            if name in checked:
                regs[register] = checked[name]
        if "ramp_mode" in checked:
            mode = AP138_MODES[checked["ramp_mode"]]
            if mode != r.mode:
                regs["mode"] = mode
                regs["v_max"] = V_LIMIT if mode == VELOCITY_MODE else self._params["max_positioning_speed"]
                if mode == VELOCITY_MODE:       # keep the present speed (docs/assumptions.md)
                    regs["v_target"] = r.v_actual
        return regs

    def _recompute_p(self) -> None:
        pmul, pdiv = registers_for(self._params["max_acceleration"], self._params["ramp_divisor"],
                                   self._params["pulse_divisor"], self.p_reduction)
        self.ramp.set(pmul=pmul, pdiv=pdiv)
