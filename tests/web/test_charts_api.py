"""The chart sampler (web/sampler.py, docs/dashboard-charts.md): subscriptions, rows read over the
wire (GAP/GGP/GIO, TMCM-6212 manual 3.6.6, 3.6.8, 3.6.15) and its bounds. `tick()` is called
directly on a virtual module in virtual time; the endpoints go through the guarded app."""
from __future__ import annotations

import pytest
from starlette.testclient import TestClient

from opentmcl.web import sampler as S
from opentmcl.web.app import create_app


class Clock:
    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


@pytest.fixture
def sampler(dash):
    s = S.Sampler(dash, clock=Clock())
    s._ensure_thread = lambda: None  # the test ticks by hand
    return s


def test_catalogue_lists_readable_parameters_and_inputs(sampler):
    """Manual 4.1: 206 "Actual load value" (R) can be charted, as can global 132 "tick timer" (5.1)
    and the inputs; write-only parameters cannot."""
    cat = sampler.catalogue()
    assert any(p["number"] == 206 for p in cat["axis"])
    assert any(p["number"] == 132 and p["bank"] == 0 for p in cat["global"])
    assert cat["io"] and cat["axes"] == 6 and cat["max_series"] == S.MAX_SERIES


def test_rows_carry_the_subscribed_values_read_over_the_wire(dash, sampler):
    """A row per tick: [seq, t, values in the order subscribed]; SAP on the wire shows in the next
    row (manual 3.6.5); GIO of an input (3.6.15) is a series too."""
    series = [("axis", 1, 4), ("axis", 0, 206), ("global", 0, 77)]
    cid = sampler.subscribe(None, series)
    dash.module.request(5, 4, 1, 4321)
    sampler.tick()
    dash.module.request(5, 4, 1, 4322)
    sampler.tick()
    out = sampler.samples(cid, 0)
    assert out["series"] == ["axis:1:4", "axis:0:206", "global:0:77"]
    assert [r[2] for r in out["rows"]] == [4321, 4322]
    assert out["rows"][0][3] == dash.module.reply(6, 206, 0).value
    assert [r[0] for r in sampler.samples(cid, out["rows"][0][0])["rows"]] == [out["rows"][1][0]]
    io = next(iter(sorted(dash.profile.io)))
    sampler.subscribe(cid, [("io", *io)])
    sampler.tick()
    assert sampler.samples(cid, 0)["rows"][-1][2] == dash.module.reply(15, io[1], io[0]).value


def test_series_bound_edges(sampler):
    """At most MAX_SERIES (16) series per client: 16 are taken, 17 refused."""
    sampler.subscribe(None, [("axis", a % 6, 4) for a in range(S.MAX_SERIES)])
    with pytest.raises(S.DashboardError, match="16"):
        sampler.subscribe(None, [("axis", 0, 4)] * (S.MAX_SERIES + 1))


def test_client_bound_and_idle_expiry(sampler):
    """At most MAX_CLIENTS; a client that has not polled for IDLE_SECONDS is dropped, which frees
    a place, and with no client left a tick reports none."""
    ids = [sampler.subscribe(None, [("axis", 0, 206)]) for _ in range(S.MAX_CLIENTS)]
    with pytest.raises(S.DashboardError, match="at most"):
        sampler.subscribe(None, [("axis", 0, 206)])
    sampler.clock.now = S.IDLE_SECONDS  # exactly the limit: still kept
    sampler.samples(ids[0], 0)
    assert sampler.tick() == S.MAX_CLIENTS
    sampler.clock.now = S.IDLE_SECONDS + 0.001
    assert sampler.tick() == 1  # only ids[0] polled
    with pytest.raises(S.DashboardError, match="subscribe again"):
        sampler.samples(ids[1], 0)
    sampler.clock.now = 2 * S.IDLE_SECONDS + 0.01
    assert sampler.tick() == 0


@pytest.mark.parametrize("series", [("axis", 6, 4), ("axis", 0, 99), ("global", 1, 77), ("io", 9, 9),
                                    ("motor", 0, 1), ("axis", True, 4), ("axis", 0, "4")])
def test_series_that_cannot_be_read_are_refused(sampler, series):
    """Manual 1: axes 0..5; parameters the profile lacks; unknown kinds; non-integers."""
    with pytest.raises(S.DashboardError):
        sampler.check(*series)


def test_history_is_bounded(sampler):
    cid = sampler.subscribe(None, [("axis", 0, 4)])
    for _ in range(S.ROWS_KEPT + 3):
        sampler.tick()
    rows = sampler.samples(cid, 0)["rows"]
    assert len(rows) == S.ROWS_KEPT and rows[0][0] == 4


def test_endpoints_stream_samples_of_the_load_value(dash):
    """Through the app: subscribe to AP206 of axis 0 (manual 4.1 "Actual load value") and poll
    until the server's sampling thread delivered rows; 17 series and an unknown client are 400."""
    with TestClient(create_app(dash), base_url="http://127.0.0.1", headers={"X-OpenTMCL": "1"}) as c:
        r = c.post("/m/1/api/charts/subscribe", json={"series": [{"kind": "axis", "index": 0, "number": 206}]})
        assert r.status_code == 200, r.text
        cid = r.json()["client"]
        assert r.json()["series"] == ["axis:0:206"]
        rows = []
        for _ in range(2000):  # bounded: the thread samples 25 times a second
            rows = c.get(f"/m/1/api/charts/samples?client={cid}&since=0").json()["rows"]
            if len(rows) >= 3:
                break
            dash.closed.wait(0.01)
        assert len(rows) >= 3 and all(r[2] == dash.module.reply(6, 206, 0).value for r in rows)
        too_many = [{"kind": "axis", "index": 0, "number": 206}] * 17
        assert c.post("/m/1/api/charts/subscribe", json={"series": too_many}).status_code == 400
        assert c.post("/m/1/api/charts/subscribe", json={"series": [5]}).status_code == 400
        assert c.get("/m/1/api/charts/samples?client=nope").status_code == 400
        assert c.get("/m/1/api/charts/samples?client=x&since=y").status_code == 400
        assert c.get("/m/1/api/charts/series").json()["axes"] == 6


def test_vendored_uplot_is_served_with_its_licence(dash):
    """The vendored library ships in the package and is served (static/vendor/uplot/README.md names
    version and origin); the page loads it before app.js and links its style sheet."""
    with TestClient(create_app(dash), base_url="http://127.0.0.1") as c:
        for name in ("uPlot.iife.min.js", "uPlot.min.css", "LICENSE", "README.md"):
            assert c.get(f"/static/vendor/uplot/{name}").status_code == 200, name
        assert "MIT" in c.get("/static/vendor/uplot/LICENSE").text
        assert "1.6.32" in c.get("/static/vendor/uplot/README.md").text
        page = c.get("/m/1/").text
        assert page.index("vendor/uplot/uPlot.iife.min.js") < page.index("static/app.js")
        assert "vendor/uplot/uPlot.min.css" in page
        for name in ("params.css", "charts.css"):
            assert c.get(f"/static/{name}").status_code == 200


def test_row_numbers_are_shared_and_a_new_subscription_keeps_them(sampler):
    """seq counts the sampler's ticks for every client: a client that changes its series gets only
    rows after the change, numbered after every row it saw, so a page's `since` stays valid."""
    a = sampler.subscribe(None, [("axis", 0, 4)])
    sampler.tick()
    b = sampler.subscribe(None, [("axis", 1, 4)])
    sampler.tick()
    seen = sampler.samples(a, 0)["rows"][-1][0]
    assert sampler.samples(b, 0)["rows"][-1][0] == seen
    sampler.subscribe(a, [("axis", 2, 4)])
    assert sampler.samples(a, seen)["rows"] == []
    sampler.tick()
    assert [r[0] for r in sampler.samples(a, seen)["rows"]] == [seen + 1]
