"""Behavioural model of stallGuard2, coolStep and the drive currents (docs/world.md).

Not the chip's physics: a linear model with the properties the manuals state
(TMCM-6212 manual 6.3/6.4 and 4.1 AP168-AP183, PD86-1180 manual 5.1/7.3):

    capacity  C = (CS + 1) / 32            CS = current scale 0..31 in use (= current >> 3)
    load value SG = clamp(round(1023 * (1 - L / C)) + 16 * SGT, 0, 1023)

L is the load torque as a fraction of the torque at 100 % current, SGT the
threshold AP174. SG falls linearly with load, rises with current and reaches
0 at L = C (SGT = 0); a lower SGT reaches 0 at a lower load (more sensitive).
The objects here read the axis through the firmware's axis world `aw` (firmware/axis_world.py):
`aw.p(n)` (or `aw.ram`), `aw.has(n)`, `aw.engine`, `aw.axis`, `aw.vm`, `aw.scheduler` (its clock
`now`), `aw.caps`, `aw.spec`, and its drive `aw.drive`
(`load_now()`, `falloff()`, `load_value()`).
"""
from __future__ import annotations

from .base import CLOCK_HZ

SEUP = (1, 2, 4, 8)        # AP171: current increment per measurement below the lower threshold
SEDN = (32, 8, 2, 1)       # AP169: measurements above the upper threshold per decrement
TICKS_PER_10MS = CLOCK_HZ // 100
TICKS_PER_MS = CLOCK_HZ // 1000


def load_value(load: float, capacity: float, sgt: int) -> int:
    """AP206: 0..1023, linear in the load; 0 = maximum load (stall)."""
    if capacity <= 0:
        return 0
    sg = round(1023 * (1 - load / capacity)) + 16 * sgt
    return sg if 0 <= sg <= 1023 else 0 if sg < 0 else 1023


class CurrentModel:
    """Which current drives the motor now: run, boost, slow-run, coolStep-regulated, standby or none."""

    def __init__(self) -> None:
        self.cs_act: int | None = None       # coolStep current scale while regulating
        self.still_since: int | None = 0
        self._last_counter: int | None = None
        self._microsteps = 0                 # travelled since the last stallGuard2 measurement
        self._down = 0                       # measurements above the upper threshold so far
        self.driver_flags = 0

    # --- thresholds -------------------------------------------------------------------------
    @staticmethod
    def cs(aw) -> int:
        return aw.p(6, 128) >> 3

    # --- update --------------------------------------------------------------------------------
    def update(self, aw, moving: bool | None = None, counter: int | None = None) -> None:
        """Bring the model to now (`moving`: whether the engine moves, `counter`: its position,
        if read already). coolStep regulates while AP172 (SEMIN) is set and the motor moves at
        least at the coolStep threshold speed AP182."""
        e = aw.engine
        if moving is None:
            moving = e.moving
        if moving:
            self.still_since = None
        elif self.still_since is None:
            self.still_since = aw.scheduler.now
        if counter is None:
            counter = e.position
        last = self._last_counter
        self._last_counter = counter
        ram = aw.ram
        if not (ram.get(172, 0) and moving and abs(e.velocity) >= abs(aw.axis.to_engine(182, ram.get(182, 0)))):
            self.cs_act = None
            self._microsteps = 0
            return
        moved = 0 if last is None else abs(counter - last)
        cs = self.cs(aw)
        per = (1 << aw.p(140, 8)) * (4 if aw.p(173) else 1)   # AP173: one measurement per 4 fullsteps
        self._microsteps += moved
        n, self._microsteps = divmod(self._microsteps, per)
        self.cs_act = self._regulate(aw, n, cs, cs if self.cs_act is None else self.cs_act)

    def _regulate(self, aw, n: int, cs: int, cs_act: int) -> int:
        """`n` stallGuard2 measurements: the coolStep current scale after them, from `cs_act`."""
        semin, semax = aw.p(172), aw.p(170)
        lower, upper = semin * 32, (semin + semax + 1) * 32
        up, down = SEUP[aw.p(171) & 3], SEDN[aw.p(169) & 3]
        cs_min = max(0, (cs + 1) // (4 if aw.p(168) else 2) - 1)
        load = aw.drive.load_now()
        while n > 0:
            sg = load_value(load, (cs_act + 1) / 32 * aw.drive.falloff(), aw.p(174))
            if sg < lower and cs_act < cs:
                cs_act = min(cs, cs_act + up)
                self._down = 0
                n -= 1
            elif sg >= upper and cs_act > cs_min:
                need = down - self._down
                if n < need:
                    self._down += n
                    return cs_act
                n -= need
                self._down = 0
                cs_act -= 1
            else:
                return cs_act
        return cs_act

    # --- readings ---------------------------------------------------------------------------------
    def in_use(self, aw, moving: bool | None = None) -> int:
        """Current in use on the 0..255 scale of AP6 (`moving` as for `update`)."""
        e, ram = aw.engine, aw.ram
        if not (e.moving if moving is None else moving):
            still = 0 if self.still_since is None else aw.scheduler.now - self.still_since
            freewheel = ram.get(204, 0)
            if freewheel and aw.caps.freewheel_delay and still >= freewheel * TICKS_PER_MS:
                return 0                         # PD86-1180 AP204: power cut after the freewheeling time
            if still >= ram.get(214, 200) * TICKS_PER_10MS:
                return ram.get(7, 8)             # standby current after the power-down delay
            return ram.get(6, 128)
        boost = ram.get(200, 0)
        if boost and e.accelerating:  # boost current while the ramp changes the velocity
            return boost                         # boost current during acceleration / deceleration
        slow = ram.get(182, 0)
        if slow and 183 in aw.params and abs(e.velocity) < abs(aw.axis.to_engine(182, slow)):
            return ram[183]                      # slow-run current below the coolStep threshold speed
        if self.cs_act is not None:
            return (self.cs_act + 1) * 8 - 1
        return ram.get(6, 128)


    def driver_status(self, aw) -> int:
        """AP208 (PD86-1180 manual 5, TMC262 flags): bit 0 stallGuard2 threshold reached,
        bit 7 standstill; bits 1-6 from the scenario's `driver_flags`."""
        bits = 0
        if aw.engine.moving and aw.drive.load_value() == 0:
            bits |= 0x01
        if not aw.engine.moving:
            bits |= 0x80
        prof = aw.spec.driver_flags
        if prof is not None:
            bits |= int(round(prof.at(aw.vm.now / CLOCK_HZ))) & 0x7E
        return bits
