"""Turns on the link (docs/dashboard.md "Stop all"): every request the dashboard sends to a module
takes a turn on the link's gate (one `handover.HandoverLock` per host `Client`), so a stop is never
starved by other work.

- Turns are handed over first come, first served (a thread that gives the link back and asks
  again at once queues behind those already waiting; a plain lock lets it barge in again).
- A stop (`gate.hold(STOP)`: STOP ALL, a console MST, 128 or 131, the program view's Stop and
  Reset) goes ahead of every ordinary request waiting.
- A turn is one request or one short batch (`TURN_REQUESTS` reads). Work that holds the link
  over several requests (a program download from 132 to 133, a baud-rate scan) looks at
  `stops_waiting` between two of them and gives the link up: it leaves download mode and ends,
  or lends the link back at its own baud rate (`yield_to_stops`).

`LinkModule` and `LinkLoader` are the host's `Module` and `Loader` with each request in a turn.
"""
from __future__ import annotations

import contextlib
import threading
import weakref
from collections.abc import Sequence

from ..handover import STOP, HandoverLock
from ..host import Client, Module
from ..host.client import Answer
from ..host.loader import Loader
from ..lang.binfile import Instruction
from ..protocol.frame import Reply
from ..protocol.opcodes import STOP_COMMANDS

TURN_REQUESTS = 12  # reads of one batch turn: position and speed of six axes, 0.25 s at 9600 baud


def turn(gate: HandoverLock, command: int) -> contextlib.AbstractContextManager[HandoverLock]:
    """A turn for one request of `command`: ahead of the others for the stop commands."""
    return gate.hold(STOP) if command in STOP_COMMANDS else gate


_GATES: weakref.WeakKeyDictionary[Client, HandoverLock] = weakref.WeakKeyDictionary()
_GATES_LOCK = threading.Lock()


def link_gate(client: Client) -> HandoverLock:
    """The one gate of `client`'s link, shared by every dashboard and scan that uses it."""
    with _GATES_LOCK:
        gate = _GATES.get(client)
        if gate is None:
            gate = _GATES[client] = HandoverLock()
        return gate


class LinkModule(Module):
    """A host `Module` whose requests each take a turn on the link's gate (stops urgently)."""

    def __init__(self, module: Module, gate: HandoverLock | None = None) -> None:
        super().__init__(module.client, module.address, module.profile)
        self.gate = gate if gate is not None else link_gate(module.client)

    def request(self, command: int, type: int = 0, motor: int = 0, value: int = 0, *,
                timeout: float | None = None) -> Answer:
        with turn(self.gate, command):
            return super().request(command, type, motor, value, timeout=timeout)

    def reply(self, command: int, type: int = 0, motor: int = 0, value: int = 0, *,
              timeout: float | None = None) -> Reply:
        with turn(self.gate, command):
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
        with turn(self.gate, command):
            return super().request(command, type, motor, value)

    def read_one(self, address: int) -> Instruction:
        with self.gate:
            return super().read_one(address)
