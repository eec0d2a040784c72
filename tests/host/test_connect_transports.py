"""The transport contract of `opentmcl.host.transport.Transport` that callers outside the client
rely on: `lock` (docs/architecture.md "Request path")."""
from __future__ import annotations

import threading

from opentmcl import VirtualModule
from opentmcl.host import connect
from opentmcl.host.transports.inprocess import InProcessTransport


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
