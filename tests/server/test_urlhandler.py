"""pyserial URL handler: serial.serial_for_url("opentmcl://TMCM-6212")."""
import pytest
import serial

import opentmcl.urlhandler  # noqa: F401  (registers the opentmcl:// scheme)
from opentmcl.urlhandler.protocol_opentmcl import parse_url

from .helpers import GGP_66, REQ_EVENT_0_2, is_ok, reply, request


def test_registration_is_idempotent():
    opentmcl.urlhandler.register()
    opentmcl.urlhandler.register()
    assert serial.protocol_handler_packages.count("opentmcl.urlhandler") == 1


def test_manual_example_through_serial_for_url():
    """Manual 3.6.8 GGP 66, 0 through any pyserial-based code path."""
    with serial.serial_for_url("opentmcl://TMCM-6212", timeout=2) as port:
        port.write(GGP_66)
        assert port.read(9) == reply(2, 1, 100, 10, 1)
        assert port.in_waiting == 0


def test_several_modules_on_one_port():
    """Two modules on one bus, each answering its GP66 address (manual 5.1)."""
    with serial.serial_for_url("opentmcl://TMCM-6212@1,TMCM-6212@5", timeout=2) as port:
        port.write(request(5, 10, 66, 0))
        assert port.read(9) == reply(2, 5, 100, 10, 5)
        port.write(GGP_66)
        assert port.read(9) == reply(2, 1, 100, 10, 1)
        assert len(port.modules) == 2


def test_read_times_out_with_fewer_bytes():
    """pyserial semantics: read() returns what arrived when the timeout expires."""
    with serial.serial_for_url("opentmcl://TMCM-6212?interface=rs485", timeout=0.1) as port:
        port.write(request(9, 10, 66, 0))  # nobody at address 9 (on RS-485; USB would answer)
        assert port.read(9) == b""


def test_modules_run_in_real_time_and_send_events():
    """Manual 3.6.35: after 138 and MVP the "target position reached" reply arrives once
    the motor is there; time passes with the wall clock."""
    with serial.serial_for_url("opentmcl://TMCM-6212", timeout=10) as port:
        port.write(REQ_EVENT_0_2)
        assert port.read(9) == reply(2, 1, 100, 138, 5)
        port.write(request(1, 4, 0, 0, 100))  # MVP ABS, 0, 100
        assert is_ok(port.read(9), 2, 1, 4)  # MVP reply value: "don't care" (3.6.4)
        assert port.read(9) == reply(2, 1, 128, 138, 1)


class FakeTime:
    """Stands in for the `time` module of the port class: sleep() moves the clock forward."""

    def __init__(self):
        self.t = 1000.0

    def monotonic(self):
        return self.t

    def sleep(self, seconds):
        self.t += seconds


@pytest.fixture
def fake_time(monkeypatch):
    from opentmcl.urlhandler import protocol_opentmcl

    ft = FakeTime()
    monkeypatch.setattr(protocol_opentmcl, "time", ft)
    return ft


def test_telegram_pause_delays_readability(fake_time):
    """Manual 5.1 GP75 "Pause time before the reply via RS485 is sent" (ms, docs/assumptions.md):
    the reply to the 3.6.8 GGP 66 example becomes readable only when the pause is over (a port
    that stands for an RS-485 line)."""
    with serial.serial_for_url("opentmcl://TMCM-6212?interface=rs485", timeout=2) as port:
        port.write(request(1, 9, 75, 0, 200))  # SGP 75, 0, 200
        port.read(9)
        port.write(GGP_66)
        assert port.in_waiting == 0
        fake_time.t += 0.199
        assert port.in_waiting == 0
        fake_time.t += 0.002
        assert port.in_waiting == 9
        assert port.read(9) == reply(2, 1, 100, 10, 1)


def test_no_telegram_pause_on_usb(fake_time):
    """Manual 5.1 GP75 "Pause time before the reply via RS485 is sent" (PD86-1180 6.1: "via RS232
    or RS485"): a one-module port stands for the module's USB port, where GP75 = 200 delays nothing."""
    with serial.serial_for_url("opentmcl://TMCM-6212", timeout=2) as port:
        port.write(request(1, 9, 75, 0, 200))  # SGP 75, 0, 200
        port.read(9)
        port.write(GGP_66)
        assert port.in_waiting == 9
        assert port.read(9) == reply(2, 1, 100, 10, 1)


def test_a_paced_port_is_a_serial_line():
    """Manual 5.1 GP65 is the "RS485 baud rate": ?pace=1 paces at it, so a paced port to one module
    stands for an RS-485 line (frames for other addresses get no reply) and ?interface=usb, which
    has no baud rate, is refused with it."""
    with serial.serial_for_url("opentmcl://TMCM-6212?pace=1", timeout=0.5) as port:
        port.write(request(0, 10, 66, 0))
        assert port.read(9) == b""
        port.write(GGP_66)
        assert port.read(9) == reply(2, 1, 100, 10, 1)
    with pytest.raises(serial.SerialException, match="baud rate"):
        serial.serial_for_url("opentmcl://TMCM-6212?pace=1&interface=usb")


@pytest.mark.parametrize(("gp65", "baud"), [(0, 9600), (7, 115200)])
def test_pace_sends_reply_bytes_at_the_gp65_baud_rate(fake_time, gp65, baud):
    """Manual 5.1 GP65 "RS485 baud rate" table: with ?pace=1 the request crosses the line first
    (nine bytes), then the reply bytes become readable one per ten bit times (8N1) at that rate;
    the 3.6.8 GGP 66 reply (9 bytes) as the probe."""
    byte = 10 / baud
    with serial.serial_for_url("opentmcl://TMCM-6212?pace=1", timeout=2) as port:
        port.write(request(1, 9, 65, 0, gp65))  # SGP 65, 0, gp65
        fake_time.t += 1.0
        port.read(9)
        port.write(GGP_66)
        assert port.in_waiting == 0
        fake_time.t += 8.5 * byte
        assert port.in_waiting == 0 and port.out_waiting == 1      # the request's last byte
        fake_time.t += 1 * byte
        assert port.in_waiting == 0 and port.out_waiting == 0
        fake_time.t += 4 * byte
        assert port.in_waiting == 4
        fake_time.t += 5 * byte
        assert port.read(9) == reply(2, 1, 100, 10, 1)


def test_eeprom_file_is_flushed_on_close(tmp_path):
    """Manual 5.1: bank-0 parameters 64..127 are stored automatically by SGP; the EEPROM
    file keeps them for the next power-up."""
    url = f"opentmcl://TMCM-6212?eeprom={tmp_path / 'ee.json'}"
    with serial.serial_for_url(url, timeout=2) as port:
        port.write(request(1, 9, 75, 0, 7))  # SGP 75, 0, 7
        assert is_ok(port.read(9), 2, 1, 9)  # SGP reply value: "don't care" (3.6.7)
    with serial.serial_for_url(url, timeout=2) as port:
        port.write(request(1, 10, 75, 0))
        assert port.read(9) == reply(2, 1, 100, 10, 7)


@pytest.mark.parametrize("url", ["opentmcl://", "opentmcl://NO-SUCH-MODULE", "opentmcl://TMCM-6212@x",
                                 "opentmcl://TMCM-6212@1,TMCM-6212@1", "opentmcl://TMCM-6212?color=red",
                                 "opentmcl://TMCM-6212@300", "opentmcl://TMCM-6212?gap=nan",
                                 "opentmcl://TMCM-6212?gap=inf", "opentmcl://TMCM-6212?gap=0"])
def test_bad_urls_raise_serial_exception(url):
    with pytest.raises(serial.SerialException):
        serial.serial_for_url(url)


def test_parse_url():
    opts = parse_url("opentmcl://TMCM-6212@3,TMCM-6212?gap=0.5&pace=1")
    assert opts["modules"] == [("TMCM-6212", 3), ("TMCM-6212", 2)]
    assert opts["gap"] == 0.5 and opts["pace"] is True


def test_closed_port_raises():
    port = serial.serial_for_url("opentmcl://TMCM-6212")
    port.close()
    with pytest.raises(serial.PortNotOpenError):
        port.write(GGP_66)
    with pytest.raises(serial.PortNotOpenError):
        port.read(1)


def test_one_module_port_is_usb_and_ignores_the_address_byte():
    """An `opentmcl://` port to one module stands for its USB port (docs/endpoints.md): a frame
    to address 0 (odemis' driver discovers modules so) gets the module's reply from address 1."""
    with serial.serial_for_url("opentmcl://TMCM-6212", timeout=2) as port:
        port.write(request(0, 10, 66, 0))
        assert port.read(9) == reply(2, 1, 100, 10, 1)


@pytest.mark.parametrize(("url", "says"), [("opentmcl://TMCM-6212?interface=can", "usb, rs485, rs232"),
                                           ("opentmcl://TMCM-6212@1,TMCM-6212@2?interface=usb", "one module"),
                                           ("opentmcl://PD28-1021?interface=usb", "no USB port")])
def test_bad_interface_in_the_url_is_refused(url, says):
    """usb carries one module, of a module that has USB (not the PD28-1021: "RS485 interface" on
    its manual's title page); only usb, rs485 and rs232 are serial interfaces; rs485 filters."""
    with pytest.raises(serial.SerialException, match=says):
        serial.serial_for_url(url)
    with serial.serial_for_url("opentmcl://TMCM-6212@1,TMCM-6212@2?interface=rs485", timeout=0.2) as port:
        port.write(request(0, 10, 66, 0))
        assert port.read(9) == b""


def test_paced_port_round_trip_takes_the_wire_time_of_both_directions():
    """TMCM-6212 manual 5.1 GP65 0 = 9600 baud: with `pace=1` the written request reaches the
    module only after its nine bytes crossed the line, the reply takes nine byte times too, so a
    round trip takes at least 18 x 10 / 9600 s (lower bound only); `flush` waits until the
    written bytes are through."""
    import time

    with serial.serial_for_url("opentmcl://TMCM-6212?pace=1", timeout=5) as port:
        for _ in range(5):
            start = time.monotonic()
            port.write(GGP_66)
            assert port.read(9) == reply(2, 1, 100, 10, 1)
            assert time.monotonic() - start >= 18 * 10 / 9600
        port.write(GGP_66)
        port.flush()
        assert port.out_waiting == 0
        assert port.read(9) == reply(2, 1, 100, 10, 1)


def test_unread_replies_are_bounded_like_a_terminal_buffer():
    """Issue 11 "per-connection buffers stay bounded", for the in-process port: 10000 manual 3.6.8
    GGP 66 requests written without reading leave at most RX_BUFFER (4096) reply bytes waiting, as
    a tty's input buffer would; the rest is dropped and counted, and after the host flushes its
    input the next request is answered."""
    from opentmcl.urlhandler.protocol_opentmcl import RX_BUFFER

    port = serial.serial_for_url("opentmcl://TMCM-6212", timeout=1)
    try:
        for _ in range(100):
            port.write(GGP_66 * 100)
        assert port.in_waiting == RX_BUFFER == 4096
        assert port.dropped == 10000 * 9 - 4096
        assert port.read(9) == reply(2, 1, 100, 10, 1)  # the oldest replies are kept whole
        port.reset_input_buffer()
        port.write(GGP_66)
        assert port.read(9) == reply(2, 1, 100, 10, 1)
    finally:
        port.close()
