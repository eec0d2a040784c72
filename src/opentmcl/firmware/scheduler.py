"""The module's clock, its next-event look-up, and every cache that serves them
(docs/architecture.md "Time").

Time is an integer count of 16 MHz ticks. `advance_to(until)` jumps from event to event: an
engine's phase change, a heartbeat expiry, a timer, a world event (switch edge, load step, input
change), the program's own next instruction or WAIT timeout. Engines are advanced lazily: each
only at its own events, before a command touches it (`prepare`) and at the end.

Caches, and the one way to drop them (`invalidate(effect)`, effects.py):

- the **limit**: the next event of everything but the program (`limit_event`), kept while nothing
  was written (a write: Effect.ENGINES or Effect.EVENTS); when only a timer's event was reached,
  only the timers are looked up again;
- the engines' next events, looked up again after Effect.ENGINES;
- the **carried limit**: after an `advance_to` whose limit still holds, a later one that only
  pre-bound reads preceded only moves the clock and the engines (`_carry_until`);
- the caches other parts register (`register`): the request path's pre-bound handlers, the
  program's compiled steps, the world's list of axes that need events.

While a program runs, the interpreter executes instructions ahead of the event loop up to the
limit (`Interpreter.run_ahead`, `ahead_limit`) and takes what cannot run ahead as the module's
next event in place (`fold`).
"""
from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from ..motion import CLOCK_HZ
from .effects import ALL, Effect
from .program import RUNNING, STEPPING

if TYPE_CHECKING:
    from .vm import VirtualModule

_FAR = 1 << 63  # a tick no advance reaches
_INF = float("inf")
_RUNNING = (RUNNING, STEPPING)
# The flags as plain ints: an IntFlag's `&` runs Python code, and these tests run on every command.
_ENGINES = int(Effect.ENGINES)
_WRITES = int(Effect.ENGINES | Effect.EVENTS)
_ENDS_CARRY = _WRITES | int(Effect.COMMAND)
_NOT_READ = ~int(Effect.READ)


class Scheduler:
    """The clock of one `VirtualModule` and everything that decides when its next event is."""

    def __init__(self, vm: VirtualModule) -> None:
        self.vm = vm
        self.now = 0
        """The module's time in 16 MHz ticks since power-up of the object."""
        self.horizon: int | None = None
        """The end of the `advance_to` in progress: the program may run ahead up to here."""
        self._caches: dict[str, tuple[int, Callable[[], None]]] = {}
        self._engines: list[Any] = []
        self._axis_next: list[int | None] = []
        self._engine_next: int | None = None
        self._dirty = True            # an engine plan may have changed: their next events are looked up again
        self.synced_at = -1
        """The tick the engines were last all brought to (read it, never set it)."""
        self._limit: int | None = None
        self._limit_other: int | None = None  # the part of `_limit` that is not the timers'
        self._limit_ok = False        # `_limit` holds (only inside `advance_to`)
        self._carry_until = -1
        self._carry_hb = False
        self._quiet: bool | None = None  # World.quiet(), kept while the limit holds

    # --- caches ------------------------------------------------------------------------------
    def register(self, name: str, effect: Effect, forget: Callable[[], None]) -> None:
        """Call `forget` whenever something of `effect` changes: the cache `name` of another part
        (registering a name again replaces it, as a power-up's new parts do)."""
        self._caches[name] = (int(effect), forget)

    def invalidate(self, effect: Effect | int) -> None:
        """Something of `effect` changed: drop what depends on it."""
        effect = int(effect)
        if effect & _ENGINES:
            self._dirty = True
        if effect & _WRITES:
            self._limit_ok = False
            self._quiet = None
        if effect & _ENDS_CARRY:
            self._carry_until = -1
        for mask, forget in self._caches.values():
            if effect & mask:
                forget()

    def power_up(self) -> None:
        """New axes, banks and engines: every cache goes."""
        self._engines = [ax.engine for ax in self.vm.axes]
        self._axis_next = [None] * len(self._engines)
        self._engine_next = None
        self.synced_at = -1
        self.invalidate(ALL)

    def prepare(self, effect: Effect | int) -> None:
        """Before a command of `effect` acts: the engines are brought to now, and what it may
        change is dropped. A pure read (Effect.READ) leaves the engines' plans and events."""
        if self.synced_at != self.now:
            self._sync_engines()
        if int(effect) & _NOT_READ:
            self.invalidate(effect)

    # --- the clock ---------------------------------------------------------------------------
    @property
    def time(self) -> float:
        return self.now / CLOCK_HZ

    def advance(self, seconds: float) -> None:
        if not seconds >= 0 or seconds == _INF:  # also NaN
            raise ValueError(f"seconds must be a finite number >= 0, got {seconds!r}")
        self.advance_to(self.now + round(seconds * CLOCK_HZ))

    def advance_to(self, until: int) -> None:
        """Advance to absolute tick `until`, stopping at every event on the way. A call starts
        afresh unless only pre-bound reads came since the last one ended and its limit lies
        beyond `until` (the carried limit)."""
        self.horizon = until
        if self.now <= until < self._carry_until and not self._dirty \
                and not (self._carry_hb and self._heartbeat_by(until)):
            self.now = until
            self.sync_for_read()
            return
        self._carry_until = -1
        try:
            while self.now < until:
                self.event_at(self._next_event(until))
            self._carry_until = self._carry_limit()
        finally:
            self._limit_ok = False  # host commands come next
        self.sync_for_read()

    def event_at(self, tick: int) -> None:
        """Everything due at the event `tick` (> now): engines, world, heartbeats, the program."""
        self.now = tick
        vm = self.vm
        if tick == self._engine_next:
            self._engine_step(tick)
        if vm.world.service():
            self._limit_ok = False
        if vm.heartbeats.expire(tick):
            self.prepare(Effect.ENGINES)
            for engine in self._engines:  # GP68: "the motor will be stopped"
                engine.hard_stop()
        vm.interpreter.service()

    def _carry_limit(self) -> int:
        """Up to which tick the limit found by this `advance_to` holds for the next ones, if only
        pre-bound reads come in between; -1 with a program running or after a write."""
        vm = self.vm
        if not self._limit_ok or self._dirty or vm.application_status in _RUNNING:
            return -1
        limit = self._limit
        first = vm.interrupts.first_due()
        carry = _FAR if limit is None else limit
        if first is not None and first < carry:
            carry = first
        self._carry_hb = vm.heartbeats.on()
        return carry

    def _heartbeat_by(self, until: int) -> bool:
        hb = self.vm.heartbeats.deadline()
        return hb is not None and hb <= until

    def next_event_in(self) -> float | None:
        """Seconds until the next internal event (engine, heartbeat, program, world), or None."""
        self._limit_ok = False  # between `advance` calls: no cache (host commands came)
        try:
            nxt = self._next_event(self.now + 2**62)
        finally:
            self._limit_ok = False
        return None if nxt == self.now + 2**62 else (nxt - self.now) / CLOCK_HZ

    # --- the engines -------------------------------------------------------------------------
    def _engine_step(self, now: int) -> None:
        """Advance the engines whose event is due now; report arrivals (command 138)."""
        times = self._axis_next
        vm = self.vm
        for i, t in enumerate(times):
            if t == now:
                engine = self._engines[i]
                engine.advance(now)
                times[i] = engine.next_event()
                if vm.armed >> i & 1:
                    vm.report_arrival(i)
        self._engine_next = min((t for t in times if t is not None), default=None)

    def sync_for_read(self, engines: list[Any] | None = None) -> None:
        """Bring every engine (or those of `engines`, the ones a program's read looks at) to now
        for a pure read: within its segment an engine keeps its next event. Engines left behind
        follow at the next sync."""
        if self.synced_at == self.now:
            return
        if engines is None or engines is self._engines:
            self._sync_engines()
            return
        now = self.now
        for engine in engines:
            if engine.now < now:
                engine.advance(now)

    def engine_now(self, axis: int) -> Any:
        """The engine of `axis` brought to now, for a flag read outside a command (WAIT POS, the
        target-reached interrupt)."""
        engine = self._engines[axis]
        if self.synced_at != self.now and engine.now < self.now:
            engine.advance(self.now)
        return engine

    def _sync_engines(self) -> None:
        now = self.now
        for engine in self._engines:
            if engine.now < now:
                engine.advance(now)
        self.synced_at = now

    def _engine_event(self) -> int | None:
        if self._dirty:
            vm = self.vm
            self._axis_next = [e.next_event() for e in self._engines]
            armed = vm.armed
            for i in range(len(self._engines) if armed else 0):  # a move may end at once (MVP to where it is)
                if armed >> i & 1:
                    vm.report_arrival(i)
            self._engine_next = min((t for t in self._axis_next if t is not None), default=None)
            self._dirty = False
        return self._engine_next

    # --- the look-up -------------------------------------------------------------------------
    def _next_event(self, until: int) -> int:
        now = self.now
        nxt = until
        t = self.limit_event()
        if t is not None and now < t < nxt:
            nxt = t
        t = self.vm.interpreter.own_event()
        if t is not None and now < t < nxt:
            nxt = t
        return nxt

    def limit_event(self) -> int | None:
        """Next event of the engines, heartbeats, timers and world (all but the program's own),
        > now or None; cached while nothing was written."""
        now = self.now
        t = self._limit
        held = self._limit_ok and not self._dirty
        if held:
            if t is None or t > now:
                return t
            other = self._limit_other
            if other is None or other > now:  # only a timer's event was reached: the rest stands
                t = self.vm.interrupts.next_timer_event(now, refresh=False)
                best = other if t is None or now >= t or (other is not None and other <= t) else t
                self._limit = best
                return best
        return self._look_limit_up(now, held)

    def _look_limit_up(self, now: int, held: bool) -> int | None:
        vm = self.vm
        ints = vm.interrupts
        best = None
        t = self._engine_event()
        if t is not None and now < t:
            best = t
        hb = vm.heartbeats.deadline()
        if hb is not None and now < hb and (best is None or hb < best):
            best = hb
        if not held:  # else reached: an event tick, polled by the interpreter with no write since
            ints.poll(now)  # latch what a command just did (levels) and re-phase rewritten timers
        dirty = self._dirty  # the world's look-up syncs lagging engines: no plan changes
        t = vm.world.next_event(same_axes=held)
        self._dirty = dirty
        if t is not None and now < t and (best is None or t < best):
            best = t
        self._limit_other = best
        t = ints.next_timer_event(now, refresh=False)
        if t is not None and now < t and (best is None or t < best):
            best = t
        self._limit = best
        self._limit_ok = True
        return best

    def limit_held(self) -> bool:
        """Nothing was written since the limit was looked up (the world's list of watched axes
        and the interrupts' timer periods are as they were then)."""
        return self._limit_ok

    # --- running ahead (Interpreter.run_ahead) -------------------------------------------------
    def world_quiet(self) -> bool:
        """World.quiet(), kept while the limit holds."""
        quiet = self._quiet
        if quiet is None:
            quiet = self._quiet = self.vm.world.quiet()
        return quiet

    def ahead_limit(self, horizon: int, next_time: int | None) -> int:
        """The tick before which instructions may run ahead: the module's next event (all but the
        program's own) or `horizon`; now while a heartbeat is up but not yet fired; the next
        instruction's tick when the world is not quiet (it acts at every event)."""
        if not self._limit_ok or self._dirty:
            self._quiet = None
        nxt = self.limit_event()
        hb = self.vm.heartbeats.deadline()
        if hb is not None and hb <= self.now:
            return self.now
        limit = horizon if nxt is None or nxt > horizon else nxt
        if next_time is not None and next_time < limit and not self.world_quiet():
            return next_time
        return limit

    def read_at(self, tick: int, engines: list[Any] | None = None) -> None:
        """A read running ahead: time moves to its own tick and its engines follow there."""
        self.now = tick
        if self.synced_at != tick:
            self.sync_for_read(engines)

    def fold(self, tick: int) -> None:
        """Take the module's event at `tick` inside a run ahead. At a tick before every event but
        the timers', with nothing written since the look-up and a quiet world, the engines, the
        world and the heartbeats have nothing to do: only the program is served."""
        other = self._limit_other
        if self._limit_ok and not self._dirty and (other is None or tick < other) and self.world_quiet():
            self.now = tick
            self.vm.interpreter.service()
        else:
            self.event_at(tick)
