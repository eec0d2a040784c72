"""The same Module API over every endpoint: sim://, tcp:// and can:// (python-can's virtual bus),
the latter two served in real time by opentmcl.server."""
from __future__ import annotations

import sys
import uuid

import pytest

from opentmcl import VirtualModule
from opentmcl.host import TmclStatusError, connect
from opentmcl.server import CanServer, PtyServer, Server, TcpServer

ENDPOINTS = ["sim", "tcp", "can", pytest.param("serial", marks=pytest.mark.skipif(
    sys.platform == "win32", reason="pseudo-terminals need POSIX"))]


@pytest.fixture(params=ENDPOINTS)
def url(request):
    if request.param == "sim":
        yield "sim://TMCM-6212"
        return
    server = Server([VirtualModule("TMCM-6212", address=1)])
    if request.param == "tcp":
        endpoint = server.add(TcpServer(server.bus, "127.0.0.1", 0))
    elif request.param == "can":
        endpoint = server.add(CanServer(server.bus, "virtual", f"opentmcl-host-{uuid.uuid4().hex[:12]}"))
    else:
        endpoint = server.add(PtyServer(server.bus))
    server.start()
    try:
        if request.param == "tcp":
            yield endpoint.url
        elif request.param == "can":
            yield endpoint.url + "?id=1"
        else:
            yield f"serial://{endpoint.path}?baud=9600"
    finally:
        server.stop()


def test_same_module_api_on_every_endpoint(url):
    """TMCM-6212 manual 3.6.36 (136 string), 3.6.5/3.6.6 (SAP/GAP), 3.6.35 (138 event), 3.2.1
    (status 4) — the same calls give the same answers whatever carries the bytes."""
    with connect(url, timeout=2.0) as m:
        assert m.firmware_version() == "6212V105"
        assert m.name == "TMCM-6212"
        ax = m.axes[1]
        ax.set("max_positioning_speed", 200000)
        ax.set("max_acceleration", 1000000)
        assert ax.get("max_positioning_speed") == 200000
        ax.move_to(20000, wait=True, timeout=10)
        assert ax.position == 20000
        m.set_variable(7, -42)
        assert m.get_variable(7) == -42
        with pytest.raises(TmclStatusError, match="Invalid value"):
            ax.set("max_positioning_speed", 8_000_000)


def test_cli_send_to_a_tcp_endpoint(capsys):
    """The endpoints issue: `opentmcl send "MVP ABS, 0, 1000" --to URL` (MVP ABS, manual 3.6.4)."""
    from opentmcl.cli import main

    server = Server([VirtualModule("TMCM-6212", address=1)])
    tcp = server.add(TcpServer(server.bus, "127.0.0.1", 0))
    server.start()
    try:
        assert main(["send", "MVP ABS, 0, 1000", "GAP 0, 0", "--plain", "--to", tcp.url]) == 0
    finally:
        server.stop()
    out = capsys.readouterr().out.splitlines()
    assert len(out) == 2 and out[1] == "1000"  # MVP's reply value is "don't care"


def test_download_and_verify_a_program_on_every_endpoint(url):
    """TMCM-6212 manual 3.6.36: 132 download mode, the instructions (status 101), 133, then 134 reads
    program memory back (special reply) — the loader's verify works whatever carries the bytes."""
    from opentmcl.host.loader import Loader
    from opentmcl.lang import assemble

    program = assemble("SAP 4, 0, 1000\nLoop: MVP ABS, 0, -7\n  JA Loop\n", module="TMCM-6212")
    with connect(url, timeout=2.0) as m:
        loader = Loader(m)
        loader.download(program)            # verifies through 134
        assert [tuple(i) for i in loader.read(0, 4)] == [tuple(i) for i in program.instructions]
