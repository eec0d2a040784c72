"""Fault plans on served links (issue 34: link faults "on every endpoint ... Each is given as a
probability, at a scheduled time, or on a matching command (for example, drop the reply to the
third MVP). All are reproducible from a seed."): a served TMCM-6212 (`Server`, `TcpServer`: real
sockets) and the host library on ``tcp://``, each check made through the wire.

Real time: a request expected to get no reply waits a short time-out (`LOST`); every other waits
a generous one (`WAIT`); waits are polled with generous deadlines."""
from __future__ import annotations

import time

import pytest

import opentmcl
from opentmcl import VirtualModule
from opentmcl.host import TmclStatusError, TmclTimeout
from opentmcl.server import Server, TcpServer

from .helpers import GAP, MVP, SAP

LOST = 0.3
"""Seconds a request whose reply the test expects to be lost waits for it."""
WAIT = 5.0
"""Seconds every other request may wait (a busy machine only makes the tests slower)."""


class Served:
    """A served TMCM-6212 with a fault plan, and host links to it."""

    def __init__(self, plan: dict) -> None:
        self.server = Server([VirtualModule("TMCM-6212", address=1)], faults=plan)
        self.tcp = self.server.add(TcpServer(self.server.bus, "127.0.0.1", 0))
        self.server.start()
        self.links: list[opentmcl.Module] = []

    def link(self, timeout: float = WAIT) -> opentmcl.Module:
        m = opentmcl.connect(self.tcp.url, timeout=timeout, profile="TMCM-6212")
        self.links.append(m)
        return m

    def close(self) -> None:
        for m in self.links:
            m.close()
        self.server.stop()


@pytest.fixture
def served():
    made: list[Served] = []
    yield lambda plan: made.append(Served(plan)) or made[-1]
    for s in made:
        s.close()


def outcomes(m, requests, timeout: float = WAIT) -> list:
    """What each request got: its value, "timeout", or the error status (status 1: a garbled request)."""
    out: list = []
    for request in requests:
        try:
            out.append(m.request(*request, timeout=timeout).value)
        except TmclTimeout:
            out.append("timeout")
        except TmclStatusError as exc:
            out.append(f"status {exc.status}")
    return out


def test_the_reply_to_the_third_mvp_is_dropped(served):
    """The issue's example, "drop the reply to the third MVP", on a served link: the first two and
    the fourth are answered."""
    m = served({"seed": 1, "fault": [{"kind": "drop_reply", "command": "MVP", "count": 3}]}).link()
    assert [outcomes(m, [(MVP, 0, 0, target)], LOST if target == 300 else WAIT)[0]
            for target in (100, 200, 300, 400)] == [0, 0, "timeout", 0]


def test_a_seeded_run_repeats(served):
    """A fourth of the GAP requests garbled by chance (the module answers status 1, "wrong checksum",
    TMCM-6212 manual 3.2.1): two servers with the same seed garble the same requests, another seed
    garbles others."""
    plan = {"fault": [{"kind": "corrupt_request", "command": "GAP", "probability": 0.25, "byte": 7}]}
    reads = [(GAP, 4, axis % 6) for axis in range(40)]

    def run(seed: int) -> list:
        return outcomes(served({**plan, "seed": seed}).link(), reads)

    first = run(7)
    garbled = [i for i, v in enumerate(first) if v == "status 1"]
    assert 3 <= len(garbled) <= 25 and set(first) == {51200, "status 1"}
    assert run(7) == first
    assert run(8) != first


def test_a_link_fault_at_a_time(served):
    """`at` alone: the first request from that time on (seconds since the server started) loses
    its reply, once; the ones before and after are answered."""
    s = served({"seed": 1, "fault": [{"kind": "drop_reply", "at": 0.5}]})
    m = s.link()
    deadline = time.monotonic() + 30
    results: list = []
    while not (s.server.faults.log.count and results[-1] != "timeout"):
        assert time.monotonic() < deadline
        results += outcomes(m, [(GAP, 4, 0)], 2.0)   # long enough that only the fault loses a reply
        time.sleep(0.02)
    assert results.count("timeout") == 1 and results[0] != "timeout"
    (fired,) = s.server.faults.log.fired
    assert fired.t >= 0.5


def test_a_link_down_by_name_takes_every_link_down_once(served):
    """`link_down` triggered by name: both TCP clients lose their requests, and so does a client
    that connects while the link is down; it is recorded once; afterwards all are answered."""
    s = served({"seed": 1, "fault": [{"name": "down", "kind": "link_down", "duration": 1.0}]})
    a, b = s.link(), s.link()
    assert a.request(GAP, 4, 0).status == b.request(GAP, 4, 0).status == 100
    s.server.faults.trigger("down")
    late = s.link()
    for m in (a, b, late):
        with pytest.raises(TmclTimeout):
            m.request(SAP, 4, 0, 5, timeout=LOST)
    assert [f.kind for f in s.server.faults.log.fired] == ["link_down"]
    deadline = time.monotonic() + 30
    while outcomes(late, [(GAP, 4, 0)], LOST) == ["timeout"]:
        assert time.monotonic() < deadline
    assert a.request(GAP, 4, 0).value == b.request(GAP, 4, 0).value == 51200   # no SAP got through


def test_a_modules_own_link_faults_act_on_the_served_link():
    """`VirtualModule(faults=...)` with a link fault (or a scenario's [[fault]] tables): served, the
    fault acts on the link (docs/faults.md "Served": the served plan takes the modules' link faults)."""
    vm = VirtualModule("TMCM-6212", address=1, faults=[{"name": "lost", "kind": "drop_reply"}])
    server = Server([vm])
    tcp = server.add(TcpServer(server.bus, "127.0.0.1", 0))
    server.start()
    m = opentmcl.connect(tcp.url, timeout=WAIT, profile="TMCM-6212")
    try:
        server.faults.trigger("lost")
        with pytest.raises(TmclTimeout):
            m.request(SAP, 4, 0, 1234, timeout=LOST)
        assert m.request(GAP, 4, 0).value == 1234
    finally:
        m.close()
        server.stop()
