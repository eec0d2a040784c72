"""The load on one axis and the torque the drive makes against it (docs/world.md "Load, current,
stallGuard2, coolStep"): load torque, the current in use (motion/stallguard.py `CurrentModel`),
the torque fall-off with speed and the load value AP206."""
from __future__ import annotations

from typing import TYPE_CHECKING

from ..motion import CLOCK_HZ
from ..motion.stage import Load, Profile
from ..motion.stallguard import CurrentModel, load_value

if TYPE_CHECKING:
    from .axis_world import AxisWorld

END_LOAD = 100.0                     # a mechanical end: far more than any current can hold
DEFAULT_FALLOFF_RPS = 30
"""Speed (full-step revolutions per second) at which the torque has fallen to 0 unless the
scenario sets `torque_falloff_speed`: about half the torque at 15 rev/s, as a typical stepper."""
FULLSTEPS = 200
OVERTEMPERATURE, PREWARNING, SHORT_A, SHORT_B = 0x02, 0x04, 0x08, 0x10
"""AP208 bits (PD86-1180 manual 5, TMC262 driver error flags): "1: driver is shut down due to
overtemperature", "1: [pre-warning] threshold is exceeded", "1: short condition detected, driver
currently shut down" (coil A, B)."""
SHUTS_DOWN = OVERTEMPERATURE | SHORT_A | SHORT_B


def check_by(by: str) -> None:
    if by not in ("position", "time"):
        raise ValueError(f"a load is given by 'position' or 'time', not {by!r}")


def as_load(load: float | Load | Profile, by: str) -> Load:
    """A load torque given as a Load, a Profile over `by` ("position" or "time") or a constant."""
    if isinstance(load, Load):
        return load
    if isinstance(load, Profile):
        return Load(load, by)
    return Load(Profile.constant(float(load)), "position")


class Drive:
    """Load torque and motor torque of one axis."""

    def __init__(self, aw: AxisWorld) -> None:
        self.aw = aw
        self.load: Load = aw.spec.load
        self.current = CurrentModel()
        self.fault_flags = 0
        """AP208 bits 1-6 a fault sets (firmware/faults.py); they persist across power cycles."""
        self.shut_down = False
        """The driver is off because of them: the motor makes no torque (docs/world.md)."""

    def bind(self) -> None:
        """Power-up: the current model starts afresh."""
        self.current = CurrentModel()

    def set_fault_flags(self, bits: int) -> None:
        self.fault_flags = bits & 0x7E
        self.shut_down = bool(self.fault_flags & SHUTS_DOWN)

    def load_now(self, direction: int | None = None) -> float:
        """Load torque now; pushing into a mechanical end adds END_LOAD (`direction`: the
        engine's, if read already)."""
        aw = self.aw
        rotor = aw.rotor
        load = self.load.at(rotor.phys, aw.scheduler.now / CLOCK_HZ)
        d = rotor.slipping or rotor.heading(direction)
        if d and rotor.blocked(d):
            load += END_LOAD
        return load

    def falloff(self) -> float:
        """Share of the torque left at the present speed: falls linearly to 0 at the scenario's
        `torque_falloff_speed` (pps), by default DEFAULT_FALLOFF_RPS of a 200-step motor."""
        aw = self.aw
        fall = aw.spec.torque_falloff_speed
        if not fall:
            fall = DEFAULT_FALLOFF_RPS * FULLSTEPS * (1 << aw.ram.get(140, 8))
        pps = float(aw.engine.velocity)  # the engine's velocity in microsteps per second
        if aw.caps.velocity_unit == "tmc429":  # AP154 pulse divisor (PD86-1180 manual 5)
            pps = pps * CLOCK_HZ / ((1 << aw.ram.get(154, 0)) * 2048 * 32)
        left = 1.0 - abs(pps) / fall
        return left if left > 0.0 else 0.0

    def capacity(self, use: int | None = None) -> float:
        """Torque the motor can make now, as a fraction of the torque at 100 % current: (CS + 1)
        / 32 of the current scale CS in use (none without current) times the fall-off with speed
        (`use`: the current in use, `CurrentModel.in_use`, if known already)."""
        if use is None:
            use = self.current.in_use(self.aw)
        return 0.0 if use == 0 else ((use >> 3) + 1) / 32 * self.falloff()

    def load_value(self, use: int | None = None, direction: int | None = None) -> int:
        """AP206 (docs/world.md, stallGuard2 model); `use` as for `capacity`, `direction` as for
        `load_now`."""
        return load_value(self.load_now(direction), self.capacity(use), self.aw.ram.get(174, 0))

    def overloaded(self) -> bool:
        return self.load_now() > self.capacity()
