"""TMCL interrupts: vectors, enables, priority, timers and event sources
(TMCM-6212 manual 3.5.6, 3.6.30-3.6.33, 5.4; PD86-1180 manual 4.4.2.6, 4.6.32-4.6.35, 6.4).

An interrupt is latched (pending) when it occurs while a program is running,
interrupt processing is globally on (EI 255), the interrupt itself is enabled
(EI n) and a vector is defined (VECT n, label). The interpreter dispatches the
pending interrupt with the lowest number first ("Interrupts with a lower number
have a higher priority", manual 5.4); there is no nesting.

Sources:

- timers 0-2: period in ms in global parameter n of bank 3; the timer restarts
  its phase whenever its period is written; period 0 = off;
- target position reached 3 + axis: rising edge of the axis's position-reached flag;
- stop switches 27 + 2 * axis (left, AP11) and 28 + 2 * axis (right, AP10), input
  change 39 + port (digital input bank 0): level transitions selected by bank-3
  parameter n (0 off, 1 low-high, 2 high-low, 3 both);
- stallGuard 15 + axis and deviation 21 + axis: the physical-world model calls
  `trigger(n)` (there is no level to poll).

Levels are sampled whenever the virtual module looks its next event up again
(at the start of every `advance`, after every write that can move it) and at
every event tick, so a transition made between two `advance` calls (e.g.
`vm.io.drive_input`) or by a command is seen at the time it was made.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

from ..motion import CLOCK_HZ
from .program import RUNNING, STEPPING
from .status import TmclStatus

if TYPE_CHECKING:
    from .vm import VirtualModule

GLOBAL = 255
TIMERS = (0, 1, 2)
TARGET_REACHED, STALL, DEVIATION, STOP_SWITCH, INPUT_CHANGE = 3, 15, 21, 27, 39
TICKS_PER_MS = CLOCK_HZ // 1000
_PERIOD_0, _PERIOD_1, _PERIOD_2 = ((3, n) for n in TIMERS)  # bank 3 parameter n: timer n's period in ms
LOW_HIGH, HIGH_LOW = 1, 2


def _earliest(ticks: list[int | None]) -> int | None:
    best = None
    for t in ticks:
        if t is not None and (best is None or t < best):
            best = t
    return best


class Interrupts:
    def __init__(self, vm: VirtualModule) -> None:
        self.vm = vm
        self._power_up()

    def _power_up(self) -> None:
        """Everything off: no vectors, enables, pending interrupts or timer phases."""
        self.vectors: dict[int, int] = {}
        self.enabled: set[int] = set()
        self.global_enable = False
        self.pending: set[int] = set()
        self.active: int | None = None          # number of the interrupt being handled
        self._periods: list[int | None] = [None] * len(TIMERS)  # period (ms) last seen per timer
        self._due: list[int | None] = [None] * len(TIMERS)      # next expiry tick per timer
        self._raw_periods: tuple[int, ...] | None = None  # bank 3 parameters 0-2 as last read
        self._first_due: int | None = None      # min of `_due` (None: no timer runs)
        self._levels: dict[int, int] = {}       # last sampled level of edge sources

    # --- EI / DI / VECT ---------------------------------------------------------------
    def _check(self, number: int) -> None:
        if number != GLOBAL and number not in self.vm.profile.interrupts:
            raise TmclStatus(3)

    def enable(self, number: int, on: bool) -> None:
        """EI / DI; 255 switches interrupt processing on or off as a whole."""
        self._check(number)
        if number == GLOBAL:
            self.global_enable = on
            return
        self._levels.pop(number, None)  # start edge detection afresh
        if on:
            self.enabled.add(number)
        else:
            self.enabled.discard(number)
            self.pending.discard(number)

    def set_vector(self, number: int, address: int) -> None:
        """VECT: the handler's address; vectors can be redefined (manual 3.6.32)."""
        self._check(number)
        if number == GLOBAL:  # the EI 255 / DI 255 switch, not a vector (docs/assumptions.md)
            raise TmclStatus(3)
        if not 0 <= address < self.vm.profile.program_memory:
            raise TmclStatus(4)
        self.vectors[number] = address

    def reset(self) -> None:
        """Everything off, as after power-up (command 131 reset application)."""
        self._power_up()

    # --- occurrence ------------------------------------------------------------------
    def accepting(self, number: int) -> bool:
        """Would an occurrence of `number` be latched now?"""
        return (self.global_enable and number in self.enabled and number in self.vectors
                and self.vm.application_status in (RUNNING, STEPPING))

    def trigger(self, number: int) -> bool:
        """An interrupt source fired (also the entry point for the physical-world model and
        tests). Returns True when it was latched."""
        if self.accepting(number):
            self.pending.add(number)
            return True
        return False

    def next_dispatch(self) -> int | None:
        """Number of the pending interrupt to handle next (lowest number), or None."""
        if self.active is not None or not self.global_enable or not self.pending:
            return None
        best = None
        enabled, vectors = self.enabled, self.vectors
        for n in self.pending:
            if (best is None or n < best) and n in enabled and n in vectors:
                best = n
        return best

    # --- timers ----------------------------------------------------------------------
    def _refresh_timers(self, now: int) -> None:
        """Re-phase a timer whose period (bank 3, parameter n) was written since the last look."""
        get = self.vm.globals.ram.get
        raw = (get(_PERIOD_0, 0), get(_PERIOD_1, 0), get(_PERIOD_2, 0))  # TIMERS
        if raw == self._raw_periods:  # the usual case: one comparison
            return
        self._raw_periods = raw
        for n in TIMERS:
            period = raw[n] & 0xFFFFFFFF
            if period != self._periods[n]:
                self._periods[n] = period
                self._due[n] = now + period * TICKS_PER_MS if period else None
        self._first_due = _earliest(self._due)

    def _run_timers(self, now: int) -> None:
        first = self._first_due
        if first is None or first > now:
            return
        for n in TIMERS:
            due, period = self._due[n], self._periods[n]
            if due is None or due > now or not period:  # a timer is due only with a period
                continue
            step = period * TICKS_PER_MS
            self._due[n] = due + ((now - due) // step + 1) * step
            self.trigger(n)
        self._first_due = _earliest(self._due)

    def first_due(self) -> int | None:
        """The earliest tick a timer rolls over (whether its interrupt is latched or not)."""
        return self._first_due

    def next_timer_event(self, now: int, refresh: bool = True) -> int | None:
        """Earliest expiry of a timer whose interrupt would be latched."""
        if refresh:
            self._refresh_timers(now)
        best = None
        for n in TIMERS:
            due = self._due[n]
            if due is not None and (best is None or due < best) and self.accepting(n):
                best = due
        return best

    # --- level sources -------------------------------------------------------------------
    def _level(self, n: int) -> tuple[int, int] | None:
        """(level, transition mode) of an edge source, or None if n is not one."""
        vm = self.vm
        axes = len(vm.axes)
        if TARGET_REACHED <= n < TARGET_REACHED + axes:
            return int(vm.engine_now(n - TARGET_REACHED).position_reached), LOW_HIGH
        if STOP_SWITCH <= n < STOP_SWITCH + 2 * axes:
            axis = vm.axes[(n - STOP_SWITCH) // 2]
            param = 11 if (n - STOP_SWITCH) % 2 == 0 else 10  # left / right limit switch state
            try:
                level = axis.get(param)
            except TmclStatus:
                return None
            return int(bool(level)), vm.globals.get_raw(3, n)
        if n >= INPUT_CHANGE and (0, n - INPUT_CHANGE) in vm.io.ports:
            return int(bool(vm.io.read((0, n - INPUT_CHANGE)))), vm.globals.get_raw(3, n)
        return None

    def _sample_levels(self) -> None:
        for n in self.enabled:
            if n < TARGET_REACHED:  # a timer: no level
                continue
            if not self.accepting(n):
                self._levels.pop(n, None)
                continue
            got = self._level(n)
            if got is None:
                continue
            level, mode = got
            old = self._levels.get(n)
            self._levels[n] = level
            if old is None or old == level:
                continue
            if (mode & LOW_HIGH and level) or (mode & HIGH_LOW and not level):
                self.pending.add(n)

    def poll(self, now: int, refresh: bool = True) -> None:
        """Latch what occurred up to tick `now` (timers, level transitions). `refresh` False:
        no period was written since the last look (Scheduler.limit_held)."""
        if refresh:
            self._refresh_timers(now)
        self._run_timers(now)
        if self.enabled and self.global_enable:
            self._sample_levels()
