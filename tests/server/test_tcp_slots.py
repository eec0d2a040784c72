"""TCP slots (issue 28 item 3, docs/endpoints.md "Slots"): silent clients give their slot to a new
client, clients that talk keep theirs, and a new client is refused only when every slot is held by
a client that talks. Vector: TMCM-6212 manual 3.6.8, GGP 66, 0 -> 02 01 64 0A 00 00 00 01 72."""
from __future__ import annotations

import math
import socket
import time

import pytest

from opentmcl import VirtualModule
from opentmcl.server import Server, TcpServer

from .helpers import GGP_66, recv_exactly, reply

ANSWER = reply(2, 1, 100, 10, 1)


def served(**options):
    server = Server([VirtualModule("TMCM-6212", address=1)])
    tcp = server.add(TcpServer(server.bus, "127.0.0.1", 0, **options))
    server.start()
    return server, tcp


def talk(sock: socket.socket) -> bool:
    sock.sendall(GGP_66)
    return recv_exactly(sock, 9, timeout=10) == ANSWER


def closed(sock: socket.socket, timeout: float = 30.0) -> bool:
    sock.settimeout(timeout)
    try:
        return sock.recv(9) == b""
    except ConnectionResetError:
        return True
    except TimeoutError:
        return False


def wait_until(condition, timeout: float = 30.0) -> bool:
    deadline = time.monotonic() + timeout
    while not condition():
        if time.monotonic() > deadline:
            return False
        time.sleep(0.01)
    return True


def test_the_client_silent_longest_gives_up_its_slot():
    """Three slots held; the one that spoke first and then fell silent is the one a fourth client
    evicts; the others, silent for less long, keep their slots and still get answers."""
    server, tcp = served(max_clients=3, evict_silent=0.2, slot_wait=30.0)
    try:
        a, b, c = (socket.create_connection(tcp.address, timeout=10) for _ in range(3))
        for s in (a, b, c):
            assert talk(s)
        assert talk(b) and talk(c)  # `a` is now the one silent longest
        with socket.create_connection(tcp.address, timeout=10) as d:
            assert talk(d)
            assert closed(a)
            assert talk(b) and talk(c)
        assert tcp.evicted == 1 and tcp.rejected == 0
        for s in (a, b, c):
            s.close()
    finally:
        server.stop()


def test_a_new_client_is_refused_when_every_slot_holder_talks():
    """Clients that talked within `evict_silent` keep their slots: the new one waits `slot_wait`
    seconds for a slot, then it is closed (refused) and the others go on."""
    server, tcp = served(max_clients=2, evict_silent=3600.0, slot_wait=0.2)
    try:
        with socket.create_connection(tcp.address, timeout=10) as a, \
                socket.create_connection(tcp.address, timeout=10) as b:
            assert talk(a) and talk(b)
            with socket.create_connection(tcp.address, timeout=10) as c:
                assert closed(c)
            assert wait_until(lambda: tcp.rejected == 1)
            assert talk(a) and talk(b) and tcp.evicted == 0
    finally:
        server.stop()


def test_a_client_that_never_spoke_counts_as_silent_since_it_connected():
    """A connection that sends nothing at all (an idle socket) is silent from the moment it was
    accepted: a new client takes its slot too."""
    server, tcp = served(max_clients=1, evict_silent=0.2, slot_wait=30.0)
    try:
        with socket.create_connection(tcp.address, timeout=10) as idle:
            assert wait_until(lambda: tcp.client_count == 1)
            with socket.create_connection(tcp.address, timeout=10) as new:
                assert talk(new)
                assert closed(idle)
    finally:
        server.stop()


@pytest.mark.parametrize("evict_silent, slot_wait", [(0, 1.0), (-1, 1.0), (math.nan, 1.0), (1.0, -0.1)])
def test_slot_options_are_checked(evict_silent, slot_wait):
    """evict_silent must be > 0 (math.inf: never evict), slot_wait >= 0."""
    with pytest.raises(ValueError):
        TcpServer(None, "127.0.0.1", 0, evict_silent=evict_silent, slot_wait=slot_wait)
