"""TCP transport: raw 9-byte TMCL frames over a socket (TMCM-6212 manual 3.1, 3.2).

For `opentmcl serve --tcp` and for Ethernet-to-serial converters in front of
a real module, which carry the serial line's bytes unchanged.

    tcp://HOST:PORT[?connect_timeout=SECONDS&window=N]

`window` (default 8) is how many requests `Client.request_many` sends before it reads their
replies; our servers answer frames that arrive together in order (docs/endpoints.md). In front
of a real module (an Ethernet-to-serial converter) use ``window=1``: its receive buffer is not
documented (docs/assumptions.md).
"""
from __future__ import annotations

import socket
import urllib.parse

from ..errors import TmclConnectionError, TmclUrlError, check_timeout
from ..transport import StreamTransport, link_error, log, url_query, url_window

DEFAULT_CONNECT_TIMEOUT = 5.0
DEFAULT_WINDOW = 8


class TcpTransport(StreamTransport):
    """A connected TCP socket; `recv` returns exactly n bytes or raises `TmclTimeout`."""

    def __init__(self, host: str, port: int, connect_timeout: float = DEFAULT_CONNECT_TIMEOUT,
                 window: int = DEFAULT_WINDOW) -> None:
        connect_timeout = check_timeout(connect_timeout, "connect_timeout")
        super().__init__()
        self.window = window
        self.host, self.port = host, port
        self.name = f"tcp://{host}:{port}"
        try:
            self._sock = socket.create_connection((host, port), timeout=connect_timeout)
        except TimeoutError:
            raise TmclConnectionError(f"tcp://{host}:{port}: no connection within {connect_timeout:g} s; "
                                      "check the host name, the port and any firewall between") from None
        except ConnectionRefusedError:
            raise TmclConnectionError(f"tcp://{host}:{port}: connection refused; is a TMCL server listening "
                                      f"on port {port} (e.g. `opentmcl serve --tcp {host}:{port}`)?") from None
        except OSError as exc:
            raise TmclConnectionError(f"tcp://{host}:{port}: {exc.strerror or exc}") from None
        self._sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        log.info("connected to %s", self.name)

    def _write(self, data: bytes) -> None:
        try:
            self._sock.settimeout(DEFAULT_CONNECT_TIMEOUT)
            self._sock.sendall(data)
        except OSError as exc:
            raise TmclConnectionError(link_error(self.name, "sending", exc)) from None

    def _read_some(self, timeout: float) -> bytes:
        try:
            self._sock.settimeout(timeout)
            chunk = self._sock.recv(4096)
        except TimeoutError:
            return b""
        except OSError as exc:
            raise TmclConnectionError(link_error(self.name, "receiving", exc)) from None
        if not chunk:
            raise TmclConnectionError(
                f"{self.name}: connection closed by the server; check that it is still running, has room "
                "for another client and keeps idle ones (opentmcl serve --max-clients, --idle-timeout 0), "
                "then connect again")
        return chunk

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

    def _release(self) -> None:
        self._sock.close()


def open_tcp(url: urllib.parse.SplitResult) -> TcpTransport:
    """Factory for ``tcp://HOST:PORT[?connect_timeout=S&window=N]``."""
    query = url_query(url, ("connect_timeout", "window"))
    window = url_window(query, DEFAULT_WINDOW, url.geturl())
    try:
        port = url.port
    except ValueError:
        raise TmclUrlError(f"bad port in {url.geturl()!r}") from None
    if not url.hostname or port is None:
        raise TmclUrlError(f"TCP URL needs a host and a port, e.g. tcp://127.0.0.1:2323, got {url.geturl()!r}")
    try:
        connect_timeout = float(query.get("connect_timeout", DEFAULT_CONNECT_TIMEOUT))
    except ValueError:
        raise TmclUrlError(f"bad connect_timeout in {url.geturl()!r}") from None
    if not 0 < connect_timeout < float("inf"):  # also NaN
        raise TmclUrlError(f"connect_timeout must be a positive, finite number of seconds, "
                                  f"got {connect_timeout}")
    return TcpTransport(url.hostname, port, connect_timeout, window)
