"""What a command or an outside call can change, as the scheduler's caches see it
(docs/architecture.md "Time": invalidation by effect).

Every command of the command table (table.py) declares its effect, so the scheduler knows which of
its caches a command leaves valid; whoever writes state outside a command (the world's Python API,
power-up) says what it changed with the same flags (`Scheduler.invalidate`).
"""
from __future__ import annotations

from enum import IntFlag


class Effect(IntFlag):
    NONE = 0
    """Registers, flags, stack, user variables, outputs: nothing any next event depends on."""
    READ = 1
    """Reads the engines or the world at the present tick: they are brought there, plans unchanged."""
    ENGINES = 2
    """May change an engine's plan, hence its next events and the world's (motion, ramp parameters)."""
    EVENTS = 4
    """May move another next event: timers, interrupts, heartbeats, inputs, GP values the look-up reads."""
    REQUESTS = 8
    """May change what a pre-bound request or a program's bound read answers (addresses, GP255,
    the module's banks and axes after a power-up)."""
    PROGRAM = 16
    """Program memory or the program's run state."""
    COMMAND = 32
    """A host command came: the next `advance` looks its events up afresh (no carried limit)."""


WRITE = Effect.ENGINES | Effect.EVENTS
"""What any write may move: the engines' plans and every other next event."""
ALL = Effect.READ | WRITE | Effect.REQUESTS | Effect.PROGRAM | Effect.COMMAND
"""Power-up, reset, factory defaults: every cache."""
