"""The checks made on one axis at each of its events (docs/world.md): switch states, reference
search or limit stops, stall (AP181), step loss, deviation (AP212) and the encoder's null channel."""
from __future__ import annotations

from typing import TYPE_CHECKING

from . import flags as fl

if TYPE_CHECKING:
    from ..motion import RampEngine
    from .axis_world import AxisWorld
    from .motor import Motor

STALL, DEVIATION = 15, 21            # interrupt numbers + axis (firmware/interrupts.py)
SG_EXTENDED, DEV_EXTENDED = 1, 2     # AP207 bits


class Checks:
    """What the world does to an axis at an event: stops, error flags, interrupts, lost steps."""

    axis: Motor
    engine: RampEngine

    def __init__(self, aw: AxisWorld) -> None:
        self.aw = aw

    def bind(self, axis: Motor) -> None:
        self.axis = axis
        self.engine = axis.engine

    def run(self) -> None:
        """All checks, in order (nothing before the world is bound to an axis)."""
        aw = self.aw
        if aw.axis is None:
            return
        aw.rotor.follow()
        aw.switches.update()
        aw.drive.current.update(aw)
        search = aw.vm.reference_search(self.axis)
        if search.active:
            search.poll()
        else:
            self.limit_stops()
        if not aw.rotor.driver_off():
            self.stall()
            self.step_loss()
        self.deviation()
        aw.encoder.null_channel()

    # --- limit stops ------------------------------------------------------------------------------
    def soft_stop_enabled(self) -> bool:
        """TMCM-6212 AP26, PD86-1180 AP149: a limit switch stops with the deceleration."""
        aw = self.aw
        if aw.has(26):
            return bool(aw.p(26))
        if aw.has(149):
            return bool(aw.p(149))
        return False

    def _stop(self, soft: bool) -> None:
        e = self.engine
        if soft:
            if not (e.mode.value == "velocity" and e.target_velocity == 0):
                e.stop()
        else:
            e.hard_stop()

    def limit_due(self) -> bool:
        """A limit switch in the direction of motion is active (AP12/AP13 not set) and the
        motor is not already braking for it."""
        aw = self.aw
        d = aw.rotor.heading()
        if not d:
            return False
        switches = aw.switches
        left, right, _ = switches.logical()
        if d > 0:
            hit = right and not aw.p(12)
        else:
            hit = left and not aw.p(13)
            tol = aw.p(141)
            if hit and switches.three_switch_wiring and tol and abs(self.engine.position) <= tol \
                    and not switches.input_level("left"):
                hit = False  # PD86-1180 AP141: the reference switch inside the tolerance range
        if not hit:
            return False
        e = self.engine
        return not (self.soft_stop_enabled() and e.mode.value == "velocity" and e.target_velocity == 0)

    def limit_stops(self) -> None:
        """Stop only for the switch in the direction of motion."""
        if self.limit_due():
            self._stop(self.soft_stop_enabled())

    # --- stall, step loss, deviation --------------------------------------------------------------
    def stall_speed(self, limit: int):
        """AP181 as an engine speed."""
        return self.axis.engine_speed(181, limit)

    def stall(self) -> None:
        aw = self.aw
        limit = aw.p(181)
        if not limit or not self.engine.moving:
            return
        v = abs(self.engine.velocity)
        if v < self.stall_speed(limit):
            return
        if aw.drive.load_value() == 0:
            self.engine.hard_stop()
            self.axis.error_flags |= SG_EXTENDED
            aw.vm.interpreter.set_error_flag(fl.EPO)
            aw.vm.interrupts.trigger(STALL + aw.index)
            self._end_search()

    def _end_search(self) -> None:
        """A stall or deviation stop ends a running reference search (docs/world.md)."""
        search = self.aw.vm.reference_search(self.axis)
        if search.active:
            search.abort()

    def step_loss(self) -> None:
        rotor = self.aw.rotor
        d = rotor.heading()           # moving, or about to move
        if rotor.slipping or not d:
            return
        if rotor.blocked(d) or self.aw.drive.overloaded():
            rotor.lose_steps(d)

    def deviation(self) -> None:
        aw = self.aw
        limit = aw.p(212)
        if not limit:
            return
        if abs(self.engine.position - aw.encoder.position()) > limit:
            if self.engine.moving or aw.rotor.heading():  # also a motion commanded at this tick
                self.engine.hard_stop()
            if not self.axis.error_flags & DEV_EXTENDED:
                self.axis.error_flags |= DEV_EXTENDED
                aw.vm.interpreter.set_error_flag(fl.EDV)
                aw.vm.interrupts.trigger(DEVIATION + aw.index)
            self._end_search()

    # --- is a check due now? ----------------------------------------------------------------------
    def due_now(self) -> bool:
        """Would a check at this tick change anything (a command just started a motion into an
        active switch or into an overload)?"""
        aw = self.aw
        rotor = aw.rotor
        if aw.axis is None or not rotor.heading():
            return False
        if not aw.vm.reference_search(self.axis).active and self.limit_due():
            return True
        e = self.engine
        if not rotor.slipping and not rotor.driver_off() and (rotor.blocked(rotor.heading()) or aw.drive.overloaded()):
            return True
        dev = aw.p(212)
        if dev and abs(e.position - aw.encoder.position()) > dev:  # a deviation the motion starts with
            return True
        if not e.moving:
            return False
        limit = aw.p(181)
        return bool(limit and not rotor.driver_off() and abs(e.velocity) >= self.stall_speed(limit)
                    and aw.drive.load_value() == 0)
