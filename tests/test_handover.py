"""The lock handed over by urgency (handover.py), which the served bus (issue 28: "Stop requests
(128, MST, 131, and the dashboard's STOP ALL) go ahead of queued work") and the dashboard's link
(issue 28 item 2: "a scan, a download or any console command gives the link up to a stop") share:
first come, first served within a class, stops first, clock slices last, with real threads. The
served-process tests are in tests/server/test_realtime_served.py and tests/web/test_stop_starvation.py."""
from __future__ import annotations

import threading
import time

import pytest

from opentmcl.handover import BACKGROUND, REQUEST, STOP, HandoverLock

GUARD = 30.0  # seconds: a guard against hanging, never a timing assert


def wait_until(predicate, what: str) -> None:
    end = time.monotonic() + GUARD
    while not predicate():
        if time.monotonic() > end:
            raise AssertionError(f"not reached: {what}")
        time.sleep(0.001)


def queue_up(gate: HandoverLock, order: list[str], name: str, urgency: int = REQUEST) -> threading.Thread:
    """A thread that takes the lock as a thread of class `urgency`, notes its name, gives it back;
    returned once it waits."""
    before = gate.waiting()

    def turn() -> None:
        gate.acquire(urgency)
        order.append(name)
        gate.release()

    thread = threading.Thread(target=turn, daemon=True)
    thread.start()
    wait_until(lambda: gate.waiting() == before + 1, f"{name} waiting")
    return thread


def test_turns_go_in_the_order_asked():
    gate, order = HandoverLock(), []
    gate.acquire()
    threads = [queue_up(gate, order, name) for name in "abc"]
    gate.release()
    for t in threads:
        t.join(GUARD)
    assert order == ["a", "b", "c"]


def test_a_stop_goes_ahead_of_every_ordinary_request_waiting():
    """A stop asked last goes first when the lock is handed over."""
    gate, order = HandoverLock(), []
    gate.acquire()
    threads = [queue_up(gate, order, "a"), queue_up(gate, order, "b"), queue_up(gate, order, "stop", STOP)]
    assert gate.stops_waiting
    gate.release()
    for t in threads:
        t.join(GUARD)
    assert order == ["stop", "a", "b"]


def test_a_thread_that_asks_again_at_once_queues_behind_those_waiting():
    """A plain lock lets the thread that just released it take it again (a scan asking address
    after address starved the console for seconds): here it waits its turn."""
    gate, order = HandoverLock(), []
    gate.acquire()
    other = queue_up(gate, order, "console")
    gate.release()
    gate.acquire()  # the scan's next address
    order.append("scan")
    gate.release()
    other.join(GUARD)
    assert order == ["console", "scan"]


def test_turns_are_reentrant_also_as_a_stop():
    gate = HandoverLock()
    with gate, gate, gate.hold(STOP):
        assert gate.waiting() == 0 and gate.held()
    other = threading.Thread(target=lambda: (gate.acquire(), gate.release()), daemon=True)
    other.start()
    other.join(GUARD)
    assert not other.is_alive()  # the gate is free again


def test_yield_to_stops_lets_a_stop_in_and_resumes_before_the_others():
    """Work that holds the link over several requests (a baud-rate scan) lends it to a stop and
    carries on before the ordinary requests that queued meanwhile."""
    gate, order = HandoverLock(), []
    gate.acquire()
    gate.acquire()  # held twice: the depth comes back after the stop
    normal = queue_up(gate, order, "poll")
    stop = queue_up(gate, order, "stop", STOP)
    gate.yield_to_stops()
    order.append("scan")
    stop.join(GUARD)
    assert order == ["stop", "scan"]
    gate.release()
    assert order == ["stop", "scan"]  # still held once
    gate.release()
    normal.join(GUARD)
    assert order == ["stop", "scan", "poll"]


def test_yield_to_stops_without_a_stop_waiting_keeps_the_lock():
    gate, order = HandoverLock(), []
    gate.acquire()
    normal = queue_up(gate, order, "poll")
    gate.yield_to_stops()
    order.append("scan")
    gate.release()
    normal.join(GUARD)
    assert order == ["scan", "poll"]


def test_only_the_holder_gives_the_lock_back():
    gate = HandoverLock()
    with pytest.raises(RuntimeError):
        gate.release()


def test_stops_then_requests_then_background():
    """The served bus: queued background, request, stop, request, background are served stop first,
    then the requests in arrival order, then the clock slices."""
    gate, order = HandoverLock(), []
    gate.acquire(BACKGROUND)
    threads = [queue_up(gate, order, "slice 1", BACKGROUND), queue_up(gate, order, "request 1"),
               queue_up(gate, order, "stop", STOP), queue_up(gate, order, "request 2"),
               queue_up(gate, order, "slice 2", BACKGROUND)]
    gate.release()
    for t in threads:
        t.join(GUARD)
    assert order == ["stop", "request 1", "request 2", "slice 1", "slice 2"]


def test_yield_to_waiting_lets_the_stops_and_requests_in_then_resumes_before_the_slices():
    """The served bus's clock slice between two modules (issue 28: "serves pending requests between
    them"): the stop and the requests that wait go first, in their order; the slice then carries
    on, at its depth, before another clock slice that waits; a request that comes while the
    requests are served waits behind the slice."""
    gate, order = HandoverLock(), []
    gate.acquire(BACKGROUND)
    gate.acquire()  # held twice: the depth comes back
    threads = [queue_up(gate, order, "slice 2", BACKGROUND), queue_up(gate, order, "request 1"),
               queue_up(gate, order, "stop", STOP), queue_up(gate, order, "request 2")]
    gate.yield_to_waiting()
    order.append("slice 1")
    assert order == ["stop", "request 1", "request 2", "slice 1"]
    late = queue_up(gate, order, "request 3")
    gate.release()
    assert gate.held()
    gate.release()
    for t in [*threads, late]:
        t.join(GUARD)
    assert order == ["stop", "request 1", "request 2", "slice 1", "request 3", "slice 2"]


def test_yield_to_waiting_with_only_a_slice_waiting_keeps_the_lock():
    gate, order = HandoverLock(), []
    gate.acquire(BACKGROUND)
    other = queue_up(gate, order, "slice 2", BACKGROUND)
    gate.yield_to_waiting()
    order.append("slice 1")
    gate.release()
    other.join(GUARD)
    assert order == ["slice 1", "slice 2"]
