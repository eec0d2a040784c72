"""The faults of one running set-up (a server, a sim:// link): the plan, its seed, the log of
what fired, and triggering a fault by name (docs/faults.md "Triggering by name").

The board hands each link its `LinkFaults` and each module its faults, all drawing on streams
derived from the one seed; `trigger(name)` fires the named fault wherever it lives.
"""
from __future__ import annotations

import logging
import math
import random
import threading
import weakref
from collections.abc import Callable, Collection
from contextlib import AbstractContextManager
from typing import Protocol

from .link import LinkFaults, Pending
from .log import FaultLog
from .spec import Fault, FaultError, FaultPlan
from .trigger import stream

log = logging.getLogger("opentmcl.faults")


class Triggerable(Protocol):
    """What holds faults that fire by name (a link's `LinkFaults`, a module's faults)."""

    def trigger(self, name: str, t: float) -> bool: ...

    def names(self) -> list[str]: ...


def new_seed() -> int:
    """A seed for a plan that gives none (reported, so the run can be repeated with it)."""
    return random.SystemRandom().randrange(2**32)


class FaultBoard:
    """The armed plan of one set-up. `clock`: seconds since the set-up started (the log's time)."""

    def __init__(self, plan: FaultPlan, clock: Callable[[], float] | None = None) -> None:
        self.plan = plan if plan.seed is not None else plan.with_seed(new_seed())
        self.seed: int = self.plan.seed if self.plan.seed is not None else 0
        self.log = FaultLog(clock)
        self.lock: AbstractContextManager[object] = threading.RLock()
        """Held while a fault is triggered by name (a server passes its bus lock)."""
        self._targets: weakref.WeakSet[Triggerable] = weakref.WeakSet()
        self._links: weakref.WeakSet[LinkFaults] = weakref.WeakSet()
        self.pending = Pending()
        """Named link faults triggered and not fired yet: the next matching request of any link."""
        self.down_until = -math.inf
        """Every link passes nothing before this time (a `link_down` triggered by name); a link
        opened meanwhile is down too."""
        self._opened = 0
        log.info("fault plan: %d fault(s), seed %d", len(plan.faults), self.seed)

    def names(self) -> list[str]:
        """The named faults: the plan's and those of the modules and links attached (a scenario's)."""
        out = self.plan.names()
        for target in list(self._targets):  # modules (their scenario's faults too)
            out += [n for n in target.names() if n not in out]
        return out

    def link(self, scope: str = "link", kinds: Collection[str] | None = None) -> LinkFaults | None:
        """The link faults of a new link (None when the plan has none); each link its own streams.
        `kinds`: those the link can have (a CAN frame is never cut), others are left to other links."""
        faults = tuple(f for f in self.plan.link_faults if kinds is None or f.kind in kinds)
        if not faults:
            return None
        self._opened += 1
        number = self._opened
        link = LinkFaults(faults, lambda i, f: stream(self.seed, scope, number, i, f.kind), self.log, self.pending)
        link.down_until = self.down_until
        self._links.add(link)
        return link

    def module_faults(self, address: int) -> list[tuple[Fault, random.Random]]:
        """The module faults of the module at `address` (those without an address: every module),
        each with its random stream."""
        return [(f, stream(self.seed, "module", address, i, f.kind))
                for i, f in enumerate(self.plan.faults)
                if not f.link and (f.address is None or f.address == address)]

    def attach(self, target: Triggerable) -> None:
        self._targets.add(target)

    def trigger(self, name: str) -> list[str]:
        """Fire the fault called `name` now (a link fault: on the next request). FaultError for a
        name the plan does not have; returns what fired it (one line each)."""
        if name not in self.names():
            known = ", ".join(self.names()) or "none"
            raise FaultError(f"no fault named {name!r} (named faults: {known})")
        with self.lock:
            t = self.log.clock()
            hits = [f"module {getattr(target, 'address', '?')}" for target in list(self._targets)
                    if target.trigger(name, t)]
            hits += self._trigger_link(name, t)
        if not hits:
            raise FaultError(f"fault {name!r} has nowhere to act (no module it belongs to)")
        return hits

    def _trigger_link(self, name: str, t: float) -> list[str]:
        fault = next((f for f in self.plan.link_faults if f.name == name), None)
        if fault is None:
            return []
        if fault.kind == "link_down":
            duration = fault.duration or 0.0
            self.down_until = max(self.down_until, t + duration)
            for link in list(self._links):
                link.go_down(fault, t, "triggered by name", record=False)
            self.log.record(fault, f"link down for {duration:g} s (triggered by name)", t)
            return ["every link: down now"]
        self.pending.add(name)
        return ["the next matching request on a link"]
