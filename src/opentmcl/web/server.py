"""Run the dashboard in a background thread (uvicorn), for `opentmcl serve --web` and
`opentmcl dashboard --to URL`.

    handle = start_dashboard(module, "127.0.0.1", 8080)          # a host Module
    handle = start_dashboard_for_bus(server.bus, "127.0.0.1", 8080)  # modules of `opentmcl serve`
    print(handle.url); ...; handle.stop()
"""
from __future__ import annotations

import threading
import time

from .service import Dashboard, Poller


class DashboardHandle:
    """A running dashboard: `url`, `dashboard` (the service), `stop()`."""

    def __init__(self, dashboard: Dashboard, server, thread: threading.Thread, poller: Poller, on_stop=None):
        self.dashboard = dashboard
        self._server = server
        self._thread = thread
        self._poller = poller
        self._on_stop = on_stop
        self.host, self.port = self._bound()

    def _bound(self) -> tuple[str, int]:
        for srv in getattr(self._server, "servers", []):
            for sock in srv.sockets:
                name = sock.getsockname()
                return name[0], name[1]
        return self._server.config.host, self._server.config.port

    @property
    def url(self) -> str:
        host = f"[{self.host}]" if ":" in self.host else self.host
        return f"http://{host}:{self.port}/"

    def stop(self) -> None:
        self.dashboard.closed.set()
        self.dashboard.cancel_run()
        self._poller.stop()
        self._server.should_exit = True
        self._thread.join(timeout=5.0)
        if self._on_stop is not None:
            self._on_stop()
            self._on_stop = None

    def __enter__(self) -> DashboardHandle:
        return self

    def __exit__(self, *exc) -> None:
        self.stop()


def _ws_implementation() -> str:
    """uvicorn's sans-I/O websockets protocol where it exists (newer uvicorn deprecates the other)."""
    import importlib.util

    if importlib.util.find_spec("uvicorn.protocols.websockets.websockets_sansio_impl") is not None:
        return "websockets-sansio"
    return "websockets"


class DashboardStartError(OSError):
    """The web server could not start (port in use, bad address)."""


def warn_if_exposed(host: str, err=None) -> None:
    """Anyone who can open the page can move the motors: say so when it is not loopback-only."""
    import sys

    from ..server.tcp import is_loopback

    if not is_loopback(host):
        print(f"opentmcl: warning: the dashboard on {host} is reachable from the network; "
              "anyone who can open it can move the motors", file=err or sys.stderr)


def start_dashboard(module, host: str = "127.0.0.1", port: int = 8080, *, vm=None, vm_lock=None,
                    url: str = "", on_stop=None, poll: bool = True) -> DashboardHandle:
    """Serve the dashboard for a host `Module` on http://host:port/ from a daemon thread.

    `vm`/`vm_lock`: the in-process VirtualModule behind `module` and the lock that guards it, for
    the virtual-only features (forcing inputs). `port` 0 picks a free port (see `handle.port`).
    """
    import uvicorn

    from .app import create_app

    warn_if_exposed(host)
    dashboard = Dashboard(module, vm=vm, vm_lock=vm_lock, url=url)
    app = create_app(dashboard)
    config = uvicorn.Config(app, host=host, port=port, log_level="warning", lifespan="off",
                            ws=_ws_implementation(), access_log=False)
    server = uvicorn.Server(config)
    server.install_signal_handlers = lambda: None  # older uvicorn; the caller owns the signals
    failure: list[BaseException] = []

    def serve() -> None:
        try:
            server.run()
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
        raise DashboardStartError(f"cannot serve the dashboard on {host}:{port}"
                                  + (f": {failure[0]}" if failure and str(failure[0]) else
                                     " (address in use or not available)"))
    poller = Poller(dashboard)
    if poll:
        poller.start()
    return DashboardHandle(dashboard, server, thread, poller, on_stop)


def start_dashboard_for_bus(bus, host: str = "127.0.0.1", port: int = 8080, *, address: int | None = None,
                            timeout: float = 2.0) -> DashboardHandle:
    """Dashboard for the first module (or the one at `address`) of a running server's `ModuleBus`.
    Requests go through the bus like any client's; the bus lock guards the in-process module."""
    from ..host import Client
    from ..server import vmapi
    from .bus import BusTransport

    with bus.lock:
        vms = {vmapi.global_param(vm, vmapi.GP_SERIAL_ADDRESS): vm for vm in bus.modules}
    if address is None:
        address = next(iter(vms))
    if address not in vms:
        raise ValueError(f"no served module at address {address} (addresses: {sorted(vms)})")
    vm = vms[address]
    client = Client(BusTransport(bus), address=address, timeout=timeout)
    module = client.module(address, getattr(getattr(vm, "profile", None), "name", None))
    return start_dashboard(module, host, port, vm=vm, vm_lock=bus.lock, url=f"serve (address {address})",
                           on_stop=client.close)
