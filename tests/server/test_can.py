"""CAN endpoint and CAN host transport through python-can (virtual bus, vcan0 if possible)."""
import os
import shutil
import subprocess
import sys
import time
import urllib.parse

import can
import pytest

from opentmcl import VirtualModule
from opentmcl.host.errors import TmclConnectionError, TmclTimeout
from opentmcl.host.transports.can import CanTransport, open_can
from opentmcl.server import CanServer, Server

from .helpers import GGP_66, unique_channel


@pytest.fixture
def can_server():
    channel = unique_channel()
    server = Server([VirtualModule("TMCM-6212", address=1), VirtualModule("TMCM-6212", address=2)])
    # the second module gets CAN ID 3 and reply ID 4 (manual 5.1 GP71/GP70)
    second = server.modules[1]
    second.handle(bytes([2, 9, 71, 0, 0, 0, 0, 3, (2 + 9 + 71 + 3) & 0xFF]))
    second.handle(bytes([2, 9, 70, 0, 0, 0, 0, 4, (2 + 9 + 70 + 4) & 0xFF]))
    server.add(CanServer(server.bus, "virtual", channel))
    server.start()
    host = can.Bus(interface="virtual", channel=channel)
    try:
        yield server, host, channel
    finally:
        host.shutdown()
        server.stop()


def exchange(host, can_id, data, timeout=5.0):
    host.send(can.Message(arbitration_id=can_id, data=data, is_extended_id=False))
    return host.recv(timeout)


def test_request_on_gp71_reply_on_gp70(can_server):
    """Manual 3.1 note (CAN: no address byte, no checksum; the CAN ID is the address),
    5.1 GP71 "CAN ID" default 1, GP70 "CAN reply ID" default 2; reply 7 bytes (PD86-1180 4.2)."""
    _, host, _ = can_server
    msg = exchange(host, 1, GGP_66[1:8])  # GGP 66, 0
    assert msg.arbitration_id == 2 and not msg.is_extended_id
    assert bytes(msg.data) == bytes([1, 100, 10, 0, 0, 0, 1])


def test_second_module_on_the_same_can_bus(can_server):
    """Two modules on one bus: CAN ID 3 answers with reply ID 4."""
    _, host, _ = can_server
    msg = exchange(host, 3, GGP_66[1:8])
    assert msg.arbitration_id == 4 and bytes(msg.data) == bytes([2, 100, 10, 0, 0, 0, 2])


def test_eight_byte_request_with_checksum_is_accepted(can_server):
    """docs/sources.md "TMCL over CAN": public clients send 8 bytes (trailing checksum); modules
    accept both."""
    _, host, _ = can_server
    msg = exchange(host, 1, GGP_66[1:])
    assert bytes(msg.data) == bytes([1, 100, 10, 0, 0, 0, 1])


def test_version_string_eight_byte_form(can_server):
    """PD86-1180 manual, command 136 type 0 in an eight byte frame: eight bytes back."""
    server, host, _ = can_server
    msg = exchange(host, 1, bytes([136, 0, 0, 0, 0, 0, 0, 0]))
    assert bytes(msg.data) == server.modules[0].profile.firmware_version.encode()


def test_unknown_ids_and_odd_frames_are_ignored(can_server):
    """Frames for other IDs, extended IDs, remote frames and short frames get no reply;
    the next well-formed request is answered."""
    _, host, _ = can_server
    host.send(can.Message(arbitration_id=9, data=GGP_66[1:8], is_extended_id=False))
    host.send(can.Message(arbitration_id=1, data=GGP_66[1:8], is_extended_id=True))
    host.send(can.Message(arbitration_id=1, is_remote_frame=True, dlc=7, is_extended_id=False))
    host.send(can.Message(arbitration_id=1, data=b"\x0a\x42", is_extended_id=False))
    assert host.recv(0.3) is None
    assert bytes(exchange(host, 1, GGP_66[1:8]).data) == bytes([1, 100, 10, 0, 0, 0, 1])


def test_can_transport_roundtrip(can_server):
    """Host transport can://virtual/CH?id=1: 8-byte request, 7-byte reply (transport.py)."""
    _, _, channel = can_server
    t = open_can(urllib.parse.urlsplit(f"can://virtual/{channel}?id=1&reply_id=2"))
    try:
        t.send(GGP_66[1:])
        assert t.recv(7, 5) == bytes([1, 100, 10, 0, 0, 0, 1])
        t.send(bytes([10, 66, 0, 0, 0, 0, 0]))
        assert t.recv(7, 5) == bytes([1, 100, 10, 0, 0, 0, 1])
    finally:
        t.close()
        t.close()


def test_a_can_connection_reaches_only_the_module_of_its_can_id(can_server):
    """Manual 3.1: on CAN the address byte is left out - the CAN ID (GP71) selects the module. A
    connection to CAN ID 3 (the second module, address 2) answers for that module; asking it for
    another address is a typed error before anything is sent, never a reply from the wrong module
    (manual 3.6.8 GGP 66 as the probe)."""
    from opentmcl.host import TmclAddressError, open_bus

    _, _, channel = can_server
    client = open_bus(f"can://virtual/{channel}?id=3&reply_id=4", address=2, timeout=5)
    try:
        assert client.module().request(10, 66, 0).value == 2
        with pytest.raises(TmclAddressError, match="CAN ID"):
            client.request(10, 66, 0, address=1)
        with pytest.raises(TmclAddressError):
            client.module(1)
        assert client.request(10, 66, 0).value == 2   # the connection still works
    finally:
        client.close()


def test_can_transport_timeout_and_errors(can_server):
    _, _, channel = can_server
    t = CanTransport("virtual", channel, can_id=77)
    try:
        t.send(GGP_66[1:8])
        with pytest.raises(TmclTimeout):
            t.recv(7, 0.2)
    finally:
        t.close()
    with pytest.raises(TmclConnectionError):
        t.send(GGP_66[1:8])
    with pytest.raises(TmclConnectionError):
        CanTransport("no-such-interface", "x")
    for url in ("can://virtual", "can:///x", "can://virtual/x?id=abc", "can://virtual/x?id=4096"):
        with pytest.raises(TmclConnectionError):
            open_can(urllib.parse.urlsplit(url))


@pytest.fixture
def vcan0():
    """A Linux vcan0 interface: used if present, created if we may, else the test skips."""
    if not sys.platform.startswith("linux"):
        pytest.skip("SocketCAN needs Linux")
    created = False
    if not os.path.exists("/sys/class/net/vcan0"):
        ip = shutil.which("ip")
        if ip is None or os.geteuid() != 0:
            pytest.skip("no vcan0 and no permission to create one")
        made = subprocess.run([ip, "link", "add", "dev", "vcan0", "type", "vcan"], capture_output=True, timeout=10)
        if made.returncode != 0:
            pytest.skip(f"cannot create vcan0: {made.stderr.decode(errors='replace').strip()}")
        created = True
        subprocess.run([ip, "link", "set", "up", "vcan0"], capture_output=True, timeout=10)
    try:
        yield "vcan0"
    finally:
        if created:
            subprocess.run(["ip", "link", "del", "vcan0"], capture_output=True, timeout=10)


def test_socketcan_vcan0(vcan0):
    """The same exchange on a Linux SocketCAN vcan0 (manual 3.1/3.2 notes, 5.1 GP70/GP71)."""
    server = Server([VirtualModule("TMCM-6212", address=1)])
    server.add(CanServer(server.bus, "socketcan", vcan0))
    server.start()
    try:
        time.sleep(0.05)
        t = CanTransport("socketcan", vcan0)
        try:
            t.send(GGP_66[1:])
            assert t.recv(7, 5) == bytes([1, 100, 10, 0, 0, 0, 1])
        finally:
            t.close()
    finally:
        server.stop()


def test_can_endpoint_feeds_the_can_heartbeat_gp82():
    """Manual 5.1 GP82 "Heartbeat for CAN interface. If this time limit is up and no further
    command is received the motor will be stopped": requests through the CAN endpoint restart
    it (the endpoint hands them over as CAN traffic). The bus clock is driven by hand."""
    from opentmcl.server.bus import ModuleBus

    class Clock:
        t = 0.0

        def __call__(self):
            return self.t

    clock = Clock()
    channel = unique_channel()
    bus = ModuleBus([VirtualModule("TMCM-6212", address=1)], clock=clock)
    endpoint = CanServer(bus, "virtual", channel)
    endpoint.start()
    host = can.Bus(interface="virtual", channel=channel)
    try:
        def ask(data):
            return bytes(exchange(host, 1, bytes(data)).data)

        ask([9, 82, 0, 0, 0, 0, 200])                   # SGP 82, 0, 200 (ms)
        ask([1, 0, 0, 0, 0, 0x03, 0xE8])                # ROR 0, 1000
        for _ in range(4):                              # CAN host keeps talking every 0.15 s
            clock.t += 0.15
            assert ask([6, 3, 0, 0, 0, 0, 0])[3:7] != bytes(4)   # GAP 3: still turning
        clock.t += 0.5                                  # CAN silent for longer than GP82
        assert ask([6, 3, 0, 0, 0, 0, 0])[3:7] == bytes(4)       # stopped
    finally:
        host.shutdown()
        endpoint.stop()
