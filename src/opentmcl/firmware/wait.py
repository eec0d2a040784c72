"""WAIT conditions (TMCM-6212 manual 3.6.20, PD86-1180 manual 4.6.22).

"one tick is 10 milliseconds". TICKS waits for <ticks>; POS, REFSW, LIMSW and
RFS wait for their condition with an optional timeout (<ticks>, 0 = none);
reaching the timeout sets the ETO flag and the program goes on.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from ..motion import CLOCK_HZ
from .status import TmclStatus

if TYPE_CHECKING:
    from .motor import Motor
    from .vm import VirtualModule

TICK = CLOCK_HZ // 100  # one WAIT tick, 10 ms
TICKS, POS, REFSW, LIMSW, RFS = range(5)


@dataclass
class Wait:
    """A WAIT in progress: condition, motor, and the tick at which it ends (timeout), if any."""

    condition: int
    motor: int
    deadline: int | None


def start(vm: VirtualModule, condition: int, motor: int, ticks: int) -> Wait:
    """Begin a WAIT at vm.now; TmclStatus(3) for an unknown condition, (4) for a bad motor."""
    if not TICKS <= condition <= RFS:
        raise TmclStatus(3)
    if condition != TICKS and not 0 <= motor < len(vm.axes):
        raise TmclStatus(4)
    deadline = vm.now + ticks * TICK if ticks > 0 else None
    if condition == TICKS and deadline is None:
        deadline = vm.now
    return Wait(condition, motor, deadline)


def _param(axis: Motor, number: int) -> int:
    try:
        return axis.get(number)
    except TmclStatus:
        return 0


def satisfied(vm: VirtualModule, w: Wait) -> bool:
    """Is the condition of `w` met at vm.now? (TICKS: never - it only times out.)"""
    if w.condition == TICKS:
        return False
    axis = vm.axes[w.motor]
    if w.condition == POS:
        return bool(vm.engine_now(w.motor).position_reached)
    if w.condition == REFSW:
        return bool(_param(axis, 9))  # home switch state
    if w.condition == LIMSW:
        return bool(_param(axis, 10) or _param(axis, 11))  # right / left limit switch state
    return not vm.reference_search(axis).active  # RFS: search completed


def expired(vm: VirtualModule, w: Wait) -> bool:
    return w.deadline is not None and vm.now >= w.deadline
