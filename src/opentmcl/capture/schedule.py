"""When one twin acts on each request and samples each read (docs/capture.md "Replay").

    run = Schedule(Twin(vm, "hi", tau, axes), slots).run()

Requests act in capture order, each at the start or the end of its window as the twin's policy
says (capture/twin.py `Twin.late`); each read's sampling interval [window start - tau, window end
+ tau] opens and closes on the way, the twin sampling the value in between.
"""
from __future__ import annotations

import heapq

from ..protocol.opcodes import Op
from .timing import Slot
from .twin import READS_OF, Twin, TwinRun, windowed


def last_writes(slots: list[Slot], reads: list[bool]) -> list[int]:
    """For each read: the index of the last slot before it that writes what it reads (SAP or RSAP
    for GAP, SGP for GGP, SIO for GIO of the same type and motor or bank, 137 everything); -1 if
    none, and for every slot that is no read."""
    out = []
    written: dict[tuple, int] = {}
    for i, slot in enumerate(slots):
        rec = slot.rec
        if reads[i]:
            out.append(max(written.get((rec["command"], rec["type"], rec["motor"]), -1), written.get(("all",), -1)))
            continue
        out.append(-1)
        if rec["kind"] == "request" and rec["command"] == Op.RESTORE_FACTORY_SETTINGS:
            written[("all",)] = i
        elif rec["kind"] == "request" and rec["command"] in READS_OF:
            written[(READS_OF[rec["command"]], rec["type"], rec["motor"])] = i
    return out


OPEN, CLOSE = "open", "close"


class Schedule:
    """One twin's timeline through the slots of a capture: it acts on each request in capture
    order, at the start or the end of its window (`Twin.late`), and opens and closes the sampling
    interval of each read [window start - tau, window end + tau] on the way.

    A module handles requests one after the other, so a read's sampling interval starts no
    earlier than the last request before it that writes what it reads acts (the window waits
    for it), and ends no later than the next such request acts (whatever the time tolerance)."""

    def __init__(self, twin: Twin, slots: list[Slot]) -> None:
        self.twin, self.slots = twin, slots
        profile = twin.vm.profile
        self.reads = [s.rec["kind"] == "request" and windowed(s.rec, profile) for s in slots]
        self.last_write = last_writes(slots, self.reads)
        self.points: list[tuple[int, int, int, str]] = []   # (tick, order, slot, open|close): a heap
        for i, slot in enumerate(slots):
            if self.reads[i]:
                heapq.heappush(self.points, (twin.tick_of(slot.e - twin.tau), 0, i, OPEN))
                heapq.heappush(self.points, (twin.tick_of(slot.s + twin.tau), 3, i, CLOSE))
        self.index = 0   # slots acted on so far
        self.pending: tuple[int, Slot, bool] | None = None   # the next action: (tick, slot, decided)
        self.waiting: dict[int, int] = {}   # window -> the slot that must act before it opens
        self.opened: set[int] = set()
        self.closed: set[int] = set()

    def run(self) -> TwinRun:
        while self.index < len(self.slots) or self.points or self.pending is not None:
            if self.pending is None and self.index < len(self.slots):
                slot = self.slots[self.index]
                self.pending = (max(self.twin.tick_of(slot.e), self.twin.last_action), slot, False)
            if self.action_first():
                self.act()
            else:
                self.window_point()
        return self.twin.run

    def action_first(self) -> bool:
        """Is the pending action due before the next window point? At the same tick, windows
        open before it and close after it."""
        if self.pending is None:
            return False
        if not self.points:
            return True
        head, order = self.points[0][0], self.points[0][1]
        return self.pending[0] < head or (self.pending[0] == head and order > 0)

    def act(self) -> None:
        """The pending action: put off to the end of its window once (`Twin.late`), else done."""
        assert self.pending is not None
        tick, slot, decided = self.pending
        twin = self.twin
        twin.advance(tick)
        read = self.reads[self.index]
        if not decided and not read:
            sign = twin.effect(slot.rec) if slot.rec["kind"] == "request" else None
            if slot.s > slot.e and twin.late(sign):
                self.pending = (max(twin.tick_of(slot.s), tick), slot, True)
                return
        if not read:
            for j in [j for j in self.opened if j < self.index and twin.writes(slot.rec, self.slots[j].rec)]:
                twin.close(self.slots[j])   # sampled before this request acted
                self.opened.discard(j)
                self.closed.add(j)
        twin.act(slot)
        twin.last_action = twin.vm.now
        self.pending = None
        self.index += 1
        self.open_waiting()

    def open_waiting(self) -> None:
        """Open the windows whose write has acted now (closing at once those already past their end)."""
        for j in [j for j, after in self.waiting.items() if after < self.index]:
            del self.waiting[j]
            self.twin.open(self.slots[j])
            if j in self.closed:
                self.twin.close(self.slots[j])
            else:
                self.opened.add(j)

    def window_point(self) -> None:
        """The next window opens or closes."""
        tick, _, i, kind = heapq.heappop(self.points)
        if kind == OPEN:
            if self.index <= self.last_write[i]:   # the request that changed something before it has not acted
                self.waiting[i] = self.last_write[i]
                return
            self.twin.advance(tick)
            self.twin.open(self.slots[i])
            self.opened.add(i)
        elif i in self.opened:
            self.twin.advance(tick)
            self.twin.close(self.slots[i])
            self.opened.discard(i)
            self.closed.add(i)
        else:
            self.closed.add(i)   # closed before it could open: only its own answer counts
