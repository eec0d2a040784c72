"""Run the dashboard in a background thread (uvicorn), for `opentmcl serve --web` and
`opentmcl dashboard --to URL`.

    handle = start_dashboard(module, "127.0.0.1", 8080)          # a host Module
    handle = start_dashboard_for_bus(server.bus, "127.0.0.1", 8080)  # every module of `opentmcl serve`
    print(handle.url); ...; handle.stop()

Each module's page is at /m/ADDRESS/; the root redirects to the first one.
"""
from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable, Iterable
from typing import TYPE_CHECKING

from .connlimits import HEAD_MAX, HEAD_TIMEOUT, KEEP_ALIVE, MAX_CONNECTIONS, RESERVE, protocol_class
from .guard import BODY_TIMEOUT
from .service import Dashboard, Poller

if TYPE_CHECKING:
    import socket

    import uvicorn

    from ..host import Module
    from ..server.bus import ModuleBus
    from .app import ModuleIndex

STOP_GRACE = 0.5
"""Seconds `DashboardHandle.stop` waits for the requests under way before it returns."""
CLOSE_WAIT = 5.0
"""Seconds the links are kept open after that for requests still under way (not in `stop`)."""
WS_MAX_SIZE = 64 * 1024  # the page sends nothing on its WebSocket; uvicorn's default is 16 MiB


class DashboardHandle:
    """A running dashboard: `url` (the root), `open_url` (with ?token= when one is required),
    `token`, `dashboards` (one service per module, the first also as `dashboard`),
    `module_url(address)`, `stop()`."""

    def __init__(self, dashboards: list[Dashboard], server: uvicorn.Server, thread: threading.Thread,
                 pollers: list[Poller], on_stop: Callable[[], None] | None = None, token: str | None = None, allowed_hosts: tuple[str, ...] = ()):
        self.dashboards = list(dashboards)
        self.token = token  # required on every request when set (LAN use); None on loopback
        self.allowed_hosts = tuple(allowed_hosts)
        self._server = server
        self._thread = thread
        self._pollers = list(pollers)
        self._on_stop = on_stop
        self.index: ModuleIndex | None = None  # the app's modules, with those opened from a scan
        self.host, self.port = self._bound()

    @property
    def dashboard(self) -> Dashboard:
        return self.dashboards[0]

    def _bound(self) -> tuple[str, int]:
        for srv in getattr(self._server, "servers", []):
            for sock in srv.sockets:
                name = sock.getsockname()
                return name[0], name[1]
        return self._server.config.host, self._server.config.port

    @property
    def url(self) -> str:
        """The root: it redirects to the first module's page, which offers the others."""
        host = f"[{self.host}]" if ":" in self.host else self.host
        return f"http://{host}:{self.port}/"

    @property
    def open_url(self) -> str:
        """The URL to open in a browser: `url`, with ?token=... when a token is required."""
        return self.url + (f"?token={self.token}" if self.token else "")

    def urls_to_open(self) -> list[str]:
        """`open_url` and the same page under every --allow-host name."""
        query = f"?token={self.token}" if self.token else ""
        names = [f"[{h}]" if ":" in h and not h.startswith("[") else h for h in self.allowed_hosts]
        return [self.open_url] + [f"http://{h}:{self.port}/{query}" for h in names]

    def module_url(self, address: int) -> str:
        """The page of the module at `address`."""
        return f"{self.url}m/{address}/"

    def stop(self) -> None:
        """Within about `STOP_GRACE` s (issue 28: `serve` ends within 2 s of SIGTERM): a download
        under way ends at its next instruction (133 sent), a table read at its next batch, the scan
        at its current address. Requests still under way then keep their links until they end
        (closed under them, a serial port fails with errors of its own); the links are closed
        once they have."""
        for d in self.dashboards:
            d.closed.set()
        if self.index is not None:
            self.index.close()  # the scan and the modules opened from it
        for d in self.dashboards:
            d.cancel_run()
        for poller in self._pollers:
            poller.stop()
        self._server.should_exit = True
        self._thread.join(timeout=STOP_GRACE)
        on_stop, self._on_stop = self._on_stop, None
        if on_stop is None:
            return
        if not self._thread.is_alive():
            on_stop()
            return
        threading.Thread(target=self._close_later, args=(on_stop,), name="dashboard-close", daemon=True).start()

    def _close_later(self, on_stop: Callable[[], None]) -> None:
        self._thread.join(timeout=CLOSE_WAIT)
        on_stop()

    def __enter__(self) -> DashboardHandle:
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()


def _ws_implementation() -> str:
    """uvicorn's sans-I/O websockets protocol where it exists (newer uvicorn deprecates the other)."""
    import importlib.util

    if importlib.util.find_spec("uvicorn.protocols.websockets.websockets_sansio_impl") is not None:
        return "websockets-sansio"
    return "websockets"


class _RefusedHandshakeFilter(logging.Filter):
    """uvicorn's sans-I/O WebSocket protocol logs "ASGI callable returned without completing
    handshake." at ERROR level after a denial response (guard.py's 403), which it does complete:
    drop that line, the guard has logged the refusal with its reason."""

    def filter(self, record: logging.LogRecord) -> bool:
        return not str(record.msg).startswith("ASGI callable returned without completing handshake")


_HANDSHAKE_FILTER = _RefusedHandshakeFilter()


class DashboardStartError(OSError):
    """The web server could not start (port in use, bad address)."""


def warn_if_exposed(host: str) -> None:
    """Anyone who has the token can move the motors: say so (a log warning) when it is not loopback-only."""
    from ..server.tcp import is_loopback

    if not is_loopback(host):
        logging.getLogger("opentmcl.web").warning(
            "warning: the dashboard on %s is reachable from the network; anyone who has its token can move "
            "the motors", host)


def check_allowed_hosts(names: Iterable[object]) -> tuple[str, ...]:
    """--allow-host values: host names or IP addresses (IPv6 with or without brackets), no scheme,
    port or path; ValueError with a one-line message otherwise."""
    import ipaddress
    import re

    out: list[str] = []
    for name in names:
        text = str(name).strip().lower()
        bare = text[1:-1] if text.startswith("[") and text.endswith("]") else text
        try:
            ok = ipaddress.ip_address(bare).version == 6 or bare == text
        except ValueError:
            ok = bare == text and re.fullmatch(r"[a-z0-9_]([a-z0-9_.-]*[a-z0-9_])?\.?", text) is not None
        if not ok:
            raise ValueError(f"--allow-host {name!r}: give a host name or IP address, without scheme or port")
        out.append(bare)
    return tuple(out)


def start_dashboard(module: Module, host: str = "127.0.0.1", port: int = 8080, *, vm: object = None,
                    vm_lock: object = None, url: str = "", on_stop: Callable[[], None] | None = None,
                    poll: bool = True, allow_hosts: Iterable[str] = (), token: str | None = None,
                    head_timeout: float = HEAD_TIMEOUT, max_connections: int = MAX_CONNECTIONS,
                    body_timeout: float = BODY_TIMEOUT, reserve: int = RESERVE) -> DashboardHandle:
    """Serve the dashboard for a host `Module` at http://host:port/m/ADDRESS/ (the root redirects
    there) from a daemon thread.

    `vm`/`vm_lock`: the in-process VirtualModule behind `module` and the lock that guards it, for
    the virtual-only features (forcing inputs). `port` 0 picks a free port (see `handle.port`).
    `allow_hosts`, `token`, `head_timeout`, `max_connections`, `body_timeout` and `reserve`: see
    `serve_dashboards`.
    """
    dashboard = Dashboard(module, vm=vm, vm_lock=vm_lock, url=url)
    return serve_dashboards([dashboard], host, port, on_stop=on_stop, poll=poll, allow_hosts=allow_hosts,
                            token=token, head_timeout=head_timeout, max_connections=max_connections,
                            body_timeout=body_timeout, reserve=reserve)


def _bind(host: str, port: int) -> socket.socket:
    """The listening socket, bound here so a port in use is a clear DashboardStartError."""
    import socket

    where = f"cannot serve the dashboard on {host}:{port}"
    try:
        family, kind, proto, _, addr = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM,
                                                          flags=socket.AI_PASSIVE)[0]
    except socket.gaierror as exc:
        raise DashboardStartError(f"{where}: {exc.strerror}") from None
    sock = socket.socket(family, kind, proto)
    try:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        sock.bind(addr)
    except OSError as exc:
        sock.close()
        raise DashboardStartError(f"{where}: {exc.strerror or exc}") from None
    return sock


def serve_dashboards(dashboards: list[Dashboard], host: str = "127.0.0.1", port: int = 8080, *,
                     on_stop: Callable[[], None] | None = None, poll: bool = True,
                     allow_hosts: Iterable[str] = (), token: str | None = None,
                     head_timeout: float = HEAD_TIMEOUT, max_connections: int = MAX_CONNECTIONS,
                     body_timeout: float = BODY_TIMEOUT, reserve: int = RESERVE) -> DashboardHandle:
    """Serve several `Dashboard`s (distinct module addresses) on one port, one poller each.

    Requests must name a loopback host, `host` or one of `allow_hosts` (guard.py). A token is
    required when `allow_hosts` is given or `host` is not loopback (a new random one unless `token`
    is given; `handle.token`, `handle.open_url`); `token` also forces one on loopback.

    Connection limits (connlimits.py, guard.py): a request head must be complete within
    `head_timeout` seconds and its body within `body_timeout`; at most `max_connections` at once,
    and `reserve` more that carry only STOP ALL; an idle connection gives its place to a new one.
    """
    import uvicorn

    from ..server.tcp import is_loopback
    from .app import create_app
    from .guard import new_token

    hosts = check_allowed_hosts(allow_hosts)
    if token is None and (hosts or not is_loopback(host)):
        token = new_token()
    app = create_app(dashboards, allowed_hosts=(host, *hosts), token=token, body_timeout=body_timeout)
    warn_if_exposed(host)
    sock = _bind(host, port)
    config = uvicorn.Config(app, host=host, port=port, log_level="warning", lifespan="off",
                            ws=_ws_implementation(), access_log=False, ws_max_size=WS_MAX_SIZE,
                            http=protocol_class(head_timeout, max_connections, reserve), h11_max_incomplete_event_size=HEAD_MAX,
                            timeout_keep_alive=KEEP_ALIVE)
    server = uvicorn.Server(config)
    logging.getLogger("uvicorn.error").addFilter(_HANDSHAKE_FILTER)  # idempotent: one filter object
    failure: list[BaseException] = []

    def serve() -> None:
        try:
            server.run(sockets=[sock])
        except BaseException as exc:  # SystemExit from uvicorn when the bind fails
            failure.append(exc)

    thread = threading.Thread(target=serve, name="dashboard-web", daemon=True)
    thread.start()
    deadline = time.monotonic() + 10.0
    while not server.started and thread.is_alive() and time.monotonic() < deadline:
        time.sleep(0.02)
    if not server.started:
        server.should_exit = True
        thread.join(timeout=2.0)
        sock.close()
        raise DashboardStartError(f"cannot serve the dashboard on {host}:{port}"
                                  + (f": {failure[0]}" if failure and str(failure[0]) else
                                     " (address in use or not available)"))
    pollers = [Poller(d) for d in dashboards]
    if poll:
        for poller in pollers:
            poller.start()
    handle = DashboardHandle(dashboards, server, thread, pollers, on_stop, token, hosts)
    handle.index = app.state.index
    return handle


def bus_dashboards(bus: ModuleBus, *, address: int | None = None,
                   timeout: float = 2.0) -> tuple[list[Dashboard], Callable[[], None]]:
    """One `Dashboard` per module of a `ModuleBus` (or only the one at `address`), each talking to
    its module through the bus (BusTransport). Returns the dashboards and a function that closes
    their clients."""
    from ..host import Client
    from ..server import vmapi
    from .bus_transport import BusTransport

    with bus.lock:
        vms = {vmapi.global_param(vm, vmapi.GP_SERIAL_ADDRESS): vm for vm in bus.modules}
    if address is not None:
        if address not in vms:
            raise ValueError(f"no served module at address {address} (addresses: {sorted(vms)})")
        vms = {address: vms[address]}
    clients: list[Client] = []

    def close() -> None:
        for client in clients:
            client.close()

    dashboards = []
    try:
        for addr, vm in vms.items():
            client = Client(BusTransport(bus), address=addr, timeout=timeout)
            clients.append(client)
            module = client.module(addr, getattr(vm, "profile", None))  # the profile itself: a user profile file too
            dashboard = Dashboard(module, vm=vm, vm_lock=bus.lock, url=f"serve (address {addr})")
            dashboard.faults = getattr(bus, "faults", None)  # the served fault plan (web/faults.py)
            dashboards.append(dashboard)
    except BaseException:
        close()
        raise
    return dashboards, close


def start_dashboard_for_bus(bus: ModuleBus, host: str = "127.0.0.1", port: int = 8080, *,
                            address: int | None = None, timeout: float = 2.0,
                            allow_hosts: Iterable[str] = (), token: str | None = None) -> DashboardHandle:
    """Dashboard for every module of a running server's `ModuleBus` (or only the one at `address`),
    each at /m/ADDRESS/. Requests go through the bus like any client's; the bus lock guards the
    in-process modules."""
    dashboards, close = bus_dashboards(bus, address=address, timeout=timeout)
    try:
        return serve_dashboards(dashboards, host, port, on_stop=close, allow_hosts=allow_hosts, token=token)
    except BaseException:
        close()
        raise
