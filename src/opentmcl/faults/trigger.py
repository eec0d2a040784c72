"""When a fault fires: by chance, on the n-th matching request, at a time, or by name; every
decision drawn from the fault's own seeded random stream, so a run repeats from its seed."""
from __future__ import annotations

import random

from .spec import Fault


def stream(seed: int, *scope: object) -> random.Random:
    """The random stream of one fault in one place (`scope`: e.g. "link", 2, index): the same seed
    and scope give the same stream in every run and on every platform."""
    return random.Random("/".join(map(str, (seed, *scope))))


class Trigger:
    """One fault's trigger: its random stream, the matching requests seen, once-only state."""

    __slots__ = ("fault", "rng", "seen", "done", "armed")

    def __init__(self, fault: Fault, rng: random.Random) -> None:
        self.fault = fault
        self.rng = rng
        self.seen = 0
        self.done = False
        self.armed = 0
        """Times it was triggered by name and has not fired yet (it fires on the next matching request)."""

    def fires(self, command: int, type_: int, motor: int, t: float) -> bool:
        """Does the fault fire on this request at time `t`?"""
        f = self.fault
        if not f.matches(command, type_, motor):
            return False
        if self.armed:
            self.armed -= 1
            return True
        if self.done or (f.at is not None and t < f.at):
            return False
        if f.count is not None:
            self.seen += 1
            self.done = self.seen >= f.count
            return self.done
        if f.probability is not None:
            return self.rng.random() < f.probability
        if f.at is not None:  # `at` alone: the first matching request from then on
            self.done = True
            return True
        return False
