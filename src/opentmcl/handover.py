"""A re-entrant lock handed over in order of urgency (docs/architecture.md "Real time").

The served bus (server/bus.py) and the dashboard's link to a module (web/link.py) share one rule:
whoever waits is served in three classes, in this order, first come first served within a class:

- `STOP`: a request that stops motion or a program (MST, 128, 131; the dashboard's STOP ALL);
- `REQUEST`: every other request;
- `BACKGROUND`: work nobody waits for (the served bus's clock slices).

`release` hands the lock straight to the first waiter, so a thread that lets go and asks again at
once queues behind everyone who was already waiting: nothing is starved by a busy neighbour, and a
stop waits for at most the one holder it finds. A holder doing long work in steps can let the
stops waiting go first and then carry on ahead of the other waiters (`yield_to_stops`), or let
every stop and request waiting go first and carry on after them (`yield_to_waiting`: the served
bus's clock slice, between two modules).

    lock = HandoverLock()
    with lock:                   # a REQUEST
        ...
    with lock.hold(STOP):        # a stop
        ...
"""
from __future__ import annotations

import threading
from collections import deque
from collections.abc import Iterator
from contextlib import contextmanager

STOP, REQUEST, BACKGROUND = 0, 1, 2
"""Urgency classes, most urgent first."""


class _Waiter:
    __slots__ = ("depth", "gate", "ident")

    def __init__(self, ident: int, depth: int) -> None:
        self.ident, self.depth = ident, depth
        self.gate = threading.Lock()
        self.gate.acquire()


class HandoverLock:
    """A re-entrant lock handed over to the most urgent, then the earliest, waiter."""

    def __init__(self) -> None:
        self._mutex = threading.Lock()
        self._owner: int | None = None
        self._depth = 0
        self._queues: tuple[deque[_Waiter], ...] = (deque(), deque(), deque())

    def acquire(self, urgency: int = REQUEST, depth: int = 1) -> bool:
        """Wait for the lock as a thread of class `urgency` and take it (`depth` levels); True."""
        me = threading.get_ident()
        with self._mutex:
            if self._owner == me:
                self._depth += depth
                return True
            if self._owner is None and not any(self._queues[:urgency + 1]):
                self._owner, self._depth = me, depth
                return True
            waiter = _Waiter(me, depth)
            self._queues[urgency].append(waiter)
        waiter.gate.acquire()  # `_hand_over` made us the owner before it opened the gate
        return True

    def release(self) -> int:
        """Give one level back; the depth still held."""
        with self._mutex:
            if self._owner != threading.get_ident():
                raise RuntimeError("cannot release a lock this thread does not hold")
            self._depth -= 1
            if self._depth == 0:
                self._hand_over()
            return self._depth

    def _hand_over(self) -> None:
        for queue in self._queues:
            if queue:
                waiter = queue.popleft()
                self._owner, self._depth = waiter.ident, waiter.depth
                waiter.gate.release()
                return
        self._owner = None

    def waiting(self) -> int:
        """How many threads wait for the lock."""
        return sum(len(q) for q in self._queues)

    @property
    def stops_waiting(self) -> bool:
        """A stop waits: a holder doing long work gives the lock up at its next safe point."""
        return bool(self._queues[STOP])

    def held(self) -> bool:
        """Does the calling thread hold the lock?"""
        return self._owner == threading.get_ident()

    def yield_to_stops(self) -> None:
        """Let the stops waiting go first, then take the lock back ahead of the other waiters (the
        caller holds it, at any depth)."""
        if not self._queues[STOP]:
            return
        me = threading.get_ident()
        with self._mutex:
            if self._owner != me:
                raise RuntimeError("cannot yield a lock this thread does not hold")
            waiter = _Waiter(me, self._depth)
            self._depth = 0
            self._hand_over()
            self._queues[REQUEST].appendleft(waiter)
        waiter.gate.acquire()

    def yield_to_waiting(self) -> None:
        """Let the stops and requests waiting now go first, then take the lock back after them
        (behind requests that come meanwhile only if they came earlier; ahead of `BACKGROUND`
        waiters). The caller holds the lock, at any depth."""
        if not (self._queues[STOP] or self._queues[REQUEST]):
            return
        me = threading.get_ident()
        with self._mutex:
            if self._owner != me:
                raise RuntimeError("cannot yield a lock this thread does not hold")
            waiter = _Waiter(me, self._depth)
            self._queues[REQUEST].append(waiter)
            self._depth = 0
            self._hand_over()
        waiter.gate.acquire()

    def __enter__(self) -> HandoverLock:
        self.acquire()
        return self

    def __exit__(self, *exc: object) -> None:
        self.release()

    @contextmanager
    def hold(self, urgency: int) -> Iterator[HandoverLock]:
        """``with lock.hold(STOP):`` takes the lock as a thread of class `urgency`."""
        self.acquire(urgency)
        try:
            yield self
        finally:
            self.release()
