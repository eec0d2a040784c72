"""Fixtures for the dashboard tests: a virtual module on the wall clock behind a running dashboard,
and headless Chromium from Debian's `chromium` package driven by Playwright."""
from __future__ import annotations

import importlib
from pathlib import Path

import pytest

from tests.browser import CHROMIUM, CHROMIUM_ARGS  # noqa: F401 (make_doc_screenshots imports them here)

ARTIFACTS = Path(__file__).resolve().parents[2] / "test-artifacts"


@pytest.fixture
def dash():
    """A `Dashboard` of one virtual TMCM-6212 (sim://, virtual clock); its sampling ends afterwards."""
    import opentmcl
    from opentmcl.web.service import Dashboard

    module = opentmcl.connect("sim://TMCM-6212")
    transport = module.client.transport
    d = Dashboard(module, vm=transport.module, vm_lock=transport.lock)
    yield d
    d.closed.set()  # ends a sampling thread
    module.close()


@pytest.fixture
def client():
    """A `TestClient` of one virtual TMCM-6212's dashboard app, sending what the page itself sends:
    a loopback Host and the X-OpenTMCL header (web/guard.py). `client.dash`, `client.module`."""
    from starlette.testclient import TestClient

    import opentmcl
    from opentmcl.web.app import create_app
    from opentmcl.web.service import Dashboard

    module = opentmcl.connect("sim://TMCM-6212")
    transport = module.client.transport
    dash = Dashboard(module, vm=transport.module, vm_lock=transport.lock)
    with TestClient(create_app(dash), base_url="http://127.0.0.1", headers={"X-OpenTMCL": "1"}) as c:
        c.dash, c.module = dash, module
        yield c
    dash.closed.set()
    module.close()


@pytest.fixture
def served():
    """A running dashboard for sim://TMCM-6212 (real clock); yields the handle."""
    importlib.import_module("starlette")
    importlib.import_module("uvicorn")
    import opentmcl
    from opentmcl.web import start_dashboard

    module = opentmcl.connect("sim://TMCM-6212?clock=real")
    transport = module.client.transport
    handle = start_dashboard(module, "127.0.0.1", 0, vm=transport.module, vm_lock=transport.lock,
                             url="sim://TMCM-6212", on_stop=module.close)
    try:
        yield handle
    finally:
        handle.stop()


@pytest.fixture
def served_bus():
    """A running dashboard for a bus with a TMCM-6212 at address 1 and a PD86-1180 at address 2
    (real clock), as `opentmcl serve --web` starts it; yields the handle."""
    importlib.import_module("starlette")
    importlib.import_module("uvicorn")
    from opentmcl import VirtualModule
    from opentmcl.server.bus import ModuleBus
    from opentmcl.web import start_dashboard_for_bus

    bus = ModuleBus([VirtualModule("TMCM-6212", address=1), VirtualModule("PD86-1180", address=2)])
    handle = start_dashboard_for_bus(bus, "127.0.0.1", 0)
    try:
        yield handle
    finally:
        handle.stop()


@pytest.fixture
def page(browser, served):
    ARTIFACTS.mkdir(exist_ok=True)
    page = browser.new_page()
    errors: list[str] = []
    page.on("pageerror", lambda exc: errors.append(str(exc)))
    page.goto(served.url)
    page.wait_for_selector("#axis-0")
    yield page
    page.close()
    assert not errors, f"JavaScript errors on the page: {errors}"
