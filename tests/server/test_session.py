"""SerialSession: telegram pause (GP75) and byte pacing at the RS485 baud rate (GP65)."""
import pytest

from opentmcl import VirtualModule
from opentmcl.server.bus import ModuleBus
from opentmcl.server.session import SerialSession, byte_time

from .helpers import GGP_66, reply, request


class FakeTime:
    """A clock whose sleep() just moves time forward, recording each sleep."""

    def __init__(self):
        self.t = 0.0
        self.sleeps = []

    def clock(self):
        return self.t

    def sleep(self, s):
        self.sleeps.append(s)
        self.t += s


def make(pace=False, interface="serial"):
    ft = FakeTime()
    writes = []
    bus = ModuleBus([VirtualModule("TMCM-6212", address=1)], clock=ft.clock)
    session = SerialSession(bus, lambda b: writes.append((ft.t, bytes(b))), gap=0.1,
                            pace_bytes=pace, clock=ft.clock, sleep=ft.sleep, interface=interface)
    return ft, writes, session


def test_reply_is_written_without_pause_by_default():
    """Manual 5.1 GP75 (default 0): no pause before the reply of GGP 66, 0 (3.6.8 example)."""
    ft, writes, session = make()
    assert session.receive(GGP_66) == 1
    assert writes == [(0.0, reply(2, 1, 100, 10, 1))]
    assert ft.sleeps == []


def test_telegram_pause_gp75_delays_the_reply():
    """Manual 5.1 GP75 "Pause time before the reply via RS485 is sent" (units: ms,
    docs/assumptions.md); PD86-1180 manual 7.4 suggests SGP 75, 0, 15."""
    ft, writes, session = make()
    session.receive(request(1, 9, 75, 0, 15))  # SGP 75, 0, 15
    writes.clear()
    ft.sleeps.clear()
    start = ft.t
    session.receive(GGP_66)
    assert ft.sleeps == [pytest.approx(0.015)]
    assert writes == [(pytest.approx(start + 0.015), reply(2, 1, 100, 10, 1))]


@pytest.mark.parametrize(("interface", "pause"), [("rs485", 0.015), ("rs232", 0.015), ("usb", None)])
def test_telegram_pause_only_on_rs485_and_rs232(interface, pause):
    """TMCM-6212 5.1 GP75 "Pause time before the reply via RS485 is sent"; PD86-1180 6.1 "Pause
    time before the reply via RS232 or RS485 is sent. For RS232 set to 0": a link that stands for
    USB sends the reply at once whatever GP75 holds."""
    ft, writes, session = make(interface=interface)
    session.receive(request(1, 9, 75, 0, 15))  # SGP 75, 0, 15
    writes.clear()
    ft.sleeps.clear()
    session.receive(GGP_66)
    assert ft.sleeps == ([] if pause is None else [pytest.approx(pause)])
    assert writes == [(pytest.approx(ft.t), reply(2, 1, 100, 10, 1))]


def test_byte_pacing_follows_gp65_baud_rate():
    """Manual 5.1 GP65: 0 = 9600 baud (default), 7 = 115200. With pacing the nine request bytes
    take ten bit times each (8N1) before the module sees the request, and the nine reply bytes
    leave one every ten bit times: a round trip of 18 byte times."""
    ft, writes, session = make(pace=True)
    session.receive(GGP_66)
    assert b"".join(w for _, w in writes) == reply(2, 1, 100, 10, 1)
    assert len(writes) == 9
    assert writes[0][0] == pytest.approx(10 * byte_time(9600))    # the request's nine bytes, then one
    assert ft.t == pytest.approx(18 * byte_time(9600))
    assert byte_time(9600) == pytest.approx(10 / 9600)
    session.receive(request(1, 9, 65, 0, 7))  # SGP 65, 0, 7 -> 115200 baud
    writes.clear()
    start = ft.t
    session.receive(GGP_66)
    assert ft.t - start == pytest.approx(18 * 10 / 115200)


def test_paced_request_reaches_the_module_after_its_last_byte():
    """A request split over two reads (4 + 5 bytes, read at once) reaches the module when its
    ninth byte has crossed the 9600-baud line: 9 byte times after the first read."""
    ft, writes, session = make(pace=True)
    assert session.receive(GGP_66[:4]) == 0
    assert ft.t == pytest.approx(4 * byte_time(9600)) and writes == []
    assert session.receive(GGP_66[4:]) == 1
    assert writes[0][0] == pytest.approx(10 * byte_time(9600))


def test_paced_telegram_pause_counts_from_the_last_request_byte():
    """Manual 5.1 GP75 "Pause time before the reply via RS485 is sent": the bus turn-around
    starts when the request has arrived, so with pacing the first reply byte is through 9 byte
    times + 15 ms + its own byte time after the request started."""
    ft, writes, session = make(pace=True)
    session.receive(request(1, 9, 75, 0, 15))  # SGP 75, 0, 15
    writes.clear()
    start = ft.t
    session.receive(GGP_66)
    assert writes[0][0] - start == pytest.approx(10 * byte_time(9600) + 0.015)
    assert ft.t - start == pytest.approx(18 * byte_time(9600) + 0.015)


def test_paced_ascii_line_arrives_at_the_baud_rate():
    """PD28-1021 manual 3.4 ASCII mode: a command line `AGAP 1, 0<CR>` (10 bytes) crosses the
    9600-baud line before the module echoes and answers; the echo and the reply text are
    paced too (10 bit times per byte)."""
    ft = FakeTime()
    writes = []
    vm = VirtualModule("PD28-1021", address=1)
    assert vm.request(139).status == 100
    bus = ModuleBus([vm], clock=ft.clock)
    session = SerialSession(bus, lambda b: writes.append((ft.t, bytes(b))), gap=0.1,
                            pace_bytes=True, clock=ft.clock, sleep=ft.sleep)
    line = b"AGAP 1, 0\r"
    session.receive(line)
    out = b"".join(w for _, w in writes)
    assert out.endswith(b"\r") and b"BA 100" in out
    assert writes[0][0] == pytest.approx((len(line) + 1) * byte_time(9600))
    assert ft.t == pytest.approx((len(line) + len(out)) * byte_time(9600))


def test_paced_bus_reads_at_the_slowest_modules_rate():
    """Two modules on one line, one at 9600 and one at 115200 baud (GP65 0 / 7): the request is
    paced at 9600 (docs/assumptions.md), the 115200 module's reply at its own rate."""
    ft = FakeTime()
    writes = []
    fast = VirtualModule("TMCM-6212", address=2)
    assert fast.request(9, 65, 0, 7).status == 100
    bus = ModuleBus([VirtualModule("TMCM-6212", address=1), fast], clock=ft.clock)
    session = SerialSession(bus, lambda b: writes.append((ft.t, bytes(b))), gap=0.1,
                            pace_bytes=True, clock=ft.clock, sleep=ft.sleep, interface="rs485")
    session.receive(request(2, 10, 66, 0))
    assert b"".join(w for _, w in writes) == reply(2, 2, 100, 10, 2)
    assert writes[0][0] == pytest.approx(9 * byte_time(9600) + byte_time(115200))
    assert ft.t == pytest.approx(9 * byte_time(9600) + 9 * byte_time(115200))


def test_frames_for_other_addresses_produce_no_bytes():
    """Manual 5.1 GP66: a module answers only its own address; others are ignored."""
    _, writes, session = make()
    session.receive(request(4, 10, 66, 0))
    assert writes == []


def test_time_spent_answering_is_not_silence_on_the_line():
    """Manual 3.1: a request is nine bytes with no start marker, so frames are found by
    counting and a partial frame is dropped only after an inter-byte gap (docs/assumptions.md).
    Time the session itself spends answering (here: a slow write of the GGP 66 reply, manual
    3.6.8 example) is not silence: the second frame, split across two reads, still completes."""
    ft = FakeTime()
    writes = []

    def slow_write(data):
        writes.append(bytes(data))
        ft.t += 1.0  # ten times the gap, e.g. a blocked socket or a loaded machine

    bus = ModuleBus([VirtualModule("TMCM-6212", address=1)], clock=ft.clock)
    session = SerialSession(bus, slow_write, gap=0.1, clock=ft.clock, sleep=ft.sleep)
    assert session.receive(GGP_66 + GGP_66[:4]) == 1
    assert session.receive(GGP_66[4:]) == 1          # arrived while the reply was written
    assert writes == [reply(2, 1, 100, 10, 1)] * 2
    ft.t += 0.5                                      # real silence still resynchronises
    assert session.receive(GGP_66[:4]) == 0
    ft.t += 0.5
    assert session.receive(GGP_66) == 1              # the partial frame was dropped first
    assert session.framer.dropped == 4
    assert writes[-1] == reply(2, 1, 100, 10, 1)


def test_serial_traffic_feeds_the_serial_heartbeat_gp68_only():
    """Manual 5.1 GP68 "Serial heartbeat for RS485 interface and USB interface. If this time limit
    is up and no further command is received by the module the motor will be stopped" and GP82,
    the separate "Heartbeat for CAN interface": frames through a serial session (pty, TCP) keep the
    serial heartbeat alive, not the CAN one."""
    ft, writes, session = make()

    def speed_after_talking(seconds):
        for _ in range(round(seconds / 0.15)):             # the serial host talks every 0.15 s
            ft.t += 0.15
            session.receive(request(1, 6, 3, 0))
        writes.clear()
        session.receive(request(1, 6, 3, 0))               # GAP 3: actual speed
        return writes[0][1][4:8]

    session.receive(request(1, 9, 68, 0, 200))             # SGP 68, 0, 200 (ms)
    session.receive(request(1, 1, 0, 0, 1000))             # ROR 0, 1000
    assert speed_after_talking(0.6) != bytes(4)            # still turning after 3 heartbeats
    ft.t += 0.5                                            # the serial host falls silent
    assert speed_after_talking(0) == bytes(4)              # stopped
    session.receive(request(1, 9, 68, 0, 0))               # serial heartbeat off,
    session.receive(request(1, 9, 82, 0, 200))             # CAN heartbeat 200 ms
    session.receive(request(1, 1, 0, 0, 1000))
    assert speed_after_talking(0.6) == bytes(4)            # serial traffic is no CAN traffic
