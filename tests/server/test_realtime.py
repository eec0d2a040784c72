"""The bus in real time (issue 28, docs/architecture.md "Real time"): stops take the bus first
(the lock itself: tests/test_handover.py), the simulation advances in bounded slices, and the modules' clock lags (and
drops what it cannot catch up) instead of the replies.

Costs are measured on a work clock the tests drive, so nothing here depends on the machine's speed.
"""
from __future__ import annotations

import threading

import pytest

from opentmcl import VirtualModule
from opentmcl.handover import BACKGROUND, REQUEST, STOP
from opentmcl.server.bus import ModuleBus, urgency
from opentmcl.server.pacing import MIN_SLICE, REQUEST_BUDGET, SLICE_BUDGET, Pacer

from .helpers import request


class Clock:
    def __init__(self) -> None:
        self.t = 0.0

    def __call__(self) -> float:
        return self.t


class CostlyModule(VirtualModule):
    """A module whose every `advance` costs `cost` work-clock seconds per virtual second."""

    def __init__(self, work: Clock, cost: float, **kwargs) -> None:
        self.work, self.cost, self.advanced = work, cost, []
        self.handled: list[int] = []
        super().__init__("TMCM-6212", **kwargs)

    def advance(self, seconds: float) -> None:
        self.work.t += seconds * self.cost
        self.advanced.append(seconds)
        super().advance(seconds)

    def handle(self, frame, *, interface="serial"):
        self.handled.append(frame[1])
        return super().handle(frame, interface=interface)


def costly_bus(cost: float, *, max_lag: float = 1.0, runner: bool = True):
    """A bus of one `CostlyModule` on a test clock; `runner`: as with a `RealTimeRunner` attached
    (its thread not started: the tests call `bus.step()` themselves)."""
    wall, work = Clock(), Clock()
    vm = CostlyModule(work, cost, address=1)
    bus = ModuleBus([vm], clock=wall, min_step=0.0, pacer=Pacer(wall, max_lag=max_lag, work_clock=work))
    bus.runner_attached = runner
    return bus, vm, wall


@pytest.mark.parametrize("command, expected", [(3, STOP), (128, STOP), (131, STOP), (6, REQUEST),
                                               (129, REQUEST), (130, REQUEST)])
def test_stop_requests_are_the_urgent_ones(command, expected):
    """MST (3.6.3), 128 "stop application" and 131 "reset application" (3.6.36) stop motion or
    a program; every other command, 129 "run" and 130 "step" too, is a plain request. A stop in
    the second of two pipelined frames makes the whole read urgent."""
    assert urgency(request(1, command)) == expected
    assert urgency(request(1, 6, 1) + request(1, command)) == expected


def test_a_stop_queued_behind_requests_is_handled_first():
    """Issue 28: "Stop requests (128, MST, 131 ...) go ahead of queued work": with the bus busy,
    a GAP that queued first and an MST that queued after it: the module sees the MST first."""
    bus, vm, _wall = costly_bus(0.0)
    replies: dict[int, bytes] = {}

    def send(frame: bytes) -> None:
        replies[frame[1]] = bus.request(frame)[0][1]

    bus.lock.acquire(BACKGROUND)  # a slice is running
    threads = []
    for frame in (request(1, 6, 1, 0), request(1, 3, 0, 0)):
        threads.append(threading.Thread(target=send, args=(frame,)))
        threads[-1].start()
        while bus.lock.waiting() < len(threads):
            threading.Event().wait(0.001)
    bus.lock.release()
    for t in threads:
        t.join(10)
    assert vm.handled == [3, 6]
    assert replies[3][2] == replies[6][2] == 100


def test_a_request_leaves_a_costly_lag_to_the_clock_thread():
    """A request brings the modules to the wall clock only when that costs at most REQUEST_BUDGET;
    behind a costly simulation it is answered at once, at the modules' (lagging) time."""
    bus, vm, wall = costly_bus(0.5)
    wall.t = 0.001
    bus.request(request(1, 6, 1, 0))  # cheap: 0.5 ms of work, taken whole; the cost is now known
    assert vm.advanced == [0.001] and bus.pacer.cost == pytest.approx(0.5)
    wall.t += 0.5  # half a second of simulation would cost 0.25 s
    assert bus.request(request(1, 6, 1, 0))[0][1][2] == 100
    assert vm.advanced == [0.001]
    assert bus.lag == pytest.approx(0.5)


def test_without_a_runner_a_request_advances_one_bounded_slice():
    """A bus nobody runs a clock thread for (the dashboard of a bare `ModuleBus`, `opentmcl://`) moves
    on with its requests: each one simulates at most REQUEST_BUDGET's worth."""
    bus, vm, wall = costly_bus(0.5, runner=False)
    wall.t = 0.001
    bus.request(request(1, 6, 1, 0))
    wall.t += 0.5
    bus.request(request(1, 6, 1, 0))
    assert vm.advanced == [0.001, pytest.approx(REQUEST_BUDGET / 0.5)]


def test_attaching_a_runner_makes_requests_take_whole_lags_only():
    """`RealTimeRunner.start` tells the bus that a clock thread works the lag off; `stop` takes it back."""
    from opentmcl.server.bus import RealTimeRunner

    bus, _vm, _wall = costly_bus(0.0, runner=False)
    runner = RealTimeRunner(bus, tick=3600.0)
    runner.start()
    try:
        assert bus.runner_attached
    finally:
        runner.stop()
    assert not bus.runner_attached


def test_the_clock_thread_advances_one_bounded_slice_at_a_time():
    """Each slice of the clock thread costs SLICE_BUDGET by the estimate: 0.5 CPU s per virtual s
    gives slices of SLICE_BUDGET / 0.5; the lag shrinks by one slice per step."""
    bus, vm, wall = costly_bus(0.5)
    wall.t = 0.001
    bus.request(request(1, 6, 1, 0))
    wall.t += 0.3
    _events, lag = bus.step()
    assert vm.advanced[1:] == [pytest.approx(SLICE_BUDGET / 0.5)]
    assert lag == pytest.approx(0.3 - SLICE_BUDGET / 0.5)


def test_a_slice_advances_at_least_min_slice():
    """However costly the simulation, a slice makes progress: MIN_SLICE virtual seconds."""
    bus, vm, wall = costly_bus(1000.0)
    wall.t = 1e-6
    bus.request(request(1, 6, 1, 0))
    wall.t += 0.1
    bus.step()
    assert vm.advanced[-1] == pytest.approx(MIN_SLICE)


def test_a_lag_beyond_max_lag_is_dropped_and_reported():
    """docs/endpoints.md "When the simulation cannot keep up": the modules' clock catches up a lag
    of up to max_lag; beyond it the rest is dropped (the module runs slower than the wall clock)."""
    bus, vm, wall = costly_bus(2.0, max_lag=1.0)
    wall.t = 0.0005
    bus.request(request(1, 6, 1, 0))
    wall.t += 5.0
    bus.step()
    report = bus.clock_report()
    assert report.lag == pytest.approx(1.0)
    assert report.dropped == pytest.approx(5.0 - 1.0 - SLICE_BUDGET / 2.0)
    assert report.worst == pytest.approx(5.0 - SLICE_BUDGET / 2.0)
    assert report.cost == pytest.approx(2.0)
    assert vm.time == pytest.approx(0.0005 + SLICE_BUDGET / 2.0)


def test_a_cheap_lag_is_caught_up_whole_however_long():
    """Idle modules cost next to nothing: a long gap (a suspended process, a fake clock) is caught up
    whole, nothing dropped."""
    bus, vm, wall = costly_bus(1e-6)
    wall.t = 10.0
    bus.request(request(1, 6, 1, 0))
    assert vm.time == pytest.approx(10.0) and bus.clock_report().dropped == 0


def test_pacer_step_edges():
    """All of the lag when the budget buys it, else the budget's worth, never below MIN_SLICE, never
    beyond the lag; `whole` gives nothing rather than a part."""
    wall = Clock()
    pacer = Pacer(wall)
    pacer.cost = 0.5
    assert pacer.step(0.002, REQUEST_BUDGET) == pytest.approx(0.002)       # costs exactly the budget
    assert pacer.step(0.0021, REQUEST_BUDGET) == pytest.approx(0.002)      # first lag beyond it
    assert pacer.step(0.0021, REQUEST_BUDGET, whole=True) == 0.0
    assert pacer.step(0.0001, REQUEST_BUDGET) == pytest.approx(0.0001)
    pacer.cost = 1e6
    assert pacer.step(1.0, REQUEST_BUDGET) == MIN_SLICE
    assert pacer.step(MIN_SLICE / 2, REQUEST_BUDGET) == MIN_SLICE / 2
    assert pacer.step(-1.0, REQUEST_BUDGET) == 0.0
    with pytest.raises(ValueError):
        Pacer(wall, max_lag=0)
