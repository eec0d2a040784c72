"""ModuleBus: several modules on one bus, CAN addressing, real-time pacing, events."""

from opentmcl import VirtualModule
from opentmcl.protocol.frame import Reply
from opentmcl.server.bus import ModuleBus

from .helpers import GGP_66, REQ_EVENT_0_2, reply, request


class FakeClock:
    def __init__(self):
        self.t = 100.0

    def __call__(self):
        return self.t


class Recorder:
    interface = "serial"

    def __init__(self):
        self.got = []

    def deliver(self, vm, data):
        self.got.append(data)


def test_manual_ggp_66_example_gets_its_reply():
    """Manual 3.6.8 example GGP 66, 0 (01 0A 42 00 00000000 4D) to a module at address 1:
    reply 3.2 with host address 2, module 1, status 100, command 10, value 1."""
    bus = ModuleBus([VirtualModule("TMCM-6212", address=1)])
    [(vm, got)] = bus.request(GGP_66)
    assert got == reply(2, 1, 100, 10, 1)
    assert got.hex() == "0201640a0000000172"


def test_two_modules_on_one_bus_each_answer_their_address():
    """Manual 5.1 GP66 "Module (target) address for RS485": on a shared bus only the
    addressed module answers; a frame for an absent address is ignored silently."""
    a, b = VirtualModule("TMCM-6212", address=1), VirtualModule("TMCM-6212", address=2)
    bus = ModuleBus([a, b])
    [(vm, got)] = bus.request(request(2, 10, 66, 0))
    assert vm is b and got == reply(2, 2, 100, 10, 2)
    assert bus.request(request(7, 10, 66, 0)) == []


def test_secondary_address_gp87_also_answers():
    """Manual 5.1 GP87 "Second module (target) address for RS485": a module answers it."""
    bus = ModuleBus([VirtualModule("TMCM-6212", address=1)])
    assert bus.request(request(9, 10, 66, 0)) == []
    [(_, ok)] = bus.request(request(1, 9, 87, 0, 9))  # SGP 87, 0, 9
    assert Reply.decode(ok).status == 100
    [(_, got)] = bus.request(request(9, 10, 66, 0))
    assert Reply.decode(got).status == 100 and Reply.decode(got).value == 1


def test_host_address_gp76_is_used_in_replies():
    """Manual 5.1 GP76 "Host address used in the reply telegrams sent back via RS485"."""
    bus = ModuleBus([VirtualModule("TMCM-6212", address=1)])
    bus.request(request(1, 9, 76, 0, 5))  # SGP 76, 0, 5
    [(_, got)] = bus.request(GGP_66)
    assert got == reply(5, 1, 100, 10, 1)


def test_reply_suppression_gp255_but_not_for_ggp():
    """Manual 5.1 GP255: "The reply in direct mode will be suppressed when this parameter
    is set to 1 ... The reply will not be suppressed for GAP, GGP and GIO commands."."""
    bus = ModuleBus([VirtualModule("TMCM-6212", address=1)])
    bus.request(request(1, 9, 255, 0, 1))  # SGP 255, 0, 1
    assert bus.request(request(1, 5, 4, 0, 1000)) == []  # SAP 4: suppressed
    [(_, got)] = bus.request(request(1, 6, 4, 0))  # GAP 4: still answered
    assert Reply.decode(got).value == 1000


def test_time_follows_the_clock():
    """docs/architecture.md "Time": in a server, virtual time is paced to the wall clock."""
    clock = FakeClock()
    vm = VirtualModule("TMCM-6212", address=1)
    bus = ModuleBus([vm], clock=clock)
    clock.t += 0.25
    bus.sync()
    assert abs(vm.time - 0.25) < 1e-6
    clock.t += 0.5
    bus.request(GGP_66)
    assert abs(vm.time - 0.75) < 1e-6


def test_position_reached_event_goes_to_the_channel_that_asked():
    """Manual 3.6.35: after command 138 and an MVP, an additional reply with status 128
    and the motor bit mask is sent when the motor has reached its target."""
    clock = FakeClock()
    vm = VirtualModule("TMCM-6212", address=1)
    bus = ModuleBus([vm], clock=clock)
    ch = Recorder()
    [(_, got)] = bus.request(REQ_EVENT_0_2, ch)
    assert got == reply(2, 1, 100, 138, 5)
    bus.request(request(1, 4, 0, 0, 2000), ch)  # MVP ABS, 0, 2000
    assert bus.poll() == []
    clock.t += 5.0
    events = bus.poll()
    assert [(c, e) for c, _, e in events] == [(ch, reply(2, 1, 128, 138, 1))]


def test_can_request_uses_gp71_and_replies_with_gp70():
    """Manual 3.1/3.2 notes and 5.1 GP70/GP71: on CAN the CAN ID is the module address
    (default 1), replies go out with the reply ID (default 2) and carry 7 bytes: module
    address, status, command, value (PD86-1180 manual 4.2)."""
    bus = ModuleBus([VirtualModule("TMCM-6212", address=1)])
    ggp = GGP_66[1:8]  # GGP 66, 0 without address and checksum
    [(_, reply_id, payload)] = bus.can_request(1, ggp)
    assert reply_id == 2
    assert payload == bytes([1, 100, 10, 0, 0, 0, 1])
    assert bus.can_request(5, ggp) == []
    # the eight-byte form with a trailing checksum is accepted too
    [(_, _, payload8)] = bus.can_request(1, GGP_66[1:])
    assert payload8 == payload


def test_can_secondary_id_gp83_and_reply_id_gp70_settable():
    """Manual 5.1 GP83 "Second CAN ID for the module. Switched off when set to zero" and
    GP70 "The CAN ID for replies from the board"."""
    bus = ModuleBus([VirtualModule("TMCM-6212", address=1)])
    assert bus.can_request(0, GGP_66[1:8]) == []  # GP83 = 0 is off, not ID 0
    bus.can_request(1, bytes([9, 83, 0, 0, 0, 0, 0x55]))  # SGP 83, 0, 0x55
    bus.can_request(1, bytes([9, 70, 0, 0, 0, 0x01, 0x23]))  # SGP 70, 0, 0x123
    [(_, reply_id, payload)] = bus.can_request(0x55, GGP_66[1:8])
    assert reply_id == 0x123 and payload == bytes([1, 100, 10, 0, 0, 0, 1])


def test_can_version_string_eight_byte_form():
    """PD86-1180 manual, command 136 type 0: "just send this command in an eight byte frame
    instead of a seven byte frame. Then, eight bytes will be sent back"."""
    vm = VirtualModule("TMCM-6212", address=1)
    bus = ModuleBus([vm])
    version = vm.profile.firmware_version.encode()
    [(_, _, long_)] = bus.can_request(1, bytes([136, 0, 0, 0, 0, 0, 0, 0]))
    [(_, _, short)] = bus.can_request(1, bytes([136, 0, 0, 0, 0, 0, 0]))
    assert long_ == version and short == version[:7]


def test_can_wrong_length_is_ignored():
    """Manual 3.1 note: a CAN request is the 7 bytes without address and checksum."""
    bus = ModuleBus([VirtualModule("TMCM-6212", address=1)])
    assert bus.can_request(1, b"") == []
    assert bus.can_request(1, bytes(6)) == []


def test_serial_heartbeat_gp68_stops_motors_when_host_falls_silent():
    """Manual 5.1 GP68 "Serial heartbeat ... If this time limit is up and no further command
    is received by the module the motor will be stopped" (PD86-1180 manual: unit ms)."""
    clock = FakeClock()
    bus = ModuleBus([VirtualModule("TMCM-6212", address=1)], clock=clock)
    bus.request(request(1, 9, 68, 0, 200))  # SGP 68, 0, 200
    bus.request(request(1, 1, 0, 0, 1000))  # ROR 0, 1000
    clock.t += 0.15
    [(_, v1)] = bus.request(request(1, 6, 3, 0))  # GAP 3: actual speed, host still talking
    assert Reply.decode(v1).value != 0
    clock.t += 0.5  # silence longer than the heartbeat
    bus.sync()
    [(_, v2)] = bus.request(request(1, 6, 3, 0))
    assert Reply.decode(v2).value == 0


def test_can_heartbeat_gp82_applies_to_can_traffic():
    """Manual 5.1 GP82 "Heartbeat for CAN interface. If this time limit is up and no further
    command is received the motor will be stopped". The CAN endpoint passes interface="can",
    so CAN requests feed the CAN heartbeat and serial traffic does not."""
    clock = FakeClock()
    bus = ModuleBus([VirtualModule("TMCM-6212", address=1)], clock=clock)
    bus.can_request(1, bytes([9, 82, 0, 0, 0, 0, 200]))  # SGP 82, 0, 200
    bus.can_request(1, bytes([1, 0, 0, 0, 0, 0x03, 0xE8]))  # ROR 0, 1000
    for _ in range(4):  # the CAN host keeps talking every 0.15 s: still turning after 0.6 s
        clock.t += 0.15
        [(_, _, p1)] = bus.can_request(1, bytes([6, 3, 0, 0, 0, 0, 0]))  # GAP 3
        assert p1[3:7] != bytes(4)
    for _ in range(5):  # only serial traffic for 0.5 s: the CAN host has fallen silent
        clock.t += 0.1
        bus.request(request(1, 6, 3, 0))
    [(_, _, p2)] = bus.can_request(1, bytes([6, 3, 0, 0, 0, 0, 0]))
    assert p2[3:7] == bytes(4)
