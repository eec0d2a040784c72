"""What fired: every fault that acted is recorded with its time, so traces, captures, the CLI and
the dashboard show it (docs/faults.md "Seeing what fired")."""
from __future__ import annotations

import logging
import threading
from collections.abc import Callable
from dataclasses import dataclass

from .spec import Fault

log = logging.getLogger("opentmcl.faults")

MAX_KEPT = 100_000
"""Records a log keeps (the oldest go first); `FaultLog.count` counts them all."""


@dataclass(frozen=True)
class Fired:
    """A fault that acted at `t` seconds (the log's clock), with what it did."""

    t: float
    kind: str
    name: str | None
    detail: str

    @property
    def label(self) -> str:
        return self.name or self.kind

    def text(self) -> str:
        named = f"{self.name} ({self.kind})" if self.name else self.kind
        return f"{self.t:.6f} s  {named}: {self.detail}"


class FaultLog:
    """The faults fired, in order; thread-safe. `clock` gives the time of a record (seconds: the
    module's virtual time in process, the wall clock since the start of a server)."""

    def __init__(self, clock: Callable[[], float] | None = None) -> None:
        self.clock: Callable[[], float] = clock if clock is not None else (lambda: 0.0)
        self.fired: list[Fired] = []
        self.count = 0
        """Records made so far (also those no longer kept)."""
        self.listeners: list[Callable[[Fired], None]] = []
        """Called with each record as it is made (the proxy writes it to its capture)."""
        self._lock = threading.Lock()

    def record(self, fault: Fault | str, detail: str, t: float | None = None) -> Fired:
        kind, name = (fault.kind, fault.name) if isinstance(fault, Fault) else (fault, None)
        entry = Fired(self.clock() if t is None else t, kind, name, detail)
        with self._lock:
            self.fired.append(entry)
            self.count += 1
            if len(self.fired) > MAX_KEPT:
                del self.fired[:len(self.fired) - MAX_KEPT]
            listeners = list(self.listeners)
        log.info("fault %s", entry.text())
        for listener in listeners:
            listener(entry)
        return entry

    def since(self, number: int) -> list[Fired]:
        """The records from the `number`-th (counting from 0) on, as far as they are kept."""
        with self._lock:
            first = self.count - len(self.fired)
            return list(self.fired[max(0, number - first):])

    def __len__(self) -> int:
        return self.count
