"""The oracle of the time model (docs/architecture.md "Time"): a module that takes one event per
program instruction and looks every next event up afresh, with none of the scheduler's caches.

The product runs instructions ahead of the events, keeps the next-event limit while nothing was
written and carries it from one `advance` to the next; every shortcut must give exactly the state
this slow model gives. The equivalence tests compare the two (test_folded_events.py,
test_next_event_cache*.py, test_carry.py)."""
from __future__ import annotations

from opentmcl import VirtualModule
from opentmcl.firmware.effects import Effect
from opentmcl.firmware.interpreter import Interpreter
from opentmcl.firmware.scheduler import Scheduler

AFRESH = Effect.ENGINES | Effect.EVENTS
"""Dropped before every look-up: the limit and the engines' own next events too, so that a command
whose effect the table under-declares shows as a difference from the product."""


class ReferenceScheduler(Scheduler):
    """Every next event looked up afresh; no limit carried to the next `advance`."""

    def limit_event(self) -> int | None:
        self.invalidate(AFRESH)
        return super().limit_event()

    def advance_to(self, until: int) -> None:
        super().advance_to(until)
        self.invalidate(AFRESH)


class ReferenceInterpreter(Interpreter):
    """One event per instruction: nothing runs ahead."""

    def run_ahead(self) -> None:
        return None


class ReferenceModule(VirtualModule):
    scheduler_class = ReferenceScheduler
    interpreter_class = ReferenceInterpreter
