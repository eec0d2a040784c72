"""Faults of the link (docs/faults.md "Link faults"): what happens to one request and its reply.

`LinkFaults.request` decides, for a request frame about to reach the module, its `Fate`: dropped,
a byte flipped (the module then answers status 1, "wrong checksum", TMCM-6212 manual 3.2.1), cut
into pieces with gaps; and for its reply: dropped, a byte flipped (the host sees a bad checksum),
delayed, cut into pieces. A link that goes down drops everything for a while. The endpoints
(server/linkfaults.py) and the in-process transport (host/transports/faulty.py) apply the fate
where the bytes are; the decision is made here, once, from seeded random streams.

Replies keep their order: a delayed reply delays the ones behind it, as on a serial line.
"""
from __future__ import annotations

import math
import random
import threading
from collections.abc import Callable, Iterable
from dataclasses import dataclass

from ..protocol.frame import FRAME_LEN
from ..protocol.opcodes import format_instruction
from .log import FaultLog
from .spec import Fault
from .trigger import Trigger

Fields = tuple[int, int, int, int]
"""Command, type, motor/bank and value of a request."""
Pieces = tuple[tuple[int, float], ...]
"""A frame cut into pieces: (length of the piece, seconds of silence before it)."""


@dataclass
class Fate:
    """What the link does to one request and its reply (nothing, by default)."""

    drop_request: bool = False
    corrupt_request: tuple[int, int] | None = None
    """(byte index, XOR mask) of the request byte flipped."""
    split_request: Pieces | None = None
    drop_reply: bool = False
    corrupt_reply: tuple[int, int] | None = None
    delay: float = 0.0
    """Seconds the reply (and every one behind it) is held back."""
    split_reply: Pieces | None = None

    @property
    def touches_reply(self) -> bool:
        return self.drop_reply or self.corrupt_reply is not None or self.delay > 0 or self.split_reply is not None


def describe(fields: Fields | None) -> str:
    """A request as the manual writes it (``GAP 1, 0``), or its command number."""
    if fields is None:
        return "a partial frame"
    text = format_instruction(*fields)
    return text if text is not None else f"command {fields[0]} (type {fields[1]}, motor/bank {fields[2]})"


def corrupt(data: bytes, flip: tuple[int, int]) -> bytes:
    """`data` with one byte XORed: a frame whose checksum no longer fits (manual 3.1.1)."""
    index, mask = flip
    if index >= len(data):
        return data
    out = bytearray(data)
    out[index] ^= mask
    return bytes(out)


def cut(data: bytes, pieces: Pieces) -> list[tuple[bytes, float]]:
    """`data` cut as `pieces` says: [(bytes, gap before them)]; the last piece takes the rest."""
    out, pos = [], 0
    for i, (length, gap) in enumerate(pieces):
        end = len(data) if i == len(pieces) - 1 else pos + length
        out.append((data[pos:end], gap))
        pos = end
    return [(chunk, gap) for chunk, gap in out if chunk]


def survives(pieces: Pieces, frame_gap: float) -> bool:
    """Does a receiver that drops a partial frame after `frame_gap` seconds of silence (the
    module's frame-gap rule, server/framer.py) still assemble the frame from `pieces`?"""
    return all(gap <= frame_gap for _length, gap in pieces[1:])


class Pending:
    """Link faults triggered by name that have not fired yet, shared by the links of one set-up:
    the first matching request on any of its links takes one."""

    def __init__(self) -> None:
        self.counts: dict[str, int] = {}
        self._lock = threading.Lock()

    def add(self, name: str) -> None:
        with self._lock:
            self.counts[name] = self.counts.get(name, 0) + 1

    def take(self, name: str) -> bool:
        with self._lock:
            n = self.counts.get(name, 0)
            if n:
                self.counts[name] = n - 1
            return bool(n)


class LinkFaults:
    """The link faults of one link (a pty, a TCP client, a CAN bus, an in-process transport)."""

    def __init__(self, faults: Iterable[Fault], rng_for: Callable[[int, Fault], random.Random],
                 log: FaultLog, pending: Pending | None = None) -> None:
        self.triggers = [Trigger(f, rng_for(i, f)) for i, f in enumerate(faults) if f.link]
        self.log = log
        self.pending = pending if pending is not None else Pending()
        self.down_until = -math.inf
        """The link passes nothing before this time (link_down)."""

    def __bool__(self) -> bool:
        return bool(self.triggers)

    def names(self) -> list[str]:
        return [t.fault.name for t in self.triggers if t.fault.name]

    def trigger(self, name: str, t: float) -> bool:
        """Fire the named fault on this link alone: a link that goes down goes down now, the others
        act on its next matching request. False when this link has no fault of that name. (A
        `FaultBoard` fires a named fault once, on the first of its links: `Pending`.)"""
        found = False
        for trig in self.triggers:
            if trig.fault.name == name:
                found = True
                if trig.fault.kind == "link_down":
                    self.go_down(trig.fault, t, "triggered by name")
                else:
                    trig.armed += 1
        return found

    def go_down(self, fault: Fault, t: float, why: str, *, record: bool = True) -> None:
        """The link goes down now for the fault's duration (`record`: in the log; a `FaultBoard`
        that takes every link down records it once)."""
        self._down(fault, t, why, record)

    def _fires(self, trig: Trigger, fields: Fields, t: float) -> bool:
        f = trig.fault
        if f.name is not None and self.pending.counts.get(f.name) and f.matches(fields[0], fields[1], fields[2]) \
                and self.pending.take(f.name):
            return True
        return trig.fires(fields[0], fields[1], fields[2], t)

    def down(self, t: float) -> bool:
        """Is the link down at `t` (a reply sent then is lost)?"""
        return t < self.down_until

    def _down(self, fault: Fault, t: float, why: str, record: bool = True) -> None:
        duration = fault.duration or 0.0
        self.down_until = max(self.down_until, t + duration)
        if record:
            self.log.record(fault, f"link down for {duration:g} s ({why})", t)

    def request(self, fields: Fields | None, t: float) -> Fate:
        """The fate of a request with `fields` (None: bytes that are no whole frame) at time `t`."""
        fate = Fate()
        if t < self.down_until:
            fate.drop_request = fate.drop_reply = True
            return fate
        if fields is None:
            return fate
        text = ""
        for trig in self.triggers:
            if self._fires(trig, fields, t):
                text = text or describe(fields)
                self._apply(trig, fate, text, t)
                if fate.drop_request:
                    break
        return fate

    def _apply(self, trig: Trigger, fate: Fate, text: str, t: float) -> None:
        f, rng = trig.fault, trig.rng
        kind = f.kind
        if kind == "link_down":
            self._down(f, t, f"at {text}")
            fate.drop_request = fate.drop_reply = True
            return
        if kind == "drop_request":
            fate.drop_request = True
            detail = f"request {text} dropped"
        elif kind == "drop_reply":
            fate.drop_reply = True
            detail = f"reply to {text} dropped"
        elif kind in ("corrupt_request", "corrupt_reply"):
            flip = (f.byte if f.byte is not None else rng.randint(1, FRAME_LEN - 1), rng.randint(1, 255))
            side = "request" if kind == "corrupt_request" else "reply to"
            if kind == "corrupt_request":
                fate.corrupt_request = flip
            else:
                fate.corrupt_reply = flip
            detail = f"{side} {text}: byte {flip[0]} XOR {flip[1]:#04x}"
        elif kind == "delay":
            seconds = max(0.0, f.delay + (rng.uniform(-f.jitter, f.jitter) if f.jitter else 0.0))
            fate.delay += seconds
            detail = f"reply to {text} delayed {seconds:.6f} s"
        else:  # split_request, split_reply
            cuts = sorted(rng.sample(range(1, FRAME_LEN), f.pieces - 1))
            ends = [*cuts, FRAME_LEN]
            pieces = tuple((end - start, 0.0 if i == 0 else f.gap)
                           for i, (start, end) in enumerate(zip([0, *cuts], ends, strict=True)))
            if kind == "split_request":
                fate.split_request = pieces
            else:
                fate.split_reply = pieces
            side = "request" if kind == "split_request" else "reply to"
            detail = f"{side} {text} cut into {f.pieces} pieces, {f.gap:g} s apart"
        self.log.record(f, detail, t)
