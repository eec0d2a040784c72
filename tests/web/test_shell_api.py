"""The shell's HTTP routes without a browser (Starlette test client, virtual modules in virtual
time): stop-all across modules when one fails, and the motion read-out's bounds."""
from __future__ import annotations

import importlib

import pytest

importlib.import_module("starlette")
from starlette.testclient import TestClient  # noqa: E402

import opentmcl  # noqa: E402
from opentmcl.web.app import create_app  # noqa: E402
from opentmcl.web.service import Dashboard  # noqa: E402


def dashboard(url: str) -> Dashboard:
    module = opentmcl.connect(url)
    t = module.client.transport
    return Dashboard(module, vm=t.module, vm_lock=t.lock)


@pytest.fixture
def two():
    """A TMCM-6212 at address 1 whose link is gone, and a working PD86-1180 at address 2."""
    broken, good = dashboard("sim://TMCM-6212"), dashboard("sim://PD86-1180?address=2")
    broken.module.client.close()
    with TestClient(create_app([broken, good]), base_url="http://127.0.0.1", headers={"X-OpenTMCL": "1"}) as c:
        yield c, broken, good
    good.module.client.close()


def test_stop_all_goes_on_after_a_module_that_fails(two):
    """PD86-1180 manual 4.6.1 ROR turns its motor; stop-all meets the TMCM-6212 first, whose link is
    closed: that module is reported with its error, and the PD86-1180 still gets MST (4.6.3: target
    speed AP2 becomes 0)."""
    client, broken, good = two
    good.module.request(1, 0, 0, 500)
    r = client.post("/api/stop-all", json={})
    assert r.status_code == 200
    out = r.json()
    assert not out["ok"]
    first, second = out["modules"]
    assert (first["address"], first["ok"], first["axes_stopped"]) == (1, False, [])
    assert first["error"] and len(first["errors"]) == 1 + 6  # program stop and six MSTs all tried
    assert (second["address"], second["module"], second["ok"], second["axes_stopped"]) == (2, "PD86-1180", True, [0])
    assert good.module.reply(6, 2, 0).value == 0


def test_motion_read_out_bounds():
    """TMCM-6212 manual 1: six axes, 0..5. Axis 5 (the last) is read; 6 is a 400 with one line."""
    d = dashboard("sim://TMCM-6212")
    with TestClient(create_app(d), base_url="http://127.0.0.1") as c:
        r = c.get("/m/1/api/motion/5")
        assert r.status_code == 200
        info = r.json()
        assert (info["unit"], info["velocity_min"], info["velocity_max"], info["rfs_status"]) == ("pps", 0, 7999774, 0)
        r = c.get("/m/1/api/motion/6")
        assert r.status_code == 400 and "axes 0..5" in r.json()["error"]
        assert c.get("/m/1/api/motion/x").status_code == 400
    d.module.client.close()
