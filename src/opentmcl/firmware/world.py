"""The physical world around the axes, as the firmware sees it.

Hooks the VirtualModule calls (filled in by the axis-world model):
- `next_event()`: absolute tick of the next world event (switch edge, input change, stall), or None;
- `service()`: called at every event tick after the engines were brought to `now`;
- `read_axis(axis, number)` (only asked for numbers in `axis_numbers`): value of a world-driven axis parameter (switch states AP9-11, load value
  AP206, encoder AP209, actual current AP180, ...) or None to use the parameter RAM;
- `write_axis(axis, number, value)`: True when the world took a write (e.g. AP209 encoder position).
"""
from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from .axis import Axis
    from .vm import VirtualModule


class World:
    axis_numbers: frozenset[int] = frozenset()
    """Axis parameter numbers `read_axis` serves (the hot GAP path skips the world for others)."""

    def __init__(self, vm: VirtualModule, scenario=None) -> None:
        self.vm = vm
        self.scenario = scenario

    def power_up(self) -> None:
        """Called after the module (re)started; the world itself persists across power cycles."""

    def next_event(self) -> int | None:
        return None

    def service(self) -> None:
        pass

    def read_axis(self, axis: Axis, number: int) -> int | None:
        return None

    def write_axis(self, axis: Axis, number: int, value: int) -> bool:
        return False
