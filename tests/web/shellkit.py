"""Helpers of the workbench-shell tests (test_shell_*.py): a served bus of virtual modules with a TCP
endpoint (the test's own client talks over the wire to the same modules the dashboard drives), and
a page that records every console error or warning."""
from __future__ import annotations

import contextlib
import importlib
import os
from collections.abc import Iterator
from dataclasses import dataclass, field

TIMEOUT_MS = int(os.environ.get("OPENTMCL_TEST_TIMEOUT_MS", "60000"))  # a guard against hanging: the tests wait for a state, they do not time anything
GAP, SAP, MST = 6, 5, 3
ACTUAL_SPEED, TARGET_SPEED, ACTUAL_POSITION = 3, 2, 1


@dataclass
class Bench:
    handle: object                 # the DashboardHandle
    url: str                       # tcp://... of the same bus
    server: object
    clients: list = field(default_factory=list)

    def client(self, address: int = 1):
        """A host Module at `address` over TCP (a client of the bus, like TMCL-IDE would be)."""
        from opentmcl.host import Client
        from opentmcl.host.transports.tcp import TcpTransport

        host, port = self.url.removeprefix("tcp://").rsplit(":", 1)
        client = Client(TcpTransport(host, int(port)), address=address, timeout=5.0)
        self.clients.append(client)
        return client.module(address)


@contextlib.contextmanager
def bench(*modules: tuple[str, int]) -> Iterator[Bench]:
    """Virtual modules (name, address) on one bus, served over TCP and by the dashboard."""
    importlib.import_module("starlette")
    importlib.import_module("uvicorn")
    from opentmcl import VirtualModule
    from opentmcl.server.app import Server
    from opentmcl.server.tcp import TcpServer
    from opentmcl.web import start_dashboard_for_bus

    server = Server([VirtualModule(name, address=a) for name, a in modules])
    tcp = server.add(TcpServer(server.bus, "127.0.0.1", 0))
    server.start()
    handle = None
    b = None
    try:
        handle = start_dashboard_for_bus(server.bus, "127.0.0.1", 0)
        b = Bench(handle, tcp.url, server)
        yield b
    finally:
        if b is not None:
            for c in b.clients:
                c.close()
        if handle is not None:
            handle.stop()
        server.stop()


def watched_page(browser, url: str, messages: list[str]):
    """A new page at `url` whose console errors/warnings and page errors land in `messages`."""
    page = browser.new_page()
    page.on("console", lambda m: messages.append(f"{m.type}: {m.text}") if m.type in ("error", "warning") else None)
    page.on("pageerror", lambda exc: messages.append(f"pageerror: {exc}"))
    page.goto(url)
    page.wait_for_selector("#axis-0", timeout=TIMEOUT_MS)
    return page


def open_view(page, name: str) -> None:
    """Click the view's entry in the navigation (docs/dashboard.md "Views")."""
    page.click(f"#views-nav a[data-view='{name}']")
    page.wait_for_selector(f"#view-{name}", state="visible", timeout=TIMEOUT_MS)


def wait_until(predicate, what: str, limit: float = TIMEOUT_MS / 2000, every: float = 0.05) -> None:
    """Poll `predicate` until true; fail naming `what` after `limit` seconds (a guard, not a timing)."""
    import time

    end = time.monotonic() + limit
    while not predicate():
        if time.monotonic() > end:
            raise AssertionError(f"not reached: {what}")
        time.sleep(every)
