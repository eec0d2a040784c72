"""One request path in the host library (issue 33, "a host request: `Client.request` and the lean
in-process path"; docs/architecture.md "Request path", host side).

A reply belongs to a request when its module address and command are those of the request
(TMCM-6212 manual 3.2); "target position reached" replies (status 128, command 138, manual
3.6.35) that arrive in between are kept; a reply of another module or command is counted and
dropped; a status other than 100/101 raises; a wrong checksum makes the reader move on byte by
byte (manual 3.1.1), and a good frame found only a whole frame or more further on follows a
garbled reply, which is the request's error (issue 34). The common case, the first frame is the plain reply asked for, is a short
path of that one rule: the in-process transport hands the reply over at once
(`Transport.exchange`), and the client decodes a plain reply without the general loop. These tests
check that the short path answers exactly as the rule does: against an oracle of the rule on any
byte stream, between an in-process link and the same link read through its receive buffer, and
from several threads at once.
"""
from __future__ import annotations

import sys
import threading
import time
import tracemalloc
from enum import IntEnum
from functools import partial

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from opentmcl import VirtualModule
from opentmcl.host import Client, TmclProtocolError, TmclStatusError, TmclTimeout, TmclTypeError
from opentmcl.host.client import MAX_PLAIN
from opentmcl.host.transports.inprocess import InProcessTransport
from opentmcl.protocol.frame import Reply, Request

from .fakes import FencedScript, ScriptedTransport

GAP, SAP, SGP, GGP, MVP = 6, 5, 9, 10, 4
HOST, MODULE, OTHER = 2, 1, 3


class Buffered(InProcessTransport):
    """Watches `send`: every reply goes through the receive buffer and `recv` (the general way)."""

    def send(self, data: bytes) -> None:
        super().send(data)


# --- the rule, as an oracle over a byte stream --------------------------------------------------

def _checksum_ok(frame: bytes) -> bool:
    return sum(frame[:8]) % 256 == frame[8]


class Oracle:
    """The matching rule of manual 3.2 / 3.6.35 over a byte stream, one request at a time."""

    def __init__(self, can: bool) -> None:
        self.can = can
        self.buffer = b""
        self.events = 0
        self.strays = 0
        self.dirty = False

    def answer(self, arrived: bytes, address: int, command: int) -> tuple:
        if self.dirty:  # what was left of a lost reply is discarded before the next request
            self.buffer, self.dirty = b"", False
        self.buffer += arrived
        size = 7 if self.can else 9
        while True:
            if len(self.buffer) < size:
                self.dirty = True
                return ("timeout",)
            frame, self.buffer = self.buffer[:size], self.buffer[size:]
            if not self.can:
                skipped = 0
                while not _checksum_ok(frame):
                    if not self.buffer:
                        self.dirty = True
                        return ("protocol",)
                    frame, self.buffer = frame[1:] + self.buffer[:1], self.buffer[1:]
                    skipped += 1
                if skipped >= size:  # a whole frame or more garbled: the reply (issue 34)
                    self.dirty = True
                    return ("protocol",)
                reply_address, module, status, cmd = frame[0], frame[1], frame[2], frame[3]
                value = int.from_bytes(frame[4:8], "big", signed=True)
            else:
                reply_address, module, status, cmd = HOST, frame[0], frame[1], frame[2]
                value = int.from_bytes(frame[3:7], "big", signed=True)
            if status == 128 and cmd == 138:
                if self.can or module == address:  # another module's events are kept under its address
                    self.events |= value & 0xFFFFFFFF
                continue
            if (not self.can and module != address) or cmd != command:
                self.strays += 1
                continue
            if status not in (100, 101, 128):
                return ("status", status, None, None)
            return ("reply", Reply(reply_address, module, status, cmd, value))


def outcome(call) -> tuple:
    try:
        return ("reply", call())
    except TmclStatusError as exc:
        return ("status", exc.status, exc.index, exc.answers)
    except TmclProtocolError:
        return ("protocol",)
    except TmclTimeout:
        return ("timeout",)


def serial_frames(command: int) -> st.SearchStrategy[bytes]:
    """Frames a host may receive while waiting for `command` from module 1: the plain reply and
    its variants, events, strays, wrong checksums and stray bytes."""
    value = st.integers(-(2**31), 2**31 - 1)
    frame = st.builds(lambda *f: Reply(*f).encode(), st.sampled_from([HOST, 0, 255]),
                      st.sampled_from([MODULE, OTHER]), st.sampled_from([100, 101, 128, 1, 2, 3, 4, 5, 6]),
                      st.sampled_from([command, 138, 5]), value)
    plain = st.builds(lambda v: Reply(HOST, MODULE, 100, command, v).encode(), st.integers(-3, 3))
    bad = frame.map(lambda f: f[:8] + bytes([(f[8] + 1) % 256]))
    return st.one_of(plain, plain, frame, bad, st.binary(min_size=1, max_size=4))


def can_frames(command: int) -> st.SearchStrategy[bytes]:
    value = st.integers(-(2**31), 2**31 - 1)
    return st.builds(lambda m, s, c, v: bytes([m, s, c]) + v.to_bytes(4, "big", signed=True),
                     st.sampled_from([MODULE, OTHER]), st.sampled_from([100, 101, 128, 2, 4]),
                     st.sampled_from([command, command, 138, 5]), value)


@settings(max_examples=300, deadline=None)
@given(st.data(), st.sampled_from(["serial", "can"]))
def test_any_stream_of_replies_is_read_as_the_rule_says(data, frame_format):
    """Several requests in a row (the same one again and again, so that a repeated reply is met
    too), each answered by a random stream of frames: the client's answer, its kept events and its
    count of stray replies are those of the rule."""
    can = frame_format == "can"
    frames = can_frames(GAP) if can else serial_frames(GAP)
    streams = data.draw(st.lists(st.lists(frames, max_size=4).map(b"".join), min_size=1, max_size=5))
    t = FencedScript(*streams, frame_format=frame_format)  # the fence after a loss answered in step
    client = Client(t, host_address=HOST)
    oracle = Oracle(can)
    for stream in streams:
        assert outcome(lambda: client.request(GAP, 1, 0, timeout=1.0)) == oracle.answer(stream, MODULE, GAP)
        assert client.pending_events() == oracle.events
        assert client.stray_replies == oracle.strays


def test_a_reply_of_a_negative_value_on_can():
    """PD86-1180 manual 4.2: a CAN reply is module address, status, command and the value, MSB
    first, signed (the example value -1 as FF FF FF FF)."""
    t = ScriptedTransport(bytes([1, 100, 6, 0xFF, 0xFF, 0xFF, 0xFF]), bytes([1, 100, 6, 0x80, 0, 0, 0]),
                          frame_format="can")
    client = Client(t, host_address=HOST)
    assert client.request(GAP, 1, 0) == Reply(HOST, 1, 100, 6, -1)
    assert client.request(GAP, 1, 0) == Reply(HOST, 1, 100, 6, -(2**31))


def test_a_can_reply_carries_the_host_address_of_the_moment():
    """A CAN reply has no reply address (PD86-1180 manual 4.2): the client gives its own
    `host_address`, also for a reply with the same bytes as one before."""
    same = bytes([1, 100, 6, 0, 0, 0, 7])
    client = Client(ScriptedTransport(same, same, frame_format="can"), host_address=HOST)
    assert client.request(GAP, 1, 0).reply_address == HOST
    client.host_address = 5
    assert client.request(GAP, 1, 0) == Reply(5, 1, 100, 6, 7)


# --- in process: the reply at hand against the reply through the buffer --------------------------

class ScriptedModule:
    """A `SimulatedModule` answering each frame with the next scripted bytes (maybe nothing, a
    garbled frame or several frames), with events raised right after it or before the next one."""

    def __init__(self, steps: list[tuple[bytes, list[bytes]]]) -> None:
        self.steps = list(steps)
        self.events: list[bytes] = []
        self.frames: list[bytes] = []

    def handle(self, frame: bytes) -> bytes:
        self.frames.append(bytes(frame))
        if not self.steps:
            return b""
        reply, events = self.steps.pop(0)
        self.events += events
        return reply

    def drain_events(self) -> list[bytes]:
        out = self.events[:]   # the same list stays (the transport looks at it: SimulatedModule)
        self.events.clear()
        return out

    def advance(self, seconds: float) -> None:
        return None


def event(mask: int) -> bytes:
    return Reply(HOST, MODULE, 128, 138, mask).encode()


@st.composite
def scripts(draw):
    reply = serial_frames(GAP) | st.just(b"") | st.lists(serial_frames(GAP), min_size=2, max_size=3).map(b"".join)
    events = st.lists(st.sampled_from([1, 2, 4]).map(event), max_size=2)
    steps = draw(st.lists(st.tuples(reply, events), min_size=1, max_size=8))
    before = draw(st.lists(events, min_size=len(steps), max_size=len(steps)))  # raised outside the transport
    many = draw(st.lists(st.integers(0, 3), min_size=len(steps), max_size=len(steps)))  # 0: request
    return steps, before, many


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(scripts())
def test_a_reply_at_hand_is_read_as_through_the_buffer(script):
    """The in-process link's short case (the reply handed over at once) against the same link whose
    every reply goes through its receive buffer: the same answers, events and strays, also when
    the module answers twice, garbles, stays silent or raises events before or after a frame."""
    steps, before, many = script
    outcomes, states = [], []
    for transport in (InProcessTransport, Buffered):
        module = ScriptedModule(steps)
        client = Client(transport(module, clock="none"), host_address=HOST)
        got = []
        for raised, batch in zip(before, many, strict=True):
            module.events += raised
            if batch:
                got.append(outcome(partial(client.request_many, [(GAP, 1, 0, 0)] * batch, timeout=0.5)))
            else:
                got.append(outcome(partial(client.request, GAP, 1, 0, timeout=0.5)))
            got.append((client.pending_events(), client.stray_replies))
        outcomes.append(got)
        states.append(module.frames)
    assert outcomes[0] == outcomes[1]
    assert states[0] == states[1]


ops = st.one_of(
    st.tuples(st.just("request"), st.sampled_from([(GAP, 1), (GAP, 8), (GAP, 4), (GAP, 0), (GGP, 255)]),
              st.integers(0, 6)),
    st.tuples(st.just("set"), st.sampled_from([(SAP, 4), (SAP, 5), (SGP, 0)]), st.integers(0, 6),
              st.integers(-5, 60000)),
    st.tuples(st.just("move"), st.integers(0, 5), st.integers(-3000, 3000)),
    st.tuples(st.just("event"), st.integers(1, 63)),
    st.tuples(st.just("sleep"), st.sampled_from([0.0, 0.01, 0.2, 1.0])),
    st.tuples(st.just("many"), st.lists(st.sampled_from([(GAP, 1, 0, 0), (GAP, 8, 1, 0), (GAP, 1, 7, 0),
                                                        (136, 0, 0, 0), (136, 1, 0, 0)]), max_size=4)),
    st.tuples(st.just("suppress"), st.integers(0, 1)),
    st.tuples(st.just("wait"), st.integers(1, 3)),
)


def run_op(m: Client, op: tuple) -> object:
    kind = op[0]
    if kind == "request":
        (command, type_), motor = op[1], op[2]
        return m.request(command, type_, motor, timeout=0.05)
    if kind == "set":
        (command, type_), motor, value = op[1], op[2], op[3]
        return m.request(command, type_, motor, value, timeout=0.05)
    if kind == "move":
        return m.request(MVP, 0, op[1], op[2], timeout=0.05)
    if kind == "event":
        return m.request(138, 0, 0, op[1], timeout=0.05)
    if kind == "sleep":
        return m.sleep(op[1])
    if kind == "many":
        return m.request_many(op[1], timeout=0.05)
    if kind == "suppress":
        return m.request(SGP, 255, 0, op[1], timeout=0.05)
    return m.wait_position_reached(op[1], timeout=0.3)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(st.lists(ops, min_size=1, max_size=25))
def test_a_virtual_module_answers_alike_at_hand_and_through_the_buffer(program):
    """A TMCM-6212: reads, writes (some out of range: status 4), moves with their command-138
    events, time passing, batches with special replies (136), GP255 = 1 suppressing the replies of
    writes (manual 5.1) and waiting for events. Both links give the same answers, errors, kept
    events, strays and virtual time."""
    results = []
    for transport in (InProcessTransport, Buffered):
        vm = VirtualModule("TMCM-6212", address=1)
        client = Client(transport(vm), host_address=HOST)
        got = []
        for op in program:
            try:
                got.append(("ok", run_op(client, op)))
            except TmclStatusError as exc:
                got.append(("status", exc.status, exc.index, exc.answers))
            except TmclTimeout as exc:
                got.append(("timeout", str(exc)))
            got.append((client.pending_events(), client.stray_replies, vm.now))
        results.append(got)
    assert results[0] == results[1]


# --- checked once, sent again -------------------------------------------------------------------

class Motor(IntEnum):
    ZERO = 0


@pytest.mark.parametrize(("args", "kwargs"), [
    ((GAP, True, 0), {}), ((GAP, 1.0, 0), {}), ((GAP, 1, False), {}), ((6.0, 1, 0), {}),
    ((GAP, 1, 0, 0.0), {}), ((GAP, 1, 0), {"address": True}),
])
def test_a_value_equal_to_a_request_sent_before_is_still_refused(args, kwargs):
    """Issue 33 keeps every typed error: a bool or a float is no TMCL field (TmclTypeError, nothing
    sent), even when it equals the fields of a request already sent (True == 1, 1.0 == 1)."""
    vm = ScriptedModule([(Reply(HOST, 1, 100, GAP, 0).encode(), [])])
    client = Client(InProcessTransport(vm))
    client.request(GAP, 1, 0, 0, address=1)
    with pytest.raises(TmclTypeError):
        client.request(*args, **kwargs)
    assert len(vm.frames) == 1


def test_an_int_enum_is_a_plain_int():
    """An IntEnum member is an int: it is sent as its value, before and after the plain int."""
    client = Client(InProcessTransport(VirtualModule("TMCM-6212", address=1)))
    client.request(SAP, 4, 0, 1234)
    assert client.request(GAP, 4, Motor.ZERO).value == 1234
    assert client.request(GAP, 4, 0).value == 1234
    assert client.request(GAP, 4, Motor.ZERO).value == 1234


def test_the_default_address_is_read_at_each_request():
    """`Client.address` may change (e.g. after SGP 66, manual 5.1): the next request without an
    address goes to the new one, although the same request went to the old one before."""
    bus = InProcessTransport([VirtualModule("TMCM-6212", address=1), VirtualModule("PD86-1180", address=2)])
    client = Client(bus)
    assert client.request(GGP, 66, 0).value == 1
    client.address = 2
    assert client.request(GGP, 66, 0).value == 2


def test_more_distinct_requests_than_are_kept():
    """The client keeps up to MAX_PLAIN checked requests; past that it starts afresh, and every
    answer is still the module's."""
    client = Client(InProcessTransport(VirtualModule("TMCM-6212", address=1)))
    for v in range(MAX_PLAIN + 3):
        client.request(SGP, 0, 2, v)   # user variable 0 (bank 2, manual 5.3), a new value each time
        assert client.request(GGP, 0, 2).value == v


def test_what_is_kept_is_bounded():
    """A host that writes ever new values (SGP of a user variable, manual 5.3) keeps no more of
    them than MAX_PLAIN: memory does not grow with the number of requests."""
    client = Client(InProcessTransport(VirtualModule("TMCM-6212", address=1)))
    tracemalloc.start()
    try:
        for v in range(2 * MAX_PLAIN):
            client.request(SGP, 0, 2, v)
        before = tracemalloc.get_traced_memory()[0]
        for v in range(2 * MAX_PLAIN, 6 * MAX_PLAIN):
            client.request(SGP, 0, 2, v)
        grown = tracemalloc.get_traced_memory()[0] - before
    finally:
        tracemalloc.stop()
    assert grown < 400 * MAX_PLAIN  # keeping all 4 * MAX_PLAIN would take about 600 bytes each


def test_the_same_reply_twice_and_then_another():
    """A repeated reply decodes as the first; a changed one as itself (GAP 1 of a moving axis)."""
    client = Client(InProcessTransport(VirtualModule("TMCM-6212", address=1)))
    first, again = client.request(GAP, 1, 0), client.request(GAP, 1, 0)
    assert first == again == Reply(HOST, 1, 100, GAP, 0)
    client.request(SAP, 1, 0, -77)
    assert client.request(GAP, 1, 0) == Reply(HOST, 1, 100, GAP, -77)


# --- threads ------------------------------------------------------------------------------------

@pytest.fixture
def busy_switching():
    """Threads switch as often as the interpreter allows, to bring races out."""
    before = sys.getswitchinterval()
    sys.setswitchinterval(1e-6)
    yield
    sys.setswitchinterval(before)


class Yielding:
    """A VirtualModule that lets other threads run in the middle of each call, as the interpreter
    may at any instruction."""

    def __init__(self, vm: VirtualModule) -> None:
        self.vm = vm

    def handle(self, frame: bytes) -> bytes:
        time.sleep(0)
        return self.vm.handle(frame)

    def drain_events(self) -> list[bytes]:
        time.sleep(0)
        return self.vm.drain_events()

    def advance(self, seconds: float) -> None:
        self.vm.advance(seconds)


def test_threads_share_a_client_and_the_link_lock(busy_switching):
    """docs/host.md: a `Client` may be shared by threads. Four threads each write and read back
    their own axis (SAP/GAP 4, manual 3.6.5/3.6.6) and user variable, one sends batches and
    moves with command-138 events, and a dashboard-like thread reads the module directly under
    the link's `lock`: every thread reads back what it wrote, no reply goes astray."""
    vm = VirtualModule("TMCM-6212", address=1)
    t = InProcessTransport(Yielding(vm))
    client = Client(t)
    errors: list[BaseException] = []
    rounds = 200

    def writer(axis: int) -> None:
        for i in range(rounds):
            value = 1000 + 100 * axis + i
            client.request(SAP, 4, axis, value)
            assert client.request(GAP, 4, axis).value == value
            client.request(SGP, axis, 2, -value)
            assert client.reply(GGP, axis, 2).value == -value

    def batches() -> None:
        client.request(138, 1, 0, 1 << 5)  # every time axis 5 reaches its target
        for i in range(rounds):
            client.request(MVP, 0, 5, 10 * (i % 3))
            answers = client.request_many([(GAP, 4, a, 0) for a in range(4)] + [(136, 1, 0, 0)])
            assert len(answers) == 5
            client.sleep(0.001)

    def dashboard() -> None:
        frame = Request(1, GGP, 66, 0, 0).encode()
        for _ in range(rounds):
            with t.lock:
                assert vm.handle(frame) == Reply(HOST, 1, 100, GGP, 1).encode()

    def guarded(target, *args):
        try:
            target(*args)
        except BaseException as exc:  # reported below
            errors.append(exc)

    threads = [threading.Thread(target=guarded, args=(writer, a)) for a in range(4)]
    threads += [threading.Thread(target=guarded, args=(batches,)), threading.Thread(target=guarded, args=(dashboard,))]
    for th in threads:
        th.start()
    for th in threads:
        th.join(timeout=120)
    assert not any(th.is_alive() for th in threads)
    assert errors == []
    assert client.stray_replies == 0


def test_a_request_waits_while_another_thread_holds_the_link_lock():
    """The link's one lock (`Transport.lock`): while the dashboard works on the module under it, a
    request from another thread waits, then completes."""
    t = InProcessTransport(VirtualModule("TMCM-6212", address=1))
    client = Client(t)
    client.request(GGP, 66, 0)
    done = threading.Event()
    results = []

    def request() -> None:
        results.append(client.request(GGP, 66, 0).value)
        done.set()

    with t.lock:
        th = threading.Thread(target=request)
        th.start()
        assert not done.wait(0.2)
    assert done.wait(30)
    th.join(30)
    assert results == [1]
