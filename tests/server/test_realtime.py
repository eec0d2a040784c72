"""The bus in real time (issue 28, docs/architecture.md "Real time"): stops take the bus first
(the lock itself: tests/test_handover.py), the simulation advances in bounded slices, and the modules' clock lags (and
drops what it cannot catch up) instead of the replies.

Costs are measured on a work clock the tests drive, so nothing here depends on the machine's speed.
"""
from __future__ import annotations

import threading
import time

import pytest

from opentmcl import VirtualModule
from opentmcl.handover import BACKGROUND, REQUEST, STOP
from opentmcl.server.bus import ModuleBus, urgency
from opentmcl.server.pacing import FIRST_SLICE, MIN_SLICE, REQUEST_BUDGET, SLICE_BUDGET, Pacer

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
    """Idle modules cost next to nothing: once that is measured, a long gap (a suspended process, a
    fake clock) is caught up whole, nothing dropped."""
    bus, vm, wall = costly_bus(1e-6)
    wall.t = 0.001
    bus.request(request(1, 6, 1, 0))  # the first slice measures the cost
    wall.t = 10.0
    bus.request(request(1, 6, 1, 0))
    assert vm.time == pytest.approx(10.0) and bus.clock_report().dropped == 0


def test_before_the_cost_is_measured_a_slice_is_short():
    """A served bus does not know what its modules cost before it has simulated them (a TMCL
    program started from the EEPROM at power-up may cost more than a CPU): the first lag is left
    by a request to the clock thread, which simulates FIRST_SLICE of it and so measures the cost;
    then the slices follow the estimate. (Before: the whole start-up lag in one slice.)"""
    bus, vm, wall = costly_bus(0.5)
    wall.t = 5.0
    assert bus.request(request(1, 6, 1, 0))[0][1][2] == 100
    assert vm.advanced == []
    bus.step()
    assert vm.advanced == [FIRST_SLICE] and bus.pacer.cost == pytest.approx(0.5)
    bus.step()
    assert vm.advanced[1] == pytest.approx(SLICE_BUDGET / 0.5)


def test_without_a_clock_thread_the_first_lag_is_taken_whole():
    """A bare bus (no clock thread: the library with a fake clock) moves on with its requests as
    before: an unmeasured lag is simulated whole."""
    bus, vm, wall = costly_bus(0.5, runner=False)
    wall.t = 5.0
    bus.request(request(1, 6, 1, 0))
    assert vm.advanced == [5.0]


def many_costly(count: int, cost: float, log: list):
    """A served bus (clock thread attached, not started) of `count` `CostlyModule`s at addresses
    1..count on a test clock, each noting ("advance", address) and ("handle", address) in `log`."""
    wall, work = Clock(), Clock()

    class Noting(CostlyModule):
        def advance(self, seconds: float) -> None:
            log.append(("advance", self.address))
            super().advance(seconds)
            if self.hook is not None:
                self.hook()

        def handle(self, frame, *, interface="serial"):
            log.append(("handle", self.address))
            return super().handle(frame, interface=interface)

    modules = [Noting(work, cost, address=a) for a in range(1, count + 1)]
    for vm in modules:
        vm.hook = None
    bus = ModuleBus(modules, clock=wall, min_step=0.0, pacer=Pacer(wall, work_clock=work))
    bus.runner_attached = True
    return bus, modules, wall


def test_a_clock_slice_serves_waiting_requests_between_two_modules():
    """Issue 28: "the real-time loop advances the simulation in bounded slices and serves pending
    requests between them", on "a bus of up to 255 modules": a slice advances the modules one
    after the other, and a request that comes while it runs is served after the module being
    advanced, not after all of them (with 255 modules running the issue's program one slice held
    the bus for 40 ms; GAP p99 was 224 ms with two CPU burners). The request is answered at the
    time of its module, which the slice has not reached yet, and does not advance any module
    itself: after the slice every module stands at the same time, the wall clock's."""
    log: list = []
    bus, modules, wall = many_costly(3, 0.5, log)
    wall.t = 0.001
    bus.request(request(1, 6, 1, 0))  # the cost is now known
    del log[:]
    replies: list = []

    def ask() -> None:
        replies.extend(bus.request(request(3, 6, 1, 0)))

    asker = threading.Thread(target=ask)

    def during_first() -> None:
        modules[0].hook = None
        asker.start()
        end = time.monotonic() + 30
        while bus.lock.waiting() < 1 and time.monotonic() < end:
            time.sleep(0.001)

    modules[0].hook = during_first
    wall.t += 0.0005
    bus.step()
    asker.join(30)
    assert log == [("advance", 1), ("handle", 3), ("advance", 2), ("advance", 3)]
    assert replies and replies[0][1][2] == 100
    assert [vm.time for vm in modules] == [pytest.approx(wall.t)] * 3


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


class Recording(VirtualModule):
    """A TMCM-6212 noting the command byte of every frame it reads."""

    def __init__(self, **kwargs) -> None:
        self.handled: list[int] = []
        super().__init__("TMCM-6212", **kwargs)

    def handle(self, frame, *, interface="serial"):
        self.handled.append(frame[1])
        return super().handle(frame, interface=interface)


@pytest.mark.parametrize("stop_over", ["pty", "tcp"])
def test_a_stop_over_any_serial_endpoint_goes_ahead_of_requests_waiting(stop_over):
    """Issue 28: "Stop requests (128, MST, 131 ...) go ahead of queued work" on every endpoint,
    also when the stop comes over another endpoint than the one that loads the bus: with the bus
    busy, two TCP clients' GAP requests (3.6.6) wait for it; an MST (3.6.3) that comes after them
    over the pty (or a third TCP client) is read by the module first. (Before: the TCP and pty
    endpoints took the bus as plain requests, so the stop waited behind every one of them.)"""
    import socket

    import serial

    from opentmcl.server import PtyServer, TcpServer

    from .helpers import recv_exactly

    vm = Recording(address=1)
    bus = ModuleBus([vm])
    tcp = TcpServer(bus, "127.0.0.1", 0)
    pty = PtyServer(bus, interface="rs485")
    tcp.start()
    pty.start()
    clients = [socket.create_connection(tcp.address, timeout=30) for _ in range(3)]
    port = serial.Serial(pty.path, timeout=30)
    try:
        bus.lock.acquire(BACKGROUND)  # a clock slice is running
        try:
            for n, client in enumerate(clients[:2], 1):
                client.sendall(request(1, 6, 1, 0))
                end = time.monotonic() + 30
                while bus.lock.waiting() < n and time.monotonic() < end:
                    time.sleep(0.001)
            if stop_over == "pty":
                port.write(request(1, 3, 0, 0))
            else:
                clients[2].sendall(request(1, 3, 0, 0))
            end = time.monotonic() + 30
            while bus.lock.waiting() < 3 and time.monotonic() < end:
                time.sleep(0.001)
        finally:
            bus.lock.release()
        assert [recv_exactly(c, 9, timeout=30)[2] for c in clients[:2]] == [100, 100]
        stop_reply = port.read(9) if stop_over == "pty" else recv_exactly(clients[2], 9, timeout=30)
        assert stop_reply[2] == 100
        assert vm.handled == [3, 6, 6]
    finally:
        port.close()
        for client in clients:
            client.close()
        tcp.stop()
        pty.stop()


class Hooked(Recording):
    """A `Recording` module that calls `hook` (once) while it handles the first frame."""

    hook = None

    def handle(self, frame, *, interface="serial"):
        hook, self.hook = self.hook, None
        if hook is not None:
            hook()
        return super().handle(frame, interface=interface)


def wait_for(predicate, what: str) -> None:
    end = time.monotonic() + 30
    while not predicate():
        assert time.monotonic() < end, f"not reached: {what}"
        time.sleep(0.001)


@pytest.mark.parametrize("split", [False, True])
def test_a_stop_goes_between_two_frames_of_another_hosts_pipelined_read(split):
    """Issue 28: "Stop requests ... go ahead of queued work". A host may pipeline hundreds of frames
    in one read (docs/endpoints.md "Several frames at once"), each maybe costly (a factory reset,
    137, of a large profile: 30 ms); a stop of another host goes between two of them, not after the
    whole read: three GAPs (3.6.6) in one read, and an MST (3.6.3) that comes over a second
    connection while the first GAP is handled, is read by the module second; also when the read
    completes a frame begun by the read before (`split`: the general path of server/stream.py).
    (Before: after the last GAP; a host pipelining 137 held a stop 15.7 s.)"""
    import socket

    from opentmcl.server import TcpServer

    from .helpers import recv_exactly

    vm = Hooked(address=1)
    bus = ModuleBus([vm])
    tcp = TcpServer(bus, "127.0.0.1", 0)
    tcp.start()
    busy, stopper = (socket.create_connection(tcp.address, timeout=30) for _ in range(2))
    try:
        def stop_meanwhile() -> None:
            stopper.sendall(request(1, 3, 0, 0))
            wait_for(lambda: bus.lock.stops_waiting, "the MST waiting for the bus")

        frames = request(1, 6, 1, 0) * 3
        if split:  # the first 4 bytes in a read of their own, the rest in the next
            busy.sendall(frames[:4])
            wait_for(lambda: sum(s.bytes_received for s in tcp.sessions) == 4, "the first 4 bytes handled")
            frames = frames[4:]
        vm.hook = stop_meanwhile
        busy.sendall(frames)
        assert recv_exactly(stopper, 9, timeout=30)[2] == 100
        assert len(recv_exactly(busy, 27, timeout=30)) == 27
        assert vm.handled == [6, 3, 6, 6]
    finally:
        busy.close()
        stopper.close()
        tcp.stop()


def test_a_server_that_stops_drops_the_rest_of_a_pipelined_read():
    """Issue 28: "`serve` ends within 2 s of SIGTERM/SIGINT in any state": an endpoint that stops
    while it handles a read of many frames handles no further frame of it (the server closes the
    modules and writes the EEPROM at once). (Before: a read of 455 factory resets of a large
    profile kept `serve` from ending for 16 s.)"""
    import socket

    from opentmcl.server import TcpServer

    vm = Hooked(address=1)
    bus = ModuleBus([vm])
    tcp = TcpServer(bus, "127.0.0.1", 0)
    tcp.start()
    stopping = threading.Thread(target=tcp.stop)
    client = socket.create_connection(tcp.address, timeout=30)
    try:
        def stop_meanwhile() -> None:
            stopping.start()
            wait_for(lambda: all(s.closed for s in tcp.sessions), "the session closing")

        vm.hook = stop_meanwhile
        client.sendall(request(1, 6, 1, 0) * 3)
        wait_for(lambda: stopping.ident is not None, "the endpoint stopping")
        stopping.join(30)
        assert vm.handled == [6]
    finally:
        client.close()
        tcp.stop()
