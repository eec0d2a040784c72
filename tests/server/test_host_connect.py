"""The host library's connect() against every served endpoint: tcp, serial (pty), can."""
import sys

import pytest

from opentmcl import VirtualModule
from opentmcl.host import connect
from opentmcl.server import CanServer, PtyServer, Server, TcpServer

from .helpers import unique_channel


@pytest.fixture
def server():
    channel = unique_channel()
    srv = Server([VirtualModule("TMCM-6212", address=1)])
    tcp = srv.add(TcpServer(srv.bus, "127.0.0.1", 0))
    pty = srv.add(PtyServer(srv.bus)) if sys.platform != "win32" else None
    srv.add(CanServer(srv.bus, "virtual", channel))
    srv.start()
    urls = {"tcp": tcp.url, "can": f"can://virtual/{channel}?id=1"}
    if pty is not None:
        urls["serial"] = f"serial://{pty.path}?baud=9600"
    try:
        yield srv, urls
    finally:
        srv.stop()


@pytest.mark.parametrize("kind", ["tcp", "serial", "can"])
def test_connect_reads_version_and_moves(server, kind):
    """Command 136 type 0 (manual 3.6.36), GGP 66 (3.6.8) and an MVP with the 138 event
    (3.6.4, 3.6.35) through connect(url) on each endpoint, in real time."""
    srv, urls = server
    if kind not in urls:
        pytest.skip("pseudo-terminals need POSIX")
    m = connect(urls[kind])
    try:
        assert m.firmware_version() == srv.modules[0].profile.firmware_version
        assert m.get_global(66) == 1
        m.axes[0].set("max_positioning_speed", 20000)
        m.axes[0].move_to(1500, wait=True, timeout=10)
        assert m.axes[0].position == 1500
    finally:
        m.close()


def test_serial_url_with_a_pyserial_opentmcl_port(capsys, monkeypatch):
    """The serial transport accepts any pyserial port name, including the opentmcl:// URL handler,
    without the caller importing opentmcl.urlhandler first (docs/endpoints.md): the manual 3.6.8
    GGP 66 answers the address the URL gave the module."""
    import serial

    from opentmcl.cli import main

    monkeypatch.setattr(serial, "protocol_handler_packages",
                        [p for p in serial.protocol_handler_packages if p != "opentmcl.urlhandler"])
    assert main(["send", "GGP 66, 0", "--plain", "--to", "serial://?port=opentmcl://TMCM-6212@3", "--address", "3"]) == 0
    assert capsys.readouterr().out == "3\n"


@pytest.mark.parametrize("timeout", ["nan", "inf", "-1"])
def test_send_rejects_a_timeout_that_is_not_a_positive_number(capsys, timeout):
    """A reply time-out must be a positive, finite number of seconds: one-line error, status 2."""
    from opentmcl.cli import main

    assert main(["send", "GAP 1, 0", "--to", "sim://TMCM-6212", "--timeout", timeout]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "--timeout" in err


@pytest.mark.parametrize("kind", ["tcp", "serial"])
def test_several_modules_on_one_served_bus(kind):
    """Several modules on one RS-485 line (TMCM-6212 manual 3: "more than two nodes connected to
    a single bus"), reached through one host connection: each answers the manual 3.6.8 GGP 66 with
    its own address and command 136 with its own version string; a move on one leaves the other."""
    from opentmcl.host import open_bus

    srv = Server([VirtualModule("TMCM-6212", address=1), VirtualModule("PD86-1180", address=2)])
    tcp = srv.add(TcpServer(srv.bus, "127.0.0.1", 0))
    pty = srv.add(PtyServer(srv.bus)) if sys.platform != "win32" else None
    if kind == "serial" and pty is None:
        pytest.skip("pseudo-terminals need POSIX")
    srv.start()
    try:
        with open_bus(tcp.url if kind == "tcp" else f"serial://{pty.path}") as bus:
            first, second = bus.module(1), bus.module(2)
            assert first.get_global(66) == 1 and second.get_global(66) == 2
            assert first.firmware_version() == srv.modules[0].profile.firmware_version
            assert second.firmware_version() == srv.modules[1].profile.firmware_version
            second.axes[0].set("max_positioning_speed", 1000)
            second.axes[0].move_to(800, wait=True, timeout=10)
            assert second.axes[0].position == 800 and first.axes[0].position == 0
    finally:
        srv.stop()


@pytest.mark.parametrize("url", ["tcp://[::1", "tcp://[::1:2323", "serial://[x"])
def test_malformed_url_is_a_connection_error(url):
    """Bad input gives a typed error (docs/architecture.md "Errors"), not a bare ValueError."""
    from opentmcl.host.errors import TmclConnectionError

    with pytest.raises(TmclConnectionError, match="bad module URL"):
        connect(url)


def test_send_refuses_an_address_on_can(capsys):
    """Manual 3.1: on CAN "leave out the address byte"; the CAN ID (GP71) selects the module, so
    `opentmcl send --address` cannot choose one there: a one-line error instead of silently talking
    to the module of the URL's CAN ID."""
    from opentmcl.cli import main

    assert main(["send", "GGP 66, 0", "--to", f"can://virtual/{unique_channel()}?id=1", "--address", "3"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "CAN ID" in err
