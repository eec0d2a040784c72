"""TCP endpoint: raw 9-byte TMCL frames over a socket.

This is what an Ethernet-to-serial converter in front of an RS-485 module
carries: the bytes of the serial line, no framing of its own (TMCM-6212
manual 3.1, 3.2). Each client gets its own `SerialSession` (and framer);
all clients share the bus and its lock.

Safety (docs/endpoints.md): binds to loopback unless the caller asks for
another address; at most `max_clients` clients at once (a further client is
accepted and closed at once); received bytes are only ever parsed as frames.
"""
from __future__ import annotations

import ipaddress
import logging
import socket
import struct
import sys
import threading

from .framer import DEFAULT_GAP
from .session import SerialSession

log = logging.getLogger("opentmcl.server")

DEFAULT_MAX_CLIENTS = 4
POLL = 0.2
SEND_BUFFER = 64 * 1024


def is_loopback(host: str) -> bool:
    """True for 127.0.0.0/8, ::1 and "localhost"."""
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def bound_blocking(conn: socket.socket, seconds: float) -> None:
    """Make `conn` blocking with kernel time-outs (SO_RCVTIMEO/SO_SNDTIMEO) of `seconds`.

    Cheaper per call than Python's socket time-out (which polls before every recv and
    send) and just as bounded: recv wakes up every `seconds` to check for shutdown, and a
    send to a client that has not read for `seconds` fails (the client is dropped).
    Falls back to the Python time-out where the options cannot be set."""
    if sys.platform == "win32":  # the options take milliseconds there; keep it simple
        conn.settimeout(seconds)
        return
    try:
        timeval = struct.pack("ll", int(seconds), int((seconds % 1) * 1_000_000))
        conn.settimeout(None)
        conn.setsockopt(socket.SOL_SOCKET, socket.SO_RCVTIMEO, timeval)
        conn.setsockopt(socket.SOL_SOCKET, socket.SO_SNDTIMEO, timeval)
    except (OSError, AttributeError, struct.error):
        conn.settimeout(seconds)


class TcpServer:
    """Serve the bus on a TCP port; `start()` binds, `stop()` closes everything."""

    interface = "serial"

    def __init__(self, bus, host: str = "127.0.0.1", port: int = 2323, *,
                 max_clients: int = DEFAULT_MAX_CLIENTS, gap: float = DEFAULT_GAP,
                 pace_bytes: bool = False, session=SerialSession) -> None:
        if max_clients < 1:
            raise ValueError("max_clients must be at least 1")
        self.bus = bus
        self.host = host
        self.port = port
        self.max_clients = max_clients
        self.gap = gap
        self.pace_bytes = pace_bytes
        self._session_class = session  # what handles the received bytes (the proxy passes its own)
        self._sock: socket.socket | None = None
        self._stop = threading.Event()
        self._threads: list[threading.Thread] = []
        self._clients: dict[socket.socket, SerialSession] = {}
        self._lock = threading.Lock()
        self.rejected = 0

    @property
    def address(self) -> tuple[str, int]:
        """The bound (host, port); the port is the real one when 0 was asked for."""
        if self._sock is None:
            return (self.host, self.port)
        name = self._sock.getsockname()
        return (name[0], name[1])

    @property
    def url(self) -> str:
        host, port = self.address
        return f"tcp://[{host}]:{port}" if ":" in host else f"tcp://{host}:{port}"

    def start(self) -> None:
        infos = socket.getaddrinfo(self.host, self.port, type=socket.SOCK_STREAM)
        family, _, _, _, sockaddr = infos[0]
        sock = socket.socket(family, socket.SOCK_STREAM)
        try:
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            sock.bind(sockaddr)
            sock.listen(self.max_clients)
            sock.settimeout(POLL)
        except OSError:
            sock.close()
            raise
        self._sock = sock
        self._spawn(self._accept_loop, "opentmcl-tcp-accept")

    def _spawn(self, target, name, *args) -> None:
        thread = threading.Thread(target=target, args=args, name=name, daemon=True)
        self._threads = [t for t in self._threads if t.is_alive()]
        self._threads.append(thread)
        thread.start()

    def _accept_loop(self) -> None:
        while not self._stop.is_set():
            try:
                conn, _peer = self._sock.accept()
            except TimeoutError:
                continue
            except OSError as exc:
                if self._stop.is_set() or self._sock.fileno() < 0:
                    break  # stop() closed the listening socket
                # A client that reset before it was accepted, or no file descriptor left
                # (EMFILE): the endpoint lives on and accepts again a moment later.
                log.warning("TCP accept failed: %s", exc)
                self._stop.wait(POLL)
                continue
            with self._lock:
                full = len(self._clients) >= self.max_clients
            if full or self._stop.is_set():
                self.rejected += 1
                conn.close()
                continue
            try:
                conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            except OSError:  # the client is already gone
                conn.close()
                continue
            try:  # replies are 9 bytes: a small send buffer bounds memory and finds idle readers soon
                conn.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, SEND_BUFFER)
            except OSError:
                pass
            bound_blocking(conn, POLL)
            session = self._session_class(self.bus, lambda data, c=conn: self._send(c, data),
                                    gap=self.gap, pace_bytes=self.pace_bytes)
            with self._lock:
                self._clients[conn] = session
            self._spawn(self._client_loop, "opentmcl-tcp-client", conn, session)

    def _send(self, conn: socket.socket, data: bytes) -> None:
        # The send time-out (POLL, bound_blocking) bounds sendall: a client whose
        # receive buffer stays full that long is not reading and is dropped.
        try:
            conn.sendall(data)
        except OSError:
            self._drop(conn)

    def _client_loop(self, conn: socket.socket, session: SerialSession) -> None:
        try:
            while not self._stop.is_set() and not session.closed:
                try:
                    data = conn.recv(4096)
                except (TimeoutError, BlockingIOError, InterruptedError):
                    continue
                except OSError:
                    break
                if not data:
                    break
                session.receive(data)
        finally:
            self._drop(conn)

    def _drop(self, conn: socket.socket) -> None:
        with self._lock:
            session = self._clients.pop(conn, None)
        if session is not None:
            session.close()
        try:
            conn.close()
        except OSError:
            pass

    @property
    def sessions(self) -> list[SerialSession]:
        """The sessions of the connected clients."""
        with self._lock:
            return list(self._clients.values())

    @property
    def client_count(self) -> int:
        with self._lock:
            return len(self._clients)

    def stop(self) -> None:
        self._stop.set()
        if self._sock is not None:
            self._sock.close()
        with self._lock:
            conns = list(self._clients)
        for conn in conns:
            try:
                conn.shutdown(socket.SHUT_RDWR)
            except OSError:
                pass
        for thread in self._threads:
            if thread is not threading.current_thread():
                thread.join(timeout=5)
        for conn in conns:
            self._drop(conn)
        self._threads.clear()
