"""Captures recorded from a virtual module through the decoder, as the proxy records a real one.

The module acts on each request `act` seconds after the request's first byte reached the proxy and
its reply arrives `rtt` seconds after it (the end of the reply); command-138 events arrive at the
instant the module sends them. `link` goes into the header (docs/capture.md "The capture format")."""
from __future__ import annotations

import json

from opentmcl import VirtualModule
from opentmcl.capture.decode import HOST, MODULE, Decoder
from opentmcl.protocol.frame import Request

CLOCK_HZ = 16_000_000
HEADER = {"record": "header", "format": "opentmcl-capture", "version": 1, "tool": "test", "target": "sim://"}


class Recorder:
    def __init__(self, name: str = "TMCM-6212", *, link: dict | None = None, address: int = 1) -> None:
        self.vm = VirtualModule(name, address=address)
        self.decoder = Decoder(lambda a: self.vm.profile)
        self.records: list[dict] = [{**HEADER, **({"link": link} if link else {})}]

    def _frames(self, t: float, direction: str, data: bytes) -> None:
        self.records += [{"record": "frame", **r} for r in self.decoder.feed(t, direction, data)]

    def until(self, t: float) -> None:
        """Advance the module to `t`, event by event, the events arriving when sent."""
        tick = round(t * CLOCK_HZ)
        while self.vm.now < tick:
            dt = self.vm.next_event_in()
            nxt = tick if dt is None else min(tick, self.vm.now + max(1, round(dt * CLOCK_HZ)))
            self.vm.advance_to(nxt)
            for raw in self.vm.drain_events():
                self._frames(self.vm.now / CLOCK_HZ, MODULE, raw)

    def request(self, t: float, fields: tuple, *, act: float = 0.0, rtt: float = 0.0005, address: int = 1) -> bytes:
        frame = Request(address, *fields).encode()
        self.until(t)
        self._frames(t, HOST, frame)
        self.until(t + act)
        reply = self.vm.handle(frame)
        self.until(t + rtt)
        if reply:
            self._frames(t + rtt, MODULE, reply)
        return reply

    def write(self, path):
        path.write_text("".join(json.dumps(r) + "\n" for r in self.records))
        return path


def record(path, steps, name: str = "TMCM-6212", **kwargs):
    """Run `steps` [(t, (command, type, motor, value))] against a module; write the capture."""
    rec = Recorder(name, **kwargs)
    for t, fields in steps:
        rec.request(t, fields)
    return rec.write(path)


def edit(path, predicate, **changes):
    """Change the records that match (e.g. a captured reply value); at least one must."""
    lines = [json.loads(x) for x in path.read_text().splitlines()]
    hits = [r for r in lines if predicate(r)]
    assert hits
    for r in hits:
        r.update(changes)
    path.write_text("".join(json.dumps(r) + "\n" for r in lines))


def reply_of(path, predicate) -> dict:
    """The first captured reply record that matches."""
    for line in path.read_text().splitlines():
        r = json.loads(line)
        if r.get("kind") == "reply" and predicate(r):
            return r
    raise AssertionError("no such reply")


PLANTED = """extends = "TMCM-6212"

[module]
name = "PLANTED-6212"
firmware_version = "6212V200"

[[axis_parameter]]
number = 194
default = 40000

[[axis_parameter]]
number = 4
max = 2000000

[[axis_parameter]]
number = 5
engine = ""
"""
"""A "real" module with planted differences from the TMCM-6212 (docs/capture.md "Conformance runs"):
a changed default (AP194), a narrower range (AP4 up to 2000000), another firmware string, and a
ramp that does not follow AP5 (it accelerates at the engine's 51200 pps^2 whatever AP5 says)."""


def planted_session(tmp_path, name: str | None = None):
    """A capture of a host that identifies the module, reads AP194, sets a fast ramp, rotates,
    changes speed, stops and moves back, polling speed and position every 20 ms; recorded from the
    planted module (or from `name`)."""
    profile = tmp_path / "planted.toml"
    profile.write_text(PLANTED)
    rec = Recorder(name or str(profile))
    t = 0.0

    def req(fields, gap=0.02):
        nonlocal t
        t += gap
        return rec.request(t, fields, act=0.0003, rtt=0.0008)

    req((136, 0, 0, 0))
    req((6, 194, 0, 0))
    req((5, 4, 0, 7999774))
    for fields in [(5, 5, 0, 204800), (5, 17, 0, 204800), (5, 4, 0, 40000)]:
        req(fields)
    for command, value, until in [(1, 10000, 10000), (1, 20000, 20000), (3, 0, 0)]:
        req((command, 0, 0, value))
        for _ in range(200):
            req((6, 1, 0, 0))
            if int.from_bytes(req((6, 3, 0, 0))[4:8], "big", signed=True) == until:
                break
    req((4, 0, 0, 0))
    for _ in range(200):
        req((6, 1, 0, 0))
        if req((6, 8, 0, 0))[7] == 1:
            break
    req((6, 1, 0, 0), gap=0.3)
    return rec.write(tmp_path / "planted.jsonl")
