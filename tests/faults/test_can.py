"""Link faults on the CAN endpoint (issue 34, "Link faults on every endpoint (... CAN ...)"): a
served TMCM-6212 on a python-can virtual bus, the host library on `can://`. A CAN frame is one
unit with its own CRC (TMCM-6212 manual 3.1: on CAN the checksum byte is left out), so a frame with
a flipped bit is lost and a frame is not cut (docs/assumptions.md "Faults on CAN")."""
from __future__ import annotations

import time

import pytest

import opentmcl
from opentmcl import VirtualModule
from opentmcl.host import TmclTimeout
from opentmcl.server import CanServer, Server

from ..server.helpers import unique_channel
from .helpers import GAP, SAP

LOST = 0.3
"""Seconds a request whose reply the test expects to be lost waits for it (the others: 5 s)."""
PLAN = {"seed": 2, "fault": [
    {"name": "drop-request", "kind": "drop_request"}, {"name": "drop-reply", "kind": "drop_reply"},
    {"name": "garble-request", "kind": "corrupt_request"}, {"name": "garble-reply", "kind": "corrupt_reply"},
    {"name": "slow", "kind": "delay", "delay": 0.3}, {"name": "down", "kind": "link_down", "duration": 0.6},
    {"name": "cut", "kind": "split_reply", "pieces": 3, "gap": 0.5}]}


@pytest.fixture
def can_link():
    channel = unique_channel()
    server = Server([VirtualModule("TMCM-6212", address=1)], faults=PLAN)
    server.add(CanServer(server.bus, "virtual", channel))
    server.start()
    m = opentmcl.connect(f"can://virtual/{channel}?id=1&reply_id=2", timeout=5.0, profile="TMCM-6212")
    try:
        yield server, m
    finally:
        m.close()
        server.stop()


def test_requests_and_replies_lost_on_can(can_link):
    """A dropped or garbled request is not done; a dropped or garbled reply is lost, the request done."""
    server, m = can_link
    m.request(SAP, 4, 0, 100)
    for name, done in (("drop-request", False), ("garble-request", False), ("drop-reply", True),
                       ("garble-reply", True)):
        server.faults.trigger(name)
        value = 100 + len(name)
        with pytest.raises(TmclTimeout):
            m.request(SAP, 4, 0, value, timeout=LOST)
        assert m.request(GAP, 4, 0).value == (value if done else 100), name
        m.request(SAP, 4, 0, 100)


def test_delay_and_link_down_on_can(can_link):
    server, m = can_link
    server.faults.trigger("slow")
    start = time.monotonic()
    assert m.request(GAP, 4, 0).status == 100
    assert time.monotonic() - start >= 0.3
    server.faults.trigger("down")
    with pytest.raises(TmclTimeout):
        m.request(GAP, 4, 0, timeout=LOST)
    time.sleep(0.6)
    assert m.request(10, 66, 0).value == 1


def test_a_can_frame_is_not_cut(can_link):
    """A split fault has nothing to cut on CAN: the reply comes whole and in time, and the log does
    not claim a cut (the fault stays pending for a serial link of the same server)."""
    server, m = can_link
    server.faults.trigger("cut")
    assert m.request(GAP, 4, 0).status == 100
    assert server.faults.log.count == 0
