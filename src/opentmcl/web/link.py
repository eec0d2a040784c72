"""Turns on the link (docs/dashboard.md "Stop all"): every request the dashboard sends to a module
takes a turn on a `LinkGate`, one per host `Client`, so a stop is never starved by other work.

- Turns are handed over first come, first served (a thread that gives the link back and asks
  again at once queues behind those already waiting; a plain lock lets it barge in again).
- A stop (`LinkGate.urgent()`: STOP ALL, a console MST, 128 or 131, the program view's Stop and
  Reset) goes ahead of every ordinary request waiting.
- A turn is one request or one short batch (`TURN_REQUESTS` reads). Work that holds the link
  over several requests (a program download from 132 to 133, a baud-rate scan) looks at
  `urgent_waiting` between two of them and gives the link up: it leaves download mode and ends,
  or lends the link back at its own baud rate (`yield_turn`).

`LinkModule` and `LinkLoader` are the host's `Module` and `Loader` with each request in a turn.
"""
from __future__ import annotations

import contextlib
import threading
import weakref
from collections import deque
from collections.abc import Iterator, Sequence

from ..host import Client, Module
from ..host.client import Answer
from ..host.loader import Loader
from ..lang.binfile import Instruction
from ..protocol.frame import Reply

TURN_REQUESTS = 12  # reads of one batch turn: position and speed of six axes, 0.25 s at 9600 baud
STOP_COMMANDS = frozenset({3, 128, 131})  # MST (manual 3.6.3), stop and reset the application (3.6.36)


class _Waiter:
    __slots__ = ("depth", "ident")

    def __init__(self, ident: int, depth: int) -> None:
        self.ident, self.depth = ident, depth


class LinkGate:
    """A re-entrant lock handed over in order, stops first (the module docstring)."""

    def __init__(self) -> None:
        self._cond = threading.Condition(threading.Lock())
        self._owner: int | None = None
        self._depth = 0
        self._urgent: deque[_Waiter] = deque()
        self._normal: deque[_Waiter] = deque()

    @property
    def waiting(self) -> int:
        """Threads waiting for a turn (stops and others)."""
        return len(self._urgent) + len(self._normal)

    @property
    def urgent_waiting(self) -> bool:
        """A stop waits for the link: give it up at the next point where that is safe."""
        return bool(self._urgent)

    def acquire(self, urgent: bool = False, depth: int = 1) -> None:
        me = threading.get_ident()
        with self._cond:
            if self._owner == me:
                self._depth += depth
                return
            if self._owner is None and not self._urgent and (urgent or not self._normal):
                self._owner, self._depth = me, depth
                return
            waiter = _Waiter(me, depth)
            (self._urgent if urgent else self._normal).append(waiter)
            while self._owner != me:
                self._cond.wait()

    def release(self) -> int:
        """Give one level back; the depth left."""
        with self._cond:
            if self._owner != threading.get_ident():
                raise RuntimeError("the link is not held by this thread")
            self._depth -= 1
            if self._depth == 0:
                self._hand_over()
            return self._depth

    def _hand_over(self) -> None:
        queue = self._urgent or self._normal
        if queue:
            waiter = queue.popleft()
            self._owner, self._depth = waiter.ident, waiter.depth
            self._cond.notify_all()
        else:
            self._owner = None

    def yield_turn(self) -> None:
        """Let the stops waiting go first, then carry on (the caller holds the link)."""
        if not self._urgent:
            return
        me = threading.get_ident()
        with self._cond:
            if self._owner != me:
                raise RuntimeError("the link is not held by this thread")
            depth, self._depth = self._depth, 0
            self._hand_over()
            waiter = _Waiter(me, depth)
            self._normal.appendleft(waiter)  # first of the ordinary ones: the work it holds goes on
            while self._owner != me:
                self._cond.wait()

    def __enter__(self) -> LinkGate:
        self.acquire()
        return self

    def __exit__(self, *exc: object) -> None:
        self.release()

    @contextlib.contextmanager
    def urgent(self) -> Iterator[LinkGate]:
        """The link for a stop: ahead of every ordinary request waiting."""
        self.acquire(urgent=True)
        try:
            yield self
        finally:
            self.release()

    def turn(self, command: int) -> contextlib.AbstractContextManager[LinkGate]:
        """A turn for one request of `command`: urgent for the stop commands."""
        return self.urgent() if command in STOP_COMMANDS else self


_GATES: weakref.WeakKeyDictionary[Client, LinkGate] = weakref.WeakKeyDictionary()
_GATES_LOCK = threading.Lock()


def link_gate(client: Client) -> LinkGate:
    """The one gate of `client`'s link, shared by every dashboard and scan that uses it."""
    with _GATES_LOCK:
        gate = _GATES.get(client)
        if gate is None:
            gate = _GATES[client] = LinkGate()
        return gate


class LinkModule(Module):
    """A host `Module` whose requests each take a turn on the link's gate (stops urgently)."""

    def __init__(self, module: Module, gate: LinkGate | None = None) -> None:
        super().__init__(module.client, module.address, module.profile)
        self.gate = gate if gate is not None else link_gate(module.client)

    def request(self, command: int, type: int = 0, motor: int = 0, value: int = 0, *,
                timeout: float | None = None) -> Answer:
        with self.gate.turn(command):
            return super().request(command, type, motor, value, timeout=timeout)

    def reply(self, command: int, type: int = 0, motor: int = 0, value: int = 0, *,
              timeout: float | None = None) -> Reply:
        with self.gate.turn(command):
            return super().reply(command, type, motor, value, timeout=timeout)

    def request_many(self, requests: Sequence[tuple[int, int, int, int]], *,
                     timeout: float | None = None) -> list[Answer]:
        with self.gate:
            return super().request_many(requests, timeout=timeout)


class LinkLoader(Loader):
    """A host `Loader` (program control, download, read-back) whose requests each take a turn."""

    def __init__(self, module: LinkModule) -> None:
        super().__init__(module)
        self.gate = module.gate

    def request(self, command: int, type: int = 0, motor: int = 0, value: int = 0) -> Reply:
        with self.gate.turn(command):
            return super().request(command, type, motor, value)

    def read_one(self, address: int) -> Instruction:
        with self.gate:
            return super().read_one(address)
