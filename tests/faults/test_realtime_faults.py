"""Faults keep the real-time promise (docs/architecture.md "Real time"; issue 28): a link that
waits out a delay does so in its own thread, never holding the bus lock, so the other links of the
server are answered meanwhile and the clock goes on."""
from __future__ import annotations

import threading
import time

import opentmcl
from opentmcl import VirtualModule
from opentmcl.server import Server, TcpServer

from .helpers import GAP, MVP


def test_a_delayed_reply_does_not_hold_up_another_link():
    server = Server([VirtualModule("TMCM-6212", address=1)],
                    faults=[{"name": "slow", "kind": "delay", "delay": 3.0}])
    tcp = server.add(TcpServer(server.bus, "127.0.0.1", 0))
    server.start()
    slow = opentmcl.connect(tcp.url, timeout=20.0, profile="TMCM-6212")
    other = opentmcl.connect(tcp.url, timeout=20.0, profile="TMCM-6212")
    try:
        other.request(GAP, 1, 0)
        server.faults.trigger("slow")
        done = threading.Event()
        thread = threading.Thread(target=lambda: (slow.request(GAP, 4, 0), done.set()), daemon=True)
        thread.start()
        deadline = time.monotonic() + 10
        while not server.faults.log.count and time.monotonic() < deadline:
            time.sleep(0.01)
        assert server.faults.log.count == 1          # the slow link holds its reply now
        other.request(MVP, 0, 0, 100000)
        first = other.request(GAP, 1, 0).value
        time.sleep(0.2)
        later = other.request(GAP, 1, 0).value
        assert not done.is_set()                     # answered while the delayed reply still waits
        assert later > first                         # and the modules' clock went on
        thread.join(20)
        assert done.is_set()
    finally:
        slow.close()
        other.close()
        server.stop()
