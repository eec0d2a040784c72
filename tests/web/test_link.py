"""Turns on the link (web/link.py, issue 28 item 2: "a scan, a download or any console command
gives the link up to a stop"): the gate hands the link over first come, first served, stops
first, with real threads. The served-process tests are in test_stop_starvation.py."""
from __future__ import annotations

import threading
import time

import pytest

from opentmcl.web.link import STOP_COMMANDS, LinkGate

GUARD = 30.0  # seconds: a guard against hanging, never a timing assert


def wait_until(predicate, what: str) -> None:
    end = time.monotonic() + GUARD
    while not predicate():
        if time.monotonic() > end:
            raise AssertionError(f"not reached: {what}")
        time.sleep(0.001)


def queue_up(gate: LinkGate, order: list[str], name: str, urgent: bool = False) -> threading.Thread:
    """A thread that takes a turn (urgent: as a stop), notes its name, gives the turn back;
    returned once it waits."""
    before = gate.waiting

    def turn() -> None:
        gate.acquire(urgent=urgent)
        order.append(name)
        gate.release()

    thread = threading.Thread(target=turn, daemon=True)
    thread.start()
    wait_until(lambda: gate.waiting == before + 1, f"{name} waiting")
    return thread


def test_turns_go_in_the_order_asked():
    gate, order = LinkGate(), []
    gate.acquire()
    threads = [queue_up(gate, order, name) for name in "abc"]
    gate.release()
    for t in threads:
        t.join(GUARD)
    assert order == ["a", "b", "c"]


def test_a_stop_goes_ahead_of_every_ordinary_request_waiting():
    """MST (manual 3.6.3), 128 and 131 (3.6.36) are the stop commands; a stop asked last goes
    first when the link is handed over."""
    assert STOP_COMMANDS == {3, 128, 131}
    gate, order = LinkGate(), []
    gate.acquire()
    threads = [queue_up(gate, order, "a"), queue_up(gate, order, "b"), queue_up(gate, order, "stop", urgent=True)]
    assert gate.urgent_waiting
    gate.release()
    for t in threads:
        t.join(GUARD)
    assert order == ["stop", "a", "b"]


def test_a_thread_that_asks_again_at_once_queues_behind_those_waiting():
    """A plain lock lets the thread that just released it take it again (a scan asking address
    after address starved the console for seconds): here it waits its turn."""
    gate, order = LinkGate(), []
    gate.acquire()
    other = queue_up(gate, order, "console")
    gate.release()
    gate.acquire()  # the scan's next address
    order.append("scan")
    gate.release()
    other.join(GUARD)
    assert order == ["console", "scan"]


def test_turns_are_reentrant_also_as_a_stop():
    gate = LinkGate()
    with gate, gate, gate.urgent():
        assert gate.waiting == 0
    other = threading.Thread(target=lambda: (gate.acquire(), gate.release()), daemon=True)
    other.start()
    other.join(GUARD)
    assert not other.is_alive()  # the gate is free again


def test_yield_turn_lets_a_stop_in_and_resumes_before_the_others():
    """Work that holds the link over several requests (a baud-rate scan) lends it to a stop and
    carries on before the ordinary requests that queued meanwhile."""
    gate, order = LinkGate(), []
    gate.acquire()
    gate.acquire()  # held twice: the depth comes back after the stop
    normal = queue_up(gate, order, "poll")
    stop = queue_up(gate, order, "stop", urgent=True)
    gate.yield_turn()
    order.append("scan")
    stop.join(GUARD)
    assert order == ["stop", "scan"]
    gate.release()
    assert order == ["stop", "scan"]  # still held once
    gate.release()
    normal.join(GUARD)
    assert order == ["stop", "scan", "poll"]


def test_yield_turn_without_a_stop_waiting_keeps_the_link():
    gate, order = LinkGate(), []
    gate.acquire()
    normal = queue_up(gate, order, "poll")
    gate.yield_turn()
    order.append("scan")
    gate.release()
    normal.join(GUARD)
    assert order == ["scan", "poll"]


def test_only_the_holder_gives_the_link_back():
    gate = LinkGate()
    with pytest.raises(RuntimeError):
        gate.release()
