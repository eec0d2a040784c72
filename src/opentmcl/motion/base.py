"""Common interface of the per-axis ramp generators (docs/architecture.md "Time").

Every engine lives on an integer clock: `now` counts ticks of `clock_hz` since
power-up. Positions are integer microsteps held in a 32-bit two's complement
counter (they wrap). Velocities are signed; their unit is the engine's own
(pps for the TMC5130-style and linear engines, TMC429 internal units for the
TMC429 engine). Engines are event-driven: `advance(t)` jumps straight to tick
`t` with closed-form motion inside each ramp phase, and `next_event()` tells
the caller when the next phase change (or arrival) happens, so a caller never
has to step in small increments.
"""
from __future__ import annotations

from abc import ABC, abstractmethod
from enum import Enum
from fractions import Fraction

CLOCK_HZ = 16_000_000
"""The modules' controller clock (TMC5130 and TMC429 at 16 MHz); one virtual tick."""


Velocity = int | Fraction | float
"""A velocity in engine units as an engine reports it: an int, or exact (a Fraction) where
the engine keeps fractions of its unit (the TMC5130-style engine's pps)."""


class Mode(Enum):
    POSITION = "position"
    VELOCITY = "velocity"


class RampEngine(ABC):
    """One axis's ramp generator.

    Commands act at the current tick `now`. Ramp parameters are engine
    specific and are changed with `configure(**params)`, which re-plans the
    current motion from the present state (on-the-fly changes).
    """

    clock_hz: int = CLOCK_HZ
    now: int = 0

    # --- state at `now` -------------------------------------------------
    @property
    @abstractmethod
    def position(self) -> int:
        """Actual position (AP1), 32-bit wrapped."""

    @property
    @abstractmethod
    def velocity(self) -> int | float:
        """Actual signed velocity (AP3) in engine units."""

    @property
    @abstractmethod
    def target_position(self) -> int:
        """Target position (AP0)."""

    @property
    @abstractmethod
    def target_velocity(self) -> Velocity:
        """Target velocity in velocity mode (AP2)."""

    @property
    @abstractmethod
    def mode(self) -> Mode: ...

    @property
    @abstractmethod
    def position_reached(self) -> bool:
        """AP8: target position and actual position are equal (and the motor has stopped there)."""

    @property
    def moving(self) -> bool:
        return self.velocity != 0

    @property
    def direction(self) -> int:
        """Sign of the actual velocity (-1, 0, 1), exact."""
        v = self.velocity
        return (v > 0) - (v < 0)

    @property
    def accelerating(self) -> bool:
        """The ramp is changing the velocity now."""
        return False

    @property
    def plan_token(self) -> object:
        """A value that changes whenever a command or parameter change re-plans the motion
        (the axis world caches its next event against it)."""
        return (self.mode, self.target_position, self.target_velocity, self.velocity, self.position)

    # --- commands ---------------------------------------------------------
    @abstractmethod
    def move_to(self, target: int) -> None:
        """Positioning mode towards `target` (32-bit wrap: the shorter way round)."""

    @abstractmethod
    def rotate(self, velocity: Velocity) -> None:
        """Velocity mode with signed target velocity."""

    def stop(self) -> None:
        """Soft stop: velocity mode with target velocity 0 (MST)."""
        self.rotate(0)

    @abstractmethod
    def hard_stop(self) -> None:
        """Stop at once (velocity 0 immediately, target := actual)."""

    @abstractmethod
    def set_position(self, position: int) -> None:
        """Overwrite the actual position counter (AP1)."""

    @abstractmethod
    def configure(self, **params: object) -> None:
        """Change ramp parameters; motion in progress continues with the new values."""

    # --- time -------------------------------------------------------------
    @abstractmethod
    def advance(self, until: int) -> None:
        """Move the state forward to absolute tick `until` (>= now)."""

    @abstractmethod
    def next_event(self) -> int | None:
        """Absolute tick of the next ramp phase change or arrival, or None when
        nothing will change without a new command (standing still or cruising)."""

    def time_at_speed(self, speed: Velocity) -> int | None:
        """First tick >= now at which |velocity| >= `speed` (engine units) if no command intervenes,
        or None when unknown or never (used for the stop-on-stall speed AP181)."""
        return None

    def time_at_position(self, position: int) -> int | None:
        """First tick >= now at which the actual position equals `position`
        if no command intervenes, or None if it never does (used by the axis
        world for switch edges). Engines override this with a closed form."""
        return None
