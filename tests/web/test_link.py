"""Turns on the link (web/link.py, issue 28 item 2): a request's turn is a stop's for MST (manual
3.6.3), 128 "stop application" and 131 "reset application" (3.6.36), an ordinary one otherwise. The
lock itself is tested in tests/test_handover.py."""
from __future__ import annotations

import threading

import pytest

from opentmcl.handover import HandoverLock
from opentmcl.web.link import turn


@pytest.mark.parametrize("command, stop", [(3, True), (128, True), (131, True), (4, False), (6, False),
                                           (129, False), (130, False)])
def test_a_turn_is_urgent_for_the_stop_commands(command, stop):
    gate = HandoverLock()
    gate.acquire()  # somebody holds the link; a turn queued now shows its class
    took = threading.Event()

    def take() -> None:
        with turn(gate, command):
            took.set()

    t = threading.Thread(target=take, daemon=True)
    t.start()
    while gate.waiting() == 0:
        took.wait(0.001)
    assert gate.stops_waiting is stop
    gate.release()
    t.join(30)
    assert took.is_set()
