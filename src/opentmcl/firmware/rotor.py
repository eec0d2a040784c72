"""The rotor and the stage it drives (docs/world.md "Stage and switches"): the physical position
`phys` (microsteps) follows the step counter, `phys = counter + offset`, until steps are lost or
the driver is off; then the stage stands and the counter runs on."""
from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ..motion import RampEngine
    from .axis_world import AxisWorld
    from .motor import Motor


def sign(x) -> int:
    return (x > 0) - (x < 0)


class Rotor:
    """Where the stage really is, and how it follows the position counter."""

    axis: Motor
    engine: RampEngine

    def __init__(self, aw: AxisWorld) -> None:
        self.aw = aw
        self.phys = aw.stage.start    # physical position (microsteps); the world keeps it across power cycles
        self.offset = 0               # phys = counter + offset while no step is lost
        self.slipping = 0             # direction of the commanded motion while steps are lost

    def bind(self, axis: Motor) -> None:
        """A new axis (power-up): the counter starts where the stage stands."""
        self.axis = axis
        self.engine = axis.engine
        self.offset = self.phys - self.engine.position
        self.slipping = 0

    def driver_off(self) -> bool:
        """AP167 (TOFF) = 0: "completely disables all driver transistors and the motor can
        free-wheel" (TMCM-6212 4.1), or the driver shut down by overtemperature or a short (AP208
        bits 1, 3, 4): the step counter runs on, the rotor does not follow it."""
        aw = self.aw
        return aw.drive.shut_down or (167 in aw.params and aw.ram.get(167, 1) == 0)

    def follow(self, counter: int | None = None) -> None:
        """Bring the physical position up to the counter (unless steps are being lost or the
        driver is off; then the stage stays and the frame offset follows the counter). `counter`:
        the engine's position now, if read already."""
        if counter is None:
            counter = self.engine.position
        if self.driver_off():
            self.slipping = 0
            self.offset = self.phys - counter
        elif self.slipping:
            if self.heading() != self.slipping or not (self.blocked(self.slipping) or self.aw.drive.overloaded()):
                self.slipping = 0          # stopped, reversed or the load fell: the rotor follows again
                self.offset = self.phys - counter
        else:
            self.phys = counter + self.offset

    def heading(self, direction: int | None = None) -> int:
        """Direction of motion, or of the motion about to start (0 when there is none);
        `direction`: the engine's, if read already."""
        e = self.engine
        v = e.direction if direction is None else direction
        if v:
            return v
        if e.mode.value == "velocity":
            return sign(e.target_velocity)
        return sign(((e.target_position - e.position + 2**31) % 2**32) - 2**31)

    def blocked(self, direction: int) -> bool:
        """At a mechanical end and pushing into it."""
        lo, hi = self.aw.stage.ends
        return (direction > 0 and hi is not None and self.phys >= hi) or \
               (direction < 0 and lo is not None and self.phys <= lo)

    def lose_steps(self, direction: int) -> None:
        """Steps are lost from here on: the stage stands (at the mechanical end it was pushed past)
        while the counter runs on in `direction`."""
        lo, hi = self.aw.stage.ends
        if direction > 0 and hi is not None and self.phys > hi:
            self.phys = hi
        if direction < 0 and lo is not None and self.phys < lo:
            self.phys = lo
        self.slipping = direction

    def relabel(self, counter: int) -> None:
        """Overwrite the position counter (AP1, reference point); the stage stays where it is."""
        self.follow()
        self.engine.set_position(counter)
        self.offset = self.phys - self.engine.position

    def set_toff(self, value: int) -> None:
        """SAP 167: the stage follows up to now under the old setting; after re-enabling it
        continues from where it stands."""
        self.follow()
        self.axis.ram[167] = value
        self.follow()

    def set_driver_flags(self, bits: int) -> None:
        """The driver's error flags change (a fault): as `set_toff`, the stage follows up to now
        under the old state and continues from where it stands."""
        self.follow()
        self.aw.drive.set_fault_flags(bits)
        self.follow()

    def speed(self) -> int:
        """Speed of the rotor (stage) in the unit of AP3: 0 at rest, while steps are lost or the
        driver is off; signed like AP3 (TMCM-6212 AP29 "Speed measured by the motor driver")."""
        self.follow()
        if self.slipping or self.driver_off():
            return 0
        return self.axis.from_engine(29, self.engine.velocity)
