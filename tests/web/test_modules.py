"""Several modules on one bus behind one dashboard app: each at /m/ADDRESS/ (Starlette test client,
virtual time)."""
from __future__ import annotations

import pytest
from starlette.testclient import TestClient

from opentmcl import VirtualModule
from opentmcl.server.bus import ModuleBus
from opentmcl.web.app import create_app
from opentmcl.web.server import bus_dashboards

from .test_bus_transport import FakeClock


@pytest.fixture
def client():
    """A TMCM-6212 at address 1 and a PD86-1180 at address 2 on one bus, as `opentmcl serve` builds it."""
    clock = FakeClock()
    bus = ModuleBus([VirtualModule("TMCM-6212", address=1), VirtualModule("PD86-1180", address=2)], clock=clock)
    dashboards, close = bus_dashboards(bus)
    # The page's own requests: a loopback Host and the X-OpenTMCL header (web/guard.py).
    with TestClient(create_app(dashboards), base_url="http://127.0.0.1", headers={"X-OpenTMCL": "1"}) as c:
        c.clock = clock
        c.dashboards = dashboards
        yield c
    close()


def test_modules_are_listed_and_the_root_opens_the_first(client):
    """Each module answers at its own serial address (global parameter 66, TMCM-6212 manual 5.1,
    PD86-1180 manual 4.6.9 "SGP 66, 0, 3"): the listing names both, the root opens the first."""
    assert client.get("/api/modules").json() == [
        {"address": 1, "module": "TMCM-6212", "url": "/m/1/"},
        {"address": 2, "module": "PD86-1180", "url": "/m/2/"},
    ]
    assert client.get("/", follow_redirects=False).headers["location"] == "/m/1/"
    for address in (1, 2):
        page = client.get(f"/m/{address}/")
        assert page.status_code == 200 and 'id="module-select"' in page.text


def test_overview_of_the_second_module(client):
    """PD86-1180 manual 4.6.39, command 136 type 0: "Version string (8 characters, e.g. 1180V1.30)";
    this firmware manual is V4.45, so the module answers "1180V445". One axis (manual 4.6.4 MVP: "motor
    number is always O as only one motor is involved")."""
    ov = client.get("/m/2/api/overview").json()
    assert (ov["module"], ov["version"], ov["address"], ov["axes"]) == ("PD86-1180", "1180V445", 2, 1)
    assert client.get("/m/1/api/overview").json()["module"] == "TMCM-6212"


def test_console_move_reaches_only_the_addressed_module(client):
    """PD86-1180 manual 4.6.4 MVP ABS: "MVP ABS, 0, 1000" sent on module 2's page moves module 2's
    motor to 1000 (axis parameter 1, actual position); module 1's motor stays at 0."""
    r = client.post("/m/2/api/console", json={"line": "MVP ABS, 0, 1000"})
    assert r.status_code == 200 and r.json()["status"] == 100
    client.clock.t = 10.0  # long enough for 1000 microsteps at the default speed
    assert client.get("/m/2/api/state").json()["axes"][0]["position"] == 1000
    one = client.get("/m/1/api/state").json()["axes"][0]
    assert one["position"] == 0 and one["target_position"] == 0


def test_websocket_of_each_module(client):
    """Manual 3.6.36 / 4.6.39 command 136: each module's live connection greets with its own overview."""
    for address, name in ((1, "TMCM-6212"), (2, "PD86-1180")):
        with client.websocket_connect(f"ws://127.0.0.1/m/{address}/ws", subprotocols=["opentmcl"]) as ws:
            hello = ws.receive_json()
            assert hello["type"] == "hello" and hello["overview"]["module"] == name


def test_unknown_address_is_a_404_with_a_message(client):
    """Address 9 is a valid serial address (global parameter 66: 1...255, TMCM-6212 manual 5.1) but no
    module on this bus has it: a 404 that names the addresses there are."""
    for method, path in (("get", "/m/9/api/overview"), ("post", "/m/9/api/console"), ("get", "/m/x/")):
        r = getattr(client, method)(path, **({"json": {"line": "GAP 1, 0"}} if method == "post" else {}))
        assert r.status_code == 404
        error = r.json()["error"]
        assert "no module at address" in error and "addresses: 1, 2" in error


def test_one_address_can_be_chosen_and_duplicates_are_refused(client):
    """Modules on one bus have distinct serial addresses (global parameter 66, TMCM-6212 manual 5.1):
    one may be chosen; two dashboards for one address are refused."""
    bus = ModuleBus([VirtualModule("TMCM-6212", address=1), VirtualModule("PD86-1180", address=2)],
                    clock=FakeClock())
    only, close = bus_dashboards(bus, address=2)
    try:
        assert [d.profile.name for d in only] == ["PD86-1180"]
        with pytest.raises(ValueError, match="address 2"):
            create_app([*only, *only])
    finally:
        close()
    with pytest.raises(ValueError, match="address 7"):
        bus_dashboards(bus, address=7)
