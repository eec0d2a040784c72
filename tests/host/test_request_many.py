"""`Client.request_many` / `Module.request_many`: several requests, answers in order.

TMCM-6212 manual 3.1 (request frame), 3.2 (reply frame, status codes), 3.6.35 (command 138 and its
"target position reached" reply, status 128), 3.6.36 (136 type 0: version string, 134: program
memory). The answers must be exactly those of `request`, one by one, on the same module state.
"""
from __future__ import annotations

import pytest

import opentmcl
from opentmcl import VirtualModule
from opentmcl.host import (
    Client,
    TmclBatchError,
    TmclStatusError,
    TmclTimeout,
    TmclTypeError,
    TmclValueError,
    open_bus,
)
from opentmcl.host.client import MAX_BATCH, VersionReply
from opentmcl.host.transports.inprocess import Clock, InProcessTransport
from opentmcl.protocol.frame import Reply, Request
from opentmcl.protocol.replies import MemoryReply

from .fakes import ScriptedTransport

GAP, SAP, SGP, GGP, MVP = 6, 5, 9, 10, 4


def sim(**kwargs) -> opentmcl.Module:
    return opentmcl.connect("sim://TMCM-6212", profile="TMCM-6212", **kwargs)


def test_answers_equal_single_requests_on_twin_modules():
    """The same requests through `request` on one module and `request_many` on a twin: equal
    answers, in order (manual 3.2 reply format: host 2, module 1, status, command, value)."""
    one, many = sim(), sim()
    setup = [(SAP, 4, 0, 1000), (MVP, 0, 0, 5000), (SAP, 4, 3, 2000), (MVP, 0, 3, -7000)]
    reads = [(GAP, t, m, 0) for m in range(6) for t in (1, 3, 8)] + [(GGP, 66, 0, 0)]
    for command, type_, motor, value in setup:
        one.request(command, type_, motor, value)
    many.request_many(setup)
    for _ in range(3):
        one.sleep(0.05)
        many.sleep(0.05)
        expected = [one.request(*r) for r in reads]
        assert many.request_many(reads) == expected
    assert all(isinstance(a, Reply) and a.status == 100 for a in expected)
    assert expected[0].value != 0  # the axes moved: the figures are not all zeros


def test_batch_of_one_is_the_manual_example():
    """Manual 3.6.8 example GGP 66, 0: the reply carries the module address, 1."""
    m = sim()
    assert m.request_many([(GGP, 66, 0, 0)]) == [Reply(2, 1, 100, GGP, 1)]


def test_empty_batch_sends_nothing():
    t = ScriptedTransport()
    assert Client(t).request_many([]) == []
    assert t.sent == []


def test_the_maximum_and_one_over():
    """MAX_BATCH requests are answered; MAX_BATCH + 1 is a TmclBatchError (a TmclValueError)
    and nothing is sent."""
    m = sim()
    m.request(SGP, 0, 2, 41)   # user variable 0 (bank 2) = 41
    answers = m.request_many([(GGP, 0, 2, 0)] * MAX_BATCH)
    assert len(answers) == MAX_BATCH and {a.value for a in answers} == {41}
    t = ScriptedTransport()
    with pytest.raises(TmclBatchError, match=str(MAX_BATCH)) as info:
        Client(t).request_many([(GGP, 0, 2, 0)] * (MAX_BATCH + 1))
    assert isinstance(info.value, TmclValueError)
    assert t.sent == []


@pytest.mark.parametrize("bad, error, text", [
    ([(GAP, 1, 0)], TmclTypeError, r"requests\[0\]"),
    ([(GAP, 1, 0, 0), (GAP, 256, 0, 0)], TmclValueError, r"requests\[1\]: type must be 0\.\.255"),
    ([(GAP, 1, 0, 0), (GAP, 1, 0, 2**32)], TmclValueError, r"requests\[1\]: value"),
    ([(GAP, 1, 0, 1.5)], TmclTypeError, r"requests\[0\]: value must be an int"),
    ("GAP 1, 0", TmclTypeError, "sequence"),
])
def test_bad_requests_are_refused_before_anything_is_sent(bad, error, text):
    t = ScriptedTransport()
    with pytest.raises(error, match=text):
        Client(t).request_many(bad)
    assert t.sent == []


def test_last_valid_field_values_pass():
    """255 in each byte and the 32-bit extremes are valid frame fields (manual 3.1); value
    2**32 - 1 is sent as -1, as by `request`."""
    t = ScriptedTransport(Reply(2, 1, 100, 255, 0).encode(), Reply(2, 1, 100, 255, 0).encode(),
                          Reply(2, 1, 100, 255, 0).encode())
    t.window = 8
    Client(t).request_many([(255, 255, 255, -2**31), (255, 255, 255, 2**31 - 1), (255, 255, 255, 2**32 - 1)])
    assert t.sent == [Request(1, 255, 255, 255, v).encode() for v in (-2**31, 2**31 - 1, -1)]


def test_wrong_status_in_the_middle_reads_every_reply_first():
    """Status 4 "invalid value" (manual 3.2.1) for GAP on motor 6 of a six-axis module, in the middle
    of a batch: the requests after it are still executed and read, then the TmclStatusError of that
    request is raised with its index and the answers of the others; the link stays in step."""
    m = sim()
    with pytest.raises(TmclStatusError) as info:
        m.request_many([(SGP, 0, 2, 7), (GAP, 1, 6, 0), (SGP, 1, 2, 8), (GGP, 1, 2, 0)])
    exc = info.value
    assert exc.status == 4 and exc.index == 1
    assert exc.request == Request(1, GAP, 1, 6, 0)
    assert exc.answers is not None and exc.answers[1] is None
    assert exc.answers[3] == Reply(2, 1, 100, GGP, 8)   # the request after the error ran
    assert m.request(GGP, 0, 2) == Reply(2, 1, 100, GGP, 7)  # and the next request is in step


def test_first_of_two_errors_is_raised():
    m = sim()
    with pytest.raises(TmclStatusError) as info:
        m.request_many([(GAP, 250, 0, 0), (GAP, 1, 6, 0)])
    assert (info.value.status, info.value.index) == (3, 0)  # 3 "wrong type" first, 4 later


def test_special_replies_in_a_batch():
    """136 type 0 is the version string (manual 3.6.36), 134 the stored instruction, 137 no reply:
    each answered as `request` answers it, in the middle of normal replies."""
    m = sim()
    m.download_program([(4, 0, 0, 1234)])  # MVP ABS, 0, 1234 at address 0
    answers = m.request_many([(GGP, 66, 0, 0), (136, 0, 0, 0), (134, 0, 0, 0), (136, 1, 0, 0), (GGP, 66, 0, 0)])
    assert isinstance(answers[1], VersionReply) and answers[1].text == "6212V105"
    assert isinstance(answers[2], MemoryReply) and answers[2] == m.request(134, 0, 0, 0)
    assert answers[3] == m.request(136, 1)
    assert answers[0] == answers[4] == Reply(2, 1, 100, GGP, 1)


def test_event_between_replies_is_kept_for_wait_position_reached():
    """A command-138 "position reached" reply (status 128, manual 3.6.35) that arrives among the
    replies of a batch is not taken for one of them: it is kept as a pending event."""
    reply = Reply(2, 1, 100, GAP, 5).encode()
    event = Reply(2, 1, 128, 138, 0b101).encode()   # motors 0 and 2 reached
    t = ScriptedTransport(reply, event + reply, reply)
    t.window = 8
    c = Client(t)
    assert [a.value for a in c.request_many([(GAP, 1, 0, 0)] * 3)] == [5, 5, 5]
    assert c.pending_events() == 0b101
    assert c.wait_position_reached(0b101, timeout=0.1) == 0b101


def test_event_from_a_moving_axis_in_process():
    """In process: the module's own 138 event arriving while a batch polls it (manual 3.6.35)."""
    m = sim()
    m.request(SAP, 4, 0, 2047)
    m.request(138, 0, 0, 1)           # report motor 0 once it reaches its target
    m.request(MVP, 0, 0, 2000)
    seen = 0
    for _ in range(200):
        m.sleep(0.01)
        answers = m.request_many([(GAP, 8, 0, 0), (GAP, 1, 0, 0)])
        assert [a.command for a in answers] == [GAP, GAP]
        if answers[0].value:
            seen += 1
            break
    assert seen and answers[1].value == 2000
    assert m.wait_position_reached(1, timeout=0.5) == 1


def test_suppressed_replies_do_not_shift_the_pairing():
    """GP255 = 1: "The reply in direct mode will be suppressed ... The reply will not be suppressed
    for GAP, GGP and GIO commands" (TMCM-6212 manual 5.1). The client knows it from its own SGP
    255 and reads each write with GGP 255 behind it: a write that succeeded silently answers status
    100, value 0; an error reply is paired with its own request (index 2 here, not 1); reads keep
    their replies (issue 34: "Replies suppressed by GP255 inside a batch do not shift the pairing")."""
    m = sim()
    assert m.request(SGP, 255, 0, 1).status == 100       # its own reply is suppressed already
    answers = m.request_many([(GAP, 4, 0, 0), (SAP, 4, 0, 99), (GGP, 66, 0, 0)])
    assert [(a.command, a.status) for a in answers] == [(GAP, 100), (SAP, 100), (GGP, 100)]
    assert answers[2].value == 1 and m.client.stray_replies == 0
    with pytest.raises(TmclStatusError) as info:
        m.request_many([(SAP, 4, 0, 5), (SAP, 4, 1, 6), (SAP, 4, 0, -1), (GAP, 4, 1, 0)])
    assert info.value.index == 2 and info.value.status == 4
    assert info.value.answers[3].value == 6 and m.request(GAP, 4, 0).value == 5
    assert m.request(SGP, 255, 0, 0).status == 100       # replies again from here on
    assert m.request_many([(SAP, 4, 0, 7)])[0] == Reply(2, 1, 100, SAP, 7 * 0)


def test_timeout_in_the_middle_and_what_is_left():
    """No reply to the second request (the module suppresses it while this client does not know:
    another host set GP255): TmclTimeout names that request; the third reply was read past as a
    stray reply, and the next request gets its own reply after the fence."""
    vm = VirtualModule("TMCM-6212", address=1)
    vm.request(SGP, 255, 0, 1)
    m = Client(InProcessTransport(vm))
    with pytest.raises(TmclTimeout, match="SAP"):
        m.request_many([(GAP, 4, 0, 0), (SAP, 4, 0, 99), (GGP, 66, 0, 0)], timeout=0.2)
    assert m.stray_replies == 1
    assert m.request(GAP, 4, 0) == Reply(2, 1, 100, GAP, 99)


def test_timeout_stops_the_batch_and_late_replies_are_discarded():
    """Window 2 over a stream: a timeout on the second reply stops the batch (requests 3 and 4 are
    never sent); a late reply that arrives afterwards, before or while the fence is read, is
    never taken for the next request's reply."""
    r = Reply(2, 1, 100, GAP, 1).encode()
    fence = Reply(2, 1, 100, GGP, 1).encode()
    t = ScriptedTransport(r, b"", r, r)
    t.window = 2
    c = Client(t)
    with pytest.raises(TmclTimeout):
        c.request_many([(GAP, 1, 0, 0)] * 4, timeout=0.1)
    assert len(t.sent) == 2
    t.feed(Reply(2, 1, 100, GAP, 77).encode())  # the lost reply, late
    t.answers = [Reply(2, 1, 100, GAP, 78).encode() + fence, Reply(2, 1, 100, GAP, 3).encode()]
    assert c.request(GAP, 1, 0).value == 3
    assert c.stray_replies == 1


def test_window_groups_the_sends():
    """Window 3, seven requests: three are sent before the first reply is read, then three, then one."""
    class Counting(ScriptedTransport):
        def __init__(self):
            super().__init__()
            self.writes: list[int] = []

        def send_many(self, frames):
            self.writes.append(len(frames))
            for f in frames:
                self.sent.append(f)
                self.rx += Reply(2, 1, 100, f[1], f[3]).encode()

    t = Counting()
    t.window = 3
    answers = Client(t).request_many([(GAP, 1, m, 0) for m in range(7)])
    assert t.writes == [3, 3, 1]
    assert [a.value for a in answers] == list(range(7))


def test_two_modules_in_process_and_address():
    """`address=` sends the batch to another module of the bus (sim://A@1,B@2)."""
    c = open_bus("sim://TMCM-6212@1,PD86-1180@2")
    assert [a.module_address for a in c.request_many([(GGP, 66, 0, 0)] * 2, address=2)] == [2, 2]
    assert c.request_many([(GGP, 66, 0, 0)])[0].value == 1


def test_one_time_sync_per_batch_in_process():
    """In process, the clock syncs once per batch, not once per request."""
    t = InProcessTransport(VirtualModule("TMCM-6212", address=1), clock="real")
    calls = []
    sync = t.clock.sync
    t.clock.sync = lambda transport: (calls.append(1), sync(transport))  # type: ignore[method-assign]
    Client(t).request_many([(GAP, 1, m, 0) for m in range(6)])
    assert len(calls) == 1


def test_over_tcp_matches_in_process(tcp_url):
    """The served module answers a window of frames in flight with the same replies."""
    m = opentmcl.connect(tcp_url, profile="TMCM-6212")
    try:
        assert m.client.transport.window == 8
        reads = [(SGP, i, 2, i * 10) for i in range(20)] + [(GGP, i, 2, 0) for i in range(20)]
        answers = m.request_many(reads)
        assert [a.value for a in answers[20:]] == [i * 10 for i in range(20)]
        with pytest.raises(TmclStatusError) as info:
            m.request_many([(GGP, 1, 2, 0), (GAP, 1, 6, 0), (GGP, 2, 2, 0)])
        assert info.value.index == 1 and info.value.answers[2].value == 20
        assert m.request_many([(136, 0, 0, 0)])[0].text == "6212V105"
    finally:
        m.close()


def test_module_request_many_is_the_clients():
    m = sim()
    assert m.request_many([(GGP, 66, 0, 0)], timeout=1.0) == m.client.request_many([(GGP, 66, 0, 0)])


class Jump(Clock):
    """A clock whose every sync lets one virtual second pass (events land in the buffer then)."""

    def sync(self, transport):
        transport.advance(1.0)


class Watched(InProcessTransport):
    """Overrides send: the client takes the usual path (the reference for the lean one)."""

    def send(self, data):
        super().send(data)


@pytest.mark.parametrize("transport", [InProcessTransport, Watched])
@pytest.mark.parametrize("many", [False, True])
def test_an_event_from_the_clock_sync_is_taken_before_the_reply(transport, many):
    """The 138 event produced while a request's sync lets time pass (manual 3.6.35) is registered
    by that request, on the lean path as on the usual one."""
    t = transport(VirtualModule("TMCM-6212", address=1), clock=Jump())
    c = Client(t)
    c.request(138, 0, 0, 1)
    c.request(MVP, 0, 0, 100)
    answer = c.request_many([(GAP, 1, 0, 0)])[0] if many else c.request(GAP, 1, 0)
    assert answer.value == 100
    assert c.pending_events() == 1
