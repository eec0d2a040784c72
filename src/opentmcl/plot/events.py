"""Discontinuities and program marks of a trace: what the plot draws as breaks and markers.

- An **origin write** overwrites the actual position counter (axis parameter 1: "Should only be
  overwritten for reference point setting", TMCM-6212 manual 4.1; also the end of a reference
  search): the counter jumps while the motor stands or moves on, so the position curve has a break
  there, not a vertical move.
- A **hard stop** sets the actual speed to 0 at once (a limit switch with soft stop off, stop on
  stall, a heartbeat timeout): the speed curve has a break, not a deceleration ramp.

A virtual run knows both exactly (`EngineWatch` watches the module's ramp engines); a trace from a
real module or an old CSV has no events (``Trace.events is None``), and `guess_origins` finds
position jumps the actual speed cannot explain. Marks are the program counter of a program run
(command 135 type 1, TMCM-6212 manual 3.6.36) at each sample where it changed. `Event` and `Mark`
live with the trace (opentmcl/trace.py), which writes and reads them in its CSV file.
"""
from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import Any

from ..trace import HARD_STOP, KINDS, ORIGIN, Event, Mark

__all__ = ["HARD_STOP", "KINDS", "ORIGIN", "EngineWatch", "Event", "Mark", "guess_origins"]


class EngineWatch:
    """Logs origin writes and hard stops of an in-process virtual module, with its virtual time.

    It wraps `set_position` and `hard_stop` of each axis's ramp engine (the only ways the firmware
    overwrites the position counter or stops at once) and calls the originals unchanged, so the
    module behaves exactly as unwatched. `to_pps(axis, velocity)` converts engine velocity units."""

    def __init__(self, vm: Any, to_pps: Callable[[int, float], float]) -> None:
        self.vm = vm
        self.to_pps = to_pps
        self.log: list[tuple[float, int, str, float, float]] = []   # (vm seconds, axis, kind, before, after)
        self._engines = [axis.engine for axis in vm.axes]
        for index, engine in enumerate(self._engines):
            self._wrap(index, engine)

    def _wrap(self, index: int, engine: Any) -> None:
        set_position, hard_stop = engine.set_position, engine.hard_stop

        def watched_set_position(position: int) -> None:
            before = engine.position
            set_position(position)
            if engine.position != before:
                self.log.append((self.vm.time, index, ORIGIN, before, engine.position))

        def watched_hard_stop() -> None:
            before = engine.velocity
            hard_stop()
            if before != 0:
                self.log.append((self.vm.time, index, HARD_STOP, float(self.to_pps(index, before)), 0.0))

        setattr(engine, "set_position", watched_set_position)   # noqa: B010 - instance attribute
        setattr(engine, "hard_stop", watched_hard_stop)         # noqa: B010

    def events(self, offset: float, axes: Iterable[int]) -> list[Event]:
        """The logged events of `axes`, on the trace's clock (trace time = vm time - offset)."""
        wanted = set(axes)
        return [Event(t - offset, ax, kind, before, after) for t, ax, kind, before, after in self.log
                if ax in wanted]

    def close(self) -> None:
        """Remove the wrappers (the engines' own methods show through again)."""
        for engine in self._engines:
            for name in ("set_position", "hard_stop"):
                engine.__dict__.pop(name, None)


def guess_origins(time: list[float], position: list[float | None], velocity: list[float | None],
                  axis: int) -> list[Event]:
    """Origin writes of a trace without events: a position change between two samples larger than
    twice the larger of the two actual speeds times the interval, plus one µstep (a motor cannot
    cover that distance; the factor 2 leaves room for a speed peak between the samples)."""
    out = []
    for i in range(1, len(time)):
        p0, p1, v0, v1 = position[i - 1], position[i], velocity[i - 1], velocity[i]
        if p0 is None or p1 is None:
            continue
        speed = max(abs(v0 or 0), abs(v1 or 0))
        if abs(p1 - p0) > 2 * speed * (time[i] - time[i - 1]) + 1:
            out.append(Event(time[i], axis, ORIGIN))
    return out
