"""When the module could have acted on each request, from the capture's timestamps and link speed.

A request's frame record carries the instant its bytes reached the proxy (the start of its way to
the module), a reply's the instant its last byte arrived (the end of the reply on the wire). On a
link of known speed one 9-byte frame takes `frame_time` seconds, so the module can have read a
request, acted on it and sampled what it reports only inside

    [end of the request on the wire, start of the reply on the wire]

(frames of one chunk follow each other on the wire). When the timestamps leave no room for that
(a pty or USB port that ignores the baud rate, or no link speed recorded), the window is the whole
round trip [request, reply] (docs/capture.md "Replay").

`clock_lag` opens every window that much earlier: a module may act on a request and report its
state from a clock that trails the host's (a served twin's clock advances in steps of up to 2 ms,
docs/endpoints.md "Real time"; a real module's crystal drifts).
"""
from __future__ import annotations

from dataclasses import dataclass

from .format import Capture

FRAME_BYTES = 9
BITS_PER_BYTE = 10
"""Start bit, eight data bits, stop bit (8N1)."""
CAN_FRAME_BITS = 111
"""An 8-byte CAN data frame with 11-bit identifier: 44 bits of frame, 64 data bits, 3 interframe."""


def frame_time(interface: str, rate: int | None) -> float:
    """Seconds one frame takes on the wire: 9 bytes of 10 bits on serial lines, 111 bits on CAN, 0 if unknown."""
    if not rate:
        return 0.0
    bits = CAN_FRAME_BITS if interface == "can" else FRAME_BYTES * BITS_PER_BYTE
    return bits / rate


def link_record(interface: str, rate: int | None) -> dict:
    """The header's `link`: the interface, its baud (bit) rate if known and the wire time per frame."""
    return {"interface": interface, "baud": rate, "frame_time": round(frame_time(interface, rate), 9)}


@dataclass
class Slot:
    """One host record (request or ASCII text) and the window in which the module acted on it."""

    rec: dict
    e: float
    """Earliest: the end of the request on the wire."""
    s: float
    """Latest: the start of the reply on the wire (= e when no reply came)."""
    reply: dict | None
    widened: bool = False
    """The link speed did not fit the timestamps: the window is the whole round trip."""


def _chunks(frames: list[dict], direction: str) -> dict[int, tuple[int, int]]:
    """record n -> (its index in its chunk, frames in the chunk); a chunk: records of one arrival time."""
    out: dict[int, tuple[int, int]] = {}
    group: list[dict] = []

    def close() -> None:
        for i, r in enumerate(group):
            out[r["n"]] = (i, len(group))

    for rec in frames:
        if rec["dir"] != direction or rec["kind"] in ("garbage", "ascii"):
            continue
        if group and rec["t"] != group[-1]["t"]:
            close()
            group = []
        group.append(rec)
    close()
    return out


CLOCK_LAG = 0.002
"""Default `clock_lag`: the step of a served module's clock (server/bus.py MIN_STEP)."""


def slots(cap: Capture, clock_lag: float = CLOCK_LAG) -> list[Slot]:
    """Every host request and ASCII text of the capture with its window, in capture order."""
    ft = float(cap.link.get("frame_time") or 0.0)
    replies = {r["request"]: r for r in cap.frames
               if r["kind"] in ("reply", "version", "memory") and isinstance(r.get("request"), int)}
    module_pos = _chunks(cap.frames, "module")
    out: list[Slot] = []
    line_free = float("-inf")
    for rec in cap.frames:
        if rec["dir"] != "host" or rec["kind"] not in ("request", "ascii"):
            continue
        t = float(rec["t"])
        if rec["kind"] == "ascii" or not ft:
            end = t
        else:
            line_free = max(line_free, t) + ft   # frames of one chunk follow each other on the wire
            end = line_free
        reply = replies.get(rec["n"]) if rec["kind"] == "request" else None
        if reply is None:
            out.append(Slot(rec, max(0.0, end - clock_lag), end, None))
            continue
        index, count = module_pos.get(reply["n"], (0, 1))
        start = float(reply["t"]) - ft * (count - index)   # the reply's first byte on the wire
        if start >= end:
            out.append(Slot(rec, max(0.0, end - clock_lag), start, reply))
        else:   # no room for the wire times: the link was faster than recorded
            out.append(Slot(rec, max(0.0, t - clock_lag), max(t, float(reply["t"])), reply, widened=ft > 0))
    return out


def module_starts(cap: Capture) -> dict[int, float]:
    """record n -> when that module record (a reply, an event) started on the wire."""
    ft = float(cap.link.get("frame_time") or 0.0)
    by_n = {r["n"]: r for r in cap.frames}
    return {n: float(by_n[n]["t"]) - ft * (count - index)
            for n, (index, count) in _chunks(cap.frames, "module").items()}
