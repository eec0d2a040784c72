"""Helpers of the tuning-bench browser tests (test_bench_*.py, issue 31): virtual modules with a world
scenario on one served bus, a TCP endpoint of the same bus (the test's second connection, which
confirms every effect with GAP/GGP), and a fresh page on one module."""
from __future__ import annotations

import contextlib
import importlib
from collections.abc import Iterator
from pathlib import Path

from .shellkit import TIMEOUT_MS, Bench, open_view, wait_until

ROOT = Path(__file__).resolve().parents[2]
STAGE = str(ROOT / "examples" / "scenarios" / "tmcm6212_stage.toml")  # axis 0: switches at -50000, 50000, home 10000

__all__ = ["STAGE", "TIMEOUT_MS", "Bench", "console_has", "fresh_page", "open_view", "served", "store_program",
           "wait_until"]


@contextlib.contextmanager
def served(*modules: tuple[str, int, str | None]) -> Iterator[Bench]:
    """Virtual modules (name, address, scenario file or None) on one bus, served over TCP and by the
    dashboard, in this process (so the dashboard may reach their worlds)."""
    importlib.import_module("starlette")
    importlib.import_module("uvicorn")
    from opentmcl import VirtualModule
    from opentmcl.server.app import Server
    from opentmcl.server.tcp import TcpServer
    from opentmcl.web import start_dashboard_for_bus

    server = Server([VirtualModule(name, address=a, scenario=s) for name, a, s in modules])
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


@contextlib.contextmanager
def fresh_page(browser, b: Bench, address: int = 1, view: str | None = None):
    """A page on module `address` with no unit settings from an earlier test (neither in this
    browser's storage for the dashboard's origin nor on the dashboard); yields (page, messages:
    console errors and warnings)."""
    messages: list[str] = []
    page = browser.new_page()
    try:
        page.goto(f"{b.handle.url}static/favicon.svg")  # the origin, without the page's scripts
        page.evaluate("localStorage.clear()")
        for d in b.handle.dashboards:
            d.units.clear()
        page.on("console", lambda m: messages.append(f"{m.type}: {m.text}") if m.type in ("error", "warning") else None)
        page.on("pageerror", lambda exc: messages.append(f"pageerror: {exc}"))
        page.goto(b.handle.module_url(address))
        page.wait_for_selector("#axis-0", timeout=TIMEOUT_MS)
        page.wait_for_function("window.OpenTMCL.units && window.OpenTMCL.units.info !== null", timeout=TIMEOUT_MS)
        if view:
            open_view(page, view)
        yield page, messages
    finally:
        page.close()


def store_program(b, instructions) -> None:
    """Download (132, the instructions, 133; manual 3.6.36) as another host would, but in one turn
    of the bus: a request of the dashboard's polling sent between 132 and 133 would be stored in the
    program ("All following commands ... are not executed but stored")."""
    vm = b.server.bus.modules[0]  # the first module of the bus
    with b.server.bus.lock:
        assert vm.request(132, 0, 0, 0).status == 100
        for ins in instructions:
            assert vm.request(*ins).status == 101
        assert vm.request(133, 0, 0, 0).status == 100


def console_has(page, text: str) -> None:
    """Wait until the console log shows `text`."""
    page.wait_for_function(f"document.getElementById('console-log').textContent.includes({text!r})",
                           timeout=TIMEOUT_MS)
