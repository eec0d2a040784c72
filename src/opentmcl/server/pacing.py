"""Real-time pacing: the simulation in bounded slices, and how far the modules' clock lags.

A served module must answer every request in bounded time whatever it simulates
(docs/architecture.md "Real time"). The bus therefore never advances its modules by more than
one slice while it holds its lock: a slice is as much virtual time as `budget` seconds of work
buy at the measured cost of simulating (CPU seconds per virtual second, `Pacer.cost`), at least
`MIN_SLICE`, and, on a bus with a clock thread, at most `FIRST_SLICE` before the cost is known.
What is not simulated yet is the modules' **lag** behind the wall clock: the clock thread works it
off slice by slice, letting every waiting request go first, between two slices and between two
modules of a slice.

When the simulation cannot keep up (a TMCL program that costs more CPU than the machine has),
the lag grows. It is caught up as long as it stays within `MAX_LAG`; beyond that, the rest is
dropped: the modules' clock then simply runs slower than the wall clock, and the replies stay on
time. The lag, the worst lag and the seconds dropped are reported (`Pacer.report`) and logged
at most once per `LOG_EVERY` seconds (docs/endpoints.md "When the simulation cannot keep up").
"""
from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable
from typing import NamedTuple

log = logging.getLogger("opentmcl.server")

REQUEST_BUDGET = 0.001
"""CPU seconds a host request may spend bringing the modules towards the wall clock."""
SLICE_BUDGET = 0.002
"""CPU seconds one slice of the clock thread may take (by the cost estimate)."""
MIN_SLICE = 0.0005
"""Virtual seconds a slice advances at least, however costly the simulation."""
FIRST_SLICE = 0.01
"""Virtual seconds a slice advances at most before the cost has been measured (the first slice:
a TMCL program started from the EEPROM at power-up may be costly)."""
MAX_LAG = 1.0
"""Seconds the modules' clock may lag the wall clock and still catch up; beyond, it is dropped."""
LOG_EVERY = 10.0
"""Seconds between two log lines about the lag."""
REPORT_LAG = 0.1
"""A lag below this many seconds is not logged (the clock thread works it off within a tick)."""


class ClockReport(NamedTuple):
    """How the modules' clock keeps up with the wall clock (seconds)."""

    lag: float
    """How far the modules' clock is behind the wall clock now."""
    worst: float
    """The largest lag seen since the server started."""
    dropped: float
    """Wall-clock seconds the modules never simulated (lag beyond `MAX_LAG`)."""
    cost: float
    """Estimated CPU seconds per simulated second (above 1: the simulation cannot keep up)."""


class Pacer:
    """Which slice of virtual time to simulate next; the lag; the cost estimate."""

    def __init__(self, clock: Callable[[], float], *, max_lag: float = MAX_LAG,
                 work_clock: Callable[[], float] = time.thread_time) -> None:
        if not max_lag > 0:
            raise ValueError("max_lag must be > 0")
        self._clock = clock
        self._work = work_clock
        self.at = clock()
        """The wall-clock instant the modules' clock stands for."""
        self.max_lag = max_lag
        self.cost = 0.0
        self.worst = 0.0
        self.dropped = 0.0
        self._logged = -LOG_EVERY
        self._quiet_dropped = 0.0

    def step(self, now: float, budget: float, whole: bool = False, first: float = math.inf) -> float:
        """Virtual seconds to simulate now (the caller holds the bus): all of the lag at `now` when
        `budget` CPU seconds buy it at the estimated cost, else what they buy, at least `MIN_SLICE`
        (or nothing, if `whole`: a host request leaves a lag it cannot take whole to the clock thread);
        at most `first` (the served bus: `FIRST_SLICE`) while the cost is not measured yet."""
        behind = now - self.at
        if behind <= 0:
            return 0.0
        if not self.cost and behind > first:  # not measured yet: a first slice, to measure
            return 0.0 if whole else first
        if self.cost * behind <= budget:
            return behind
        if whole:
            return 0.0
        return min(behind, max(MIN_SLICE, budget / self.cost))

    def advanced(self, seconds: float, work: float, now: float) -> None:
        """`seconds` of virtual time were simulated with `work` CPU seconds; `now` is the wall clock.
        Updates the cost estimate (up at once, down slowly) and drops a lag beyond `max_lag`."""
        self.at += seconds
        if seconds > 0:
            rate = work / seconds
            self.cost = max(rate, 0.8 * self.cost + 0.2 * rate)
        behind = now - self.at
        if behind > self.worst:
            self.worst = behind
        if behind > self.max_lag:
            excess = behind - self.max_lag
            self.at += excess
            self.dropped += excess
            self._quiet_dropped += excess
        if behind >= REPORT_LAG:
            self._log(min(behind, self.max_lag))

    def work_clock(self) -> float:
        return self._work()

    def lag(self) -> float:
        return max(0.0, self._clock() - self.at)

    def report(self) -> ClockReport:
        return ClockReport(self.lag(), self.worst, self.dropped, self.cost)

    def _log(self, lag: float) -> None:
        now = time.monotonic()
        if now - self._logged < LOG_EVERY:
            return
        self._logged = now
        dropped = f"; {self._quiet_dropped:.1f} s dropped since the last line" if self._quiet_dropped else ""
        log.warning("the modules' clock is %.2f s behind the wall clock: the simulation costs %.2f CPU s "
                    "per second%s (docs/endpoints.md)", lag, self.cost, dropped)
        self._quiet_dropped = 0.0
