"""The next event of one axis's world (docs/world.md "Time: events, never steps"): the earliest
tick at which a check can change something, found in closed form with the engine's
`time_at_position` / `time_at_speed`, and cached until what it depends on changes."""
from __future__ import annotations

from typing import TYPE_CHECKING

from ..motion import CLOCK_HZ
from ..motion.stage import Profile, ceil_ticks

if TYPE_CHECKING:
    from ..motion import RampEngine
    from .axis_world import AxisWorld
    from .motor import Motor

DUE_TICKS = 4
"""Ticks in a row at which a check that cannot resolve its condition is due again."""


class EventLookup:
    """The axis's next event and its cache."""

    axis: Motor
    engine: RampEngine

    SIGNATURE_PARAMS = (6, 7, 12, 13, 14, 24, 25, 26, 140, 141, 149, 167, 172, 174, 181, 182, 200, 202, 210, 212)
    """The axis parameters the next event depends on."""

    def __init__(self, aw: AxisWorld) -> None:
        self.aw = aw
        self.static = False              # the stage or the load gives events of their own
        self.cache: tuple | None = None  # (signature, next event)
        self.engine_wake: int | None = None
        self.due_at = -2
        self.due_streak = 0
        self.due_plan: object = None
        self.null_channel_possible = aw.caps.null_channel

    def bind(self, axis: Motor) -> None:
        self.axis = axis
        self.engine = axis.engine
        self.update_static()

    def interesting(self) -> bool:
        """Can anything happen on this axis that needs an event? (cheap; checked very often)"""
        if self.static:
            return True
        aw = self.aw
        if aw.switches.forced or aw.watch is not None:
            return True
        ram = self.axis.ram
        return bool(ram.get(181) or ram.get(212) or (self.null_channel_possible and ram.get(210, 0) & 4))

    def update_static(self) -> None:
        """After a change of the load: do the stage or the load have events of their own?"""
        aw = self.aw
        st, prof = aw.stage, aw.drive.load.profile
        self.static = bool(st.left or st.right or st.home or not prof.is_constant or prof.before
                           or st.ends != (None, None) or aw.spec.torque_falloff_speed)

    def signature(self) -> tuple:
        """Everything the next world event depends on besides time (for the cache)."""
        aw = self.aw
        eng = self.engine.plan_token
        rotor, switches = aw.rotor, aw.switches
        ram = self.axis.ram
        search = aw.vm.reference_search(self.axis)
        gp79 = aw.vm.globals.ram.get((0, 79), 0)
        return (eng, rotor.offset, rotor.slipping, tuple(switches.raw.values()),
                tuple(sorted(switches.forced.items())), aw.watch, aw.drive.load, aw.drive.shut_down,
                tuple(ram.get(n, 0) for n in self.SIGNATURE_PARAMS), gp79, search.active, search.condition)

    def next_event(self) -> int | None:
        """Absolute tick of this axis's next world event (callers check `interesting()` first)."""
        vm = self.aw.vm
        now = vm.now
        e = self.engine
        if e.now < now:
            vm.sync()
        sig = self.signature()
        cached = self.cache
        if cached is not None and cached[0] == sig and (cached[1] is None or cached[1] > now) \
                and self.aw.drive.load.by != "time":
            self.engine_wake = e.next_event()
            return cached[1]
        t = self.scan(now)
        self.cache = (sig, t)
        self.engine_wake = e.next_event()
        return t

    def needs_check(self, now: int) -> bool:
        """At this event tick: is it one of this axis's own events or an engine phase change?"""
        if self.cache is None or self.aw.drive.load.by == "time":
            return True
        return now == self.cache[1] or now == self.engine_wake

    def scan(self, now: int) -> int | None:
        """The earliest tick after `now` at which a check can change something: a position the
        counter reaches (switch edges, load steps, ends, null channel, deviation limit, the
        reference search's watch), a step of a load over time, or the stop-on-stall speed."""
        aw = self.aw
        rotor = aw.rotor
        rotor.follow()
        if self._due_again(now):
            return now + 1
        off = rotor.driver_off()
        counters = self._stage_counters() if not rotor.slipping and not off else self._deviation_counters()
        if aw.watch is not None:
            counters.append(aw.watch)
        best = self._first_arrival(counters, now)
        load = aw.drive.load
        if load.by == "time":
            t = self._next_time(load.profile)
            if t is not None and (best is None or t < best):
                best = t
        t = None if off else self._stall_speed_time()
        if t is not None and t > now and (best is None or t < best):
            best = t
        return best

    def _due_again(self, now: int) -> bool:
        """A check is due at the next tick; not more than DUE_TICKS ticks in a row, since a check
        that cannot resolve it must not stall time."""
        if not self.aw.checks.due_now():
            return False
        plan = self.engine.plan_token  # a command since the last due tick re-creates the condition
        again = self.due_at == now - 1 and plan == self.due_plan
        self.due_streak = self.due_streak + 1 if again else 0
        self.due_at, self.due_plan = now, plan
        return self.due_streak < DUE_TICKS

    def _stage_counters(self) -> list[int]:
        """Counter positions at which the stage, following the counter, meets something: a switch
        edge, a step of a load over position, a mechanical end, the encoder's null channel."""
        aw = self.aw
        phys, offset = aw.rotor.phys, aw.rotor.offset
        out = aw.switches.edges(phys)
        if aw.drive.load.by == "position":
            out += self._load_steps(phys)
        lo, hi = aw.stage.ends
        out += [x for x in (lo, hi) if x is not None and x != phys]
        out += aw.encoder.null_positions(phys)
        return [x - offset for x in out]

    def _load_steps(self, phys: int) -> list[int]:
        """Physical positions on both sides of each breakpoint of a load over position."""
        out = []
        for x in self.aw.drive.load.profile.breakpoints():
            for c in (int(-(-x // 1)), int(-(-x // 1)) - 1):
                if c != phys:
                    out.append(c)
        return out

    def _deviation_counters(self) -> list[int]:
        """The stage stands (steps lost, driver off): only the deviation limit AP212 can be crossed."""
        aw = self.aw
        lim = aw.p(212)
        if not lim:
            return []
        enc = aw.encoder.position()
        return [enc + lim + 1, enc - lim - 1]

    def _first_arrival(self, counters: list[int], now: int) -> int | None:
        """First tick after `now` at which the counter reaches one of `counters`."""
        best = None
        e = self.engine
        here = e.position
        for c in counters:
            if c == here or not -2**31 <= c < 2**31:
                continue
            t = e.time_at_position(c)
            if t is not None and t > now and (best is None or t < best):
                best = t
        return best

    def _stall_speed_time(self) -> int | None:
        """Tick at which the speed reaches the stop-on-stall limit AP181 (None: off or never)."""
        limit = self.aw.p(181)
        if not limit:
            return None
        return self.engine.time_at_speed(self.aw.checks.stall_speed(limit))

    def _next_time(self, profile: Profile) -> int | None:
        """Next tick at which a load given over time changes (steps: breakpoints; ramps: every ms)."""
        now = self.aw.vm.now
        nxt = next((t for x in profile.breakpoints() if (t := ceil_ticks(x, CLOCK_HZ)) > now), None)
        pts = profile.points
        if profile.kind == "ramp" and pts and pts[0][0] <= now / CLOCK_HZ < pts[-1][0]:
            step = now + CLOCK_HZ // 1000
            nxt = step if nxt is None else min(nxt, step)
        return nxt
