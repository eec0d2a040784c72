"""The transport contract of `opentmcl.host.transport.Transport` that callers outside the client
rely on: `lock` (docs/architecture.md "Request path")."""
from __future__ import annotations

import threading

import pytest

from opentmcl import VirtualModule
from opentmcl.host import connect
from opentmcl.host.transports.inprocess import InProcessTransport
from opentmcl.server import Server, TcpServer


@pytest.fixture
def tcp_url():
    srv = Server([VirtualModule("TMCM-6212", address=1)])
    tcp = srv.add(TcpServer(srv.bus, "127.0.0.1", 0))
    srv.start()
    try:
        yield tcp.url
    finally:
        srv.stop()


def _reentrant(lock) -> bool:
    with lock:
        with lock:
            return True


def test_every_transport_has_one_reentrant_lock(tcp_url):
    """The dashboard reads an in-process module under `transport.lock`; the lock is declared on
    every transport, the same object each time, and re-entrant. A real link answers GGP 66
    (TMCM-6212 manual 3.6.8) while its lock is held by the same thread."""
    m = connect(tcp_url)
    try:
        lock = m.client.transport.lock
        assert lock is m.client.transport.lock and _reentrant(lock)
        with lock:
            assert m.get_global(66) == 1
    finally:
        m.close()
    local = InProcessTransport(VirtualModule("PD28-1021"))
    assert local.lock is local.lock and _reentrant(local.lock)
    assert isinstance(local.lock, type(threading.RLock()))
