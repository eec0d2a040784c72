"""The bus lock: re-entrant, handed over in order of urgency (docs/architecture.md "Real time").

Whoever waits for the bus is served in three classes, in this order, first come first served
within a class:

- `STOP`: a request that stops motion or a program (MST, 128, 131; the dashboard's STOP ALL);
- `REQUEST`: every other host request;
- `BACKGROUND`: the clock thread's slices of simulation.

`release` hands the lock straight to the first waiter, so a thread that lets go and asks again
(the clock thread between two slices) queues behind everyone who was already waiting: a slice
never starts while a host request waits, and a stop waits for at most the one slice or request
that holds the bus when it arrives.

`with bus.lock:` takes it as a `REQUEST`; `bus.lock.hold(STOP)` in a `with` takes it as a stop.
"""
from __future__ import annotations

import heapq
import itertools
import threading
from collections.abc import Iterator
from contextlib import contextmanager

STOP, REQUEST, BACKGROUND = 0, 1, 2
"""Urgency classes of `BusLock.acquire`, most urgent first."""


class BusLock:
    """A re-entrant lock that is handed over to the most urgent, then the earliest, waiter."""

    def __init__(self) -> None:
        self._mutex = threading.Lock()
        self._owner: int | None = None
        self._depth = 0
        self._waiters: list[tuple[int, int, int, threading.Lock]] = []  # (class, order, thread, gate)
        self._order = itertools.count()

    def acquire(self, urgency: int = REQUEST) -> bool:
        """Wait for the lock (as a thread of class `urgency`) and take it; True."""
        me = threading.get_ident()
        with self._mutex:
            if self._owner == me:
                self._depth += 1
                return True
            if self._owner is None and not self._waiters:
                self._owner, self._depth = me, 1
                return True
            gate = threading.Lock()
            gate.acquire()
            heapq.heappush(self._waiters, (urgency, next(self._order), me, gate))
        gate.acquire()  # `release` made us the owner before it opened the gate
        return True

    def release(self) -> None:
        with self._mutex:
            if self._owner != threading.get_ident():
                raise RuntimeError("cannot release a bus lock this thread does not hold")
            self._depth -= 1
            if self._depth:
                return
            if self._waiters:
                _urgency, _order, thread, gate = heapq.heappop(self._waiters)
                self._owner, self._depth = thread, 1
                gate.release()
            else:
                self._owner = None

    def waiting(self) -> int:
        """How many threads wait for the lock (without taking it)."""
        return len(self._waiters)

    def held(self) -> bool:
        """Does the calling thread hold the lock?"""
        return self._owner == threading.get_ident()

    __enter__ = acquire

    def __exit__(self, *exc: object) -> None:
        self.release()

    @contextmanager
    def hold(self, urgency: int) -> Iterator[None]:
        """``with lock.hold(STOP):`` takes the lock as a thread of class `urgency`."""
        self.acquire(urgency)
        try:
            yield
        finally:
            self.release()
