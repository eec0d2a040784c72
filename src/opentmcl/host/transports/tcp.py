"""TCP transport: raw 9-byte TMCL frames over a socket (TMCM-6212 manual 3.1, 3.2).

For `opentmcl serve --tcp` and for Ethernet-to-serial converters in front of
a real module, which carry the serial line's bytes unchanged.

    tcp://HOST:PORT[?connect_timeout=SECONDS]
"""
from __future__ import annotations

import socket
import time
import urllib.parse

from ..errors import TmclConnectionError, TmclTimeout
from ..transport import Transport

DEFAULT_CONNECT_TIMEOUT = 5.0


class TcpTransport(Transport):
    """A connected TCP socket; `recv` returns exactly n bytes or raises `TmclTimeout`."""

    frame_format = "serial"

    def __init__(self, host: str, port: int, connect_timeout: float = DEFAULT_CONNECT_TIMEOUT) -> None:
        self.host, self.port = host, port
        try:
            self._sock = socket.create_connection((host, port), timeout=connect_timeout)
        except TimeoutError:
            raise TmclConnectionError(f"tcp://{host}:{port}: no connection within {connect_timeout:g} s") from None
        except OSError as exc:
            raise TmclConnectionError(f"tcp://{host}:{port}: {exc.strerror or exc}") from None
        self._sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self._rx = bytearray()
        self._closed = False

    def _check_open(self) -> None:
        if self._closed:
            raise TmclConnectionError(f"tcp://{self.host}:{self.port} is closed")

    def send(self, data: bytes) -> None:
        self._check_open()
        try:
            self._sock.settimeout(DEFAULT_CONNECT_TIMEOUT)
            self._sock.sendall(data)
        except OSError as exc:
            raise TmclConnectionError(f"tcp://{self.host}:{self.port}: send failed: {exc}") from None

    def recv(self, n: int, timeout: float) -> bytes:
        self._check_open()
        deadline = time.monotonic() + max(0.0, timeout)
        while len(self._rx) < n:
            left = deadline - time.monotonic()
            if left <= 0:
                raise TmclTimeout(f"tcp://{self.host}:{self.port}: no reply within {timeout:g} s "
                                  f"({len(self._rx)} of {n} bytes received)")
            try:
                self._sock.settimeout(left)
                chunk = self._sock.recv(4096)
            except TimeoutError:
                continue
            except OSError as exc:
                raise TmclConnectionError(f"tcp://{self.host}:{self.port}: receive failed: {exc}") from None
            if not chunk:
                raise TmclConnectionError(f"tcp://{self.host}:{self.port}: connection closed by the server")
            self._rx += chunk
        out = bytes(self._rx[:n])
        del self._rx[:n]
        return out

    def reset_input(self) -> None:
        self._rx.clear()
        if self._closed:
            return
        try:
            self._sock.setblocking(False)
            while self._sock.recv(4096):
                pass
        except (BlockingIOError, OSError):
            pass
        finally:
            try:
                self._sock.setblocking(True)
            except OSError:
                pass

    def close(self) -> None:
        if self._closed:
            return
        self._closed = True
        try:
            self._sock.close()
        except OSError:
            pass


def open_tcp(url: urllib.parse.SplitResult) -> TcpTransport:
    """Factory for ``tcp://HOST:PORT[?connect_timeout=S]``."""
    query = dict(urllib.parse.parse_qsl(url.query))
    try:
        port = url.port
    except ValueError:
        raise TmclConnectionError(f"bad port in {url.geturl()!r}") from None
    if not url.hostname or port is None:
        raise TmclConnectionError(f"TCP URL needs a host and a port, e.g. tcp://127.0.0.1:2323, got {url.geturl()!r}")
    try:
        connect_timeout = float(query.get("connect_timeout", DEFAULT_CONNECT_TIMEOUT))
    except ValueError:
        raise TmclConnectionError(f"bad connect_timeout in {url.geturl()!r}") from None
    return TcpTransport(url.hostname, port, connect_timeout)
