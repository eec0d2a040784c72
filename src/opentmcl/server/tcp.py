"""TCP endpoint: raw 9-byte TMCL frames over a socket.

This is what an Ethernet-to-serial converter in front of an RS-485 module
carries: the bytes of the serial line, no framing of its own (TMCM-6212
manual 3.1, 3.2). Each client gets its own `SerialSession` (and framer);
all clients share the bus and its lock.

Safety (docs/endpoints.md): binds to loopback unless the caller asks for
another address; at most `max_clients` clients at once. When every slot is
taken, a new client takes the slot of the client that has been silent longest,
once that one has sent nothing for `EVICT_SILENT` seconds; the new client
waits at most `SLOT_WAIT` seconds for that, else it is closed (and logged): so
silent sockets can never keep a host out, and clients that talk keep their
slots. A client that sends nothing for `idle_timeout` seconds is dropped
anyway, and TCP keepalive finds peers that vanished; received bytes are only
ever parsed as frames, so what a client holds in memory is one partial frame
or ASCII line.
"""
from __future__ import annotations

import ipaddress
import logging
import math
import socket
import struct
import sys
import threading
import time

from .framer import DEFAULT_GAP
from .session import SerialSession

log = logging.getLogger("opentmcl.server")

DEFAULT_MAX_CLIENTS = 4
DEFAULT_IDLE_TIMEOUT = 300.0
"""Seconds a client may send nothing before it is dropped (0: never)."""
POLL = 0.2
SEND_BUFFER = 64 * 1024
KEEPALIVE = (("TCP_KEEPIDLE", 60), ("TCP_KEEPINTVL", 10), ("TCP_KEEPCNT", 5))
"""Probe after 60 s of silence, every 10 s, give up after 5: a vanished peer is found in ~110 s."""
EVICT_SILENT = 0.5
"""Seconds a client must have been silent before a new client may take its slot."""
SLOT_WAIT = 1.0
"""Seconds a new client waits for a slot when every client talks; then it is refused."""
REFUSED_LOG_EVERY = 1.0
"""At most one "refused" log line per this many seconds (a connect storm must not flood the log)."""


def check_idle_timeout(seconds, name: str = "idle timeout") -> float:
    """`seconds` as a float: 0 (no idle timeout) or a finite positive number; ValueError otherwise."""
    if isinstance(seconds, bool) or not isinstance(seconds, (int, float)):
        raise ValueError(f"{name} must be a number of seconds, got {seconds!r}")
    if seconds != 0 and not 0 < seconds < math.inf:  # also NaN
        raise ValueError(f"{name} must be 0 (none) or a positive, finite number of seconds, got {seconds!r}")
    return float(seconds)


def set_keepalive(conn: socket.socket) -> None:
    """Turn on TCP keepalive with the `KEEPALIVE` timing where the platform has the options."""
    try:
        conn.setsockopt(socket.SOL_SOCKET, socket.SO_KEEPALIVE, 1)
    except OSError:
        return
    for name, value in KEEPALIVE:
        if name == "TCP_KEEPIDLE" and not hasattr(socket, name):
            name = "TCP_KEEPALIVE"  # macOS spells the idle time so
        option = getattr(socket, name, None)
        if option is None:
            continue
        try:
            conn.setsockopt(socket.IPPROTO_TCP, option, value)
        except OSError:
            pass


def peer_name(conn: socket.socket) -> str:
    """``HOST:PORT`` of the other end, or "?" once it is gone."""
    try:
        peer = conn.getpeername()
    except OSError:
        return "?"
    host, port = peer[0], peer[1]
    return f"[{host}]:{port}" if ":" in host else f"{host}:{port}"


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
                 pace_bytes: bool = False, idle_timeout: float = DEFAULT_IDLE_TIMEOUT,
                 session=SerialSession, evict_silent: float = EVICT_SILENT,
                 slot_wait: float = SLOT_WAIT) -> None:
        if max_clients < 1:
            raise ValueError("max_clients must be at least 1")
        self.idle_timeout = check_idle_timeout(idle_timeout)
        if not (evict_silent > 0 and slot_wait >= 0):
            raise ValueError("evict_silent must be > 0 (inf: never evict) and slot_wait >= 0")
        self.evict_silent, self.slot_wait = evict_silent, slot_wait
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
        self._peers: dict[socket.socket, str] = {}
        self._heard: dict[socket.socket, float] = {}  # when each client last sent something
        self._lock = threading.Lock()
        self.rejected = 0
        """Clients refused because `max_clients` were connected."""
        self.dropped_idle = 0
        """Clients dropped because they sent nothing for `idle_timeout` seconds."""
        self.evicted = 0
        """Silent clients that gave their slot up to a new client."""
        self._refused_logged = -math.inf
        self._refused_quiet = 0  # refusals not logged since the last line

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
            sock = self._sock  # read each time: tests put a failing socket in its place
            if sock is None:
                return
            try:
                conn, _peer = sock.accept()
            except TimeoutError:
                continue
            except OSError as exc:
                if self._stop.is_set() or sock.fileno() < 0:
                    break  # stop() closed the listening socket
                # A client that reset before it was accepted, or no file descriptor left
                # (EMFILE): the endpoint lives on and accepts again a moment later.
                log.warning("TCP accept failed: %s", exc)
                self._stop.wait(POLL)
                continue
            full = not self._free_slot()
            if full or self._stop.is_set():
                self.rejected += 1
                if full:
                    self._log_refused(peer_name(conn))
                conn.close()
                continue
            try:
                conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            except OSError:  # the client is already gone
                conn.close()
                continue
            set_keepalive(conn)
            try:  # replies are 9 bytes: a small send buffer bounds memory and finds idle readers soon
                conn.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, SEND_BUFFER)
            except OSError:
                pass
            bound_blocking(conn, POLL)
            session = self._session_class(self.bus, lambda data, c=conn: self._send(c, data),
                                    gap=self.gap, pace_bytes=self.pace_bytes)
            with self._lock:
                self._clients[conn] = session
                self._peers[conn] = peer_name(conn)
                self._heard[conn] = time.monotonic()
            self._spawn(self._client_loop, "opentmcl-tcp-client", conn, session)

    def _free_slot(self) -> bool:
        """Is there a slot for a new client? When all are taken, evict the client silent longest
        once it has been silent `evict_silent` s, waiting up to `slot_wait` s for that."""
        deadline = time.monotonic() + self.slot_wait
        while not self._stop.is_set():
            with self._lock:
                if len(self._clients) < self.max_clients:
                    return True
                conn, heard = min(self._heard.items(), key=lambda item: item[1])
            now = time.monotonic()
            if now - heard >= self.evict_silent:
                self.evicted += 1
                self._drop(conn, f"gave its slot to a new client: silent for {now - heard:.1f} s "
                                 f"with all {self.max_clients} slots taken (--max-clients)")
                return True
            if now >= deadline:
                return False
            self._stop.wait(min(0.05, deadline - now, heard + self.evict_silent - now))
        return False

    def _log_refused(self, peer: str) -> None:
        now = time.monotonic()
        if now - self._refused_logged < REFUSED_LOG_EVERY:
            self._refused_quiet += 1
            return
        more = f" ({self._refused_quiet} more refused since the last line)" if self._refused_quiet else ""
        log.warning("TCP client %s refused: %d clients connected, the maximum (--max-clients)%s",
                    peer, self.max_clients, more)
        self._refused_logged, self._refused_quiet = now, 0

    def _send(self, conn: socket.socket, data: bytes) -> None:
        # The send time-out (POLL, bound_blocking) bounds sendall: a client whose
        # receive buffer stays full that long is not reading and is dropped.
        try:
            conn.sendall(data)
        except (BlockingIOError, TimeoutError):
            self._drop(conn, "dropped: it does not read its replies")
        except OSError:
            self._drop(conn)

    def _client_loop(self, conn: socket.socket, session: SerialSession) -> None:
        idle = self.idle_timeout
        last = time.monotonic()
        reason = None
        try:
            while not self._stop.is_set() and not session.closed:
                try:
                    data = conn.recv(4096)
                except (TimeoutError, BlockingIOError, InterruptedError):
                    if idle and time.monotonic() - last >= idle:
                        self.dropped_idle += 1
                        reason = f"dropped: nothing received for {idle:g} s (--idle-timeout)"
                        break
                    continue
                except OSError:
                    break
                if not data:
                    break
                last = time.monotonic()
                with self._lock:
                    if conn in self._heard:  # not if it was evicted meanwhile
                        self._heard[conn] = last
                session.receive(data)
        finally:
            self._drop(conn, reason)

    def _drop(self, conn: socket.socket, reason: str | None = None) -> None:
        with self._lock:
            session = self._clients.pop(conn, None)
            peer = self._peers.pop(conn, "?")
            self._heard.pop(conn, None)
        if session is not None and reason:
            log.warning("TCP client %s %s", peer, reason)
        if session is not None:
            session.close()
        try:
            conn.shutdown(socket.SHUT_RDWR)  # wakes the recv of its thread, if another thread drops it
        except OSError:
            pass
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
            sessions = list(self._clients.values())
        for session in sessions:
            session.closed = True  # a read being handled ends at its next frame (server/stream.py)
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
