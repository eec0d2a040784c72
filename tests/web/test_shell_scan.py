"""Module scan (issue 14 item 6, docs/dashboard.md "Module scan"): the addresses of the link that
answer command 136 type 0 (firmware version string, TMCM-6212 manual 3.6.36 / PD86-1180 4.6.39),
bounded to 1..255 (GP66 "Serial address 1...255", manual 5.1), one scan at a time, cancellable."""
from __future__ import annotations

import http.client
import json
import time

import pytest

from .shellkit import TIMEOUT_MS, bench, wait_until, watched_page


def call(handle, method: str, path: str, body: object = None, origin: str | None = None):
    """(status, JSON) of one request to the running dashboard, as the page sends it."""
    conn = http.client.HTTPConnection(handle.host, handle.port, timeout=30)
    headers = {"Content-Type": "application/json", "X-OpenTMCL": "1"}
    if origin:
        headers["Origin"] = origin
    conn.request(method, path, body=None if body is None else json.dumps(body).encode(), headers=headers)
    r = conn.getresponse()
    data = json.loads(r.read() or b"{}")
    conn.close()
    return r.status, data


def scan_to_end(handle, body: dict) -> dict:
    status, _ = call(handle, "POST", "/api/scan", body)
    assert status == 200
    out: dict = {}

    def ended() -> bool:
        out.update(call(handle, "GET", "/api/scan")[1])
        return not out["running"]
    wait_until(ended, "scan ended")
    return out


def test_scan_finds_the_modules_and_their_firmware(browser):
    """Two modules on the bus (addresses 1 and 2): scanning 1..4 lists both with their version strings
    ("6212V105", "1180V445"), and the link is said to have no baud rate (the server's bus)."""
    with bench(("TMCM-6212", 1), ("PD86-1180", 2)) as b:
        messages: list[str] = []
        page = watched_page(browser, b.handle.module_url(1), messages)
        try:
            page.fill("#scan-first", "1")
            page.fill("#scan-last", "4")
            page.fill("#scan-timeout", "0.05")
            page.click("#btn-scan")
            page.wait_for_function("document.getElementById('scan-progress').textContent.startsWith('done')",
                                   timeout=TIMEOUT_MS)
            assert page.inner_text("#scan-found-1").split("\t")[:3] == ["1", "TMCM-6212", "6212V105"]
            assert page.inner_text("#scan-found-2").split("\t")[:3] == ["2", "PD86-1180", "1180V445"]
            assert page.locator("#scan-results tr").count() == 3  # header + two modules, 3 and 4 silent
            assert "no baud rate" in page.inner_text("#scan-link")
            assert page.locator("#scan-bauds input").count() == 0
            page.click("#scan-open-2")
            page.wait_for_url(b.handle.module_url(2), timeout=TIMEOUT_MS)
            page.wait_for_function("document.getElementById('ov-version').textContent === '1180V445'",
                                   timeout=TIMEOUT_MS)
        finally:
            page.close()
        assert not messages, messages


def test_open_a_module_the_dashboard_did_not_serve(browser):
    """`opentmcl dashboard --to tcp://...` serves the module at address 1 only; the scan finds the
    PD86-1180 at 2, "open" serves it at /m/2/, and "MVP ABS, 0, 1000" from that page (PD86-1180
    manual 4.6.4) moves that module's motor, read back with GAP 1 over another TCP client."""
    import opentmcl
    from opentmcl.web import start_dashboard

    with bench(("TMCM-6212", 1), ("PD86-1180", 2)) as b:
        link = opentmcl.connect(b.url)
        handle = start_dashboard(link, "127.0.0.1", 0, url=b.url, on_stop=link.close)
        messages: list[str] = []
        try:
            page = watched_page(browser, handle.module_url(1), messages)
            page.fill("#scan-last", "3")
            page.fill("#scan-timeout", "0.05")
            page.click("#btn-scan")
            page.wait_for_selector("#scan-open-2", timeout=TIMEOUT_MS)
            page.click("#scan-open-2")
            page.wait_for_url(handle.module_url(2), timeout=TIMEOUT_MS)
            page.wait_for_function("document.getElementById('ov-module').textContent === 'PD86-1180'",
                                   timeout=TIMEOUT_MS)
            page.wait_for_selector("#module-select", state="visible", timeout=TIMEOUT_MS)  # now two modules
            page.fill("#console-input", "MVP ABS, 0, 1000")
            page.press("#console-input", "Enter")
            one = b.client(2)
            wait_until(lambda: one.client.reply(6, 1, 0).value == 1000, "PD86-1180 motor at 1000")
            page.close()
        finally:
            handle.stop()
        assert not messages, messages


@pytest.mark.parametrize(("body", "error"), [
    ({"first": 0, "last": 4}, "1..255"),
    ({"first": 1, "last": 256}, "1..255"),
    ({"first": 5, "last": 4}, "first <= last"),
    ({"first": 1, "last": 4, "timeout": 0.009}, "0.01..0.5"),
    ({"first": 1, "last": 4, "timeout": 0.51}, "0.01..0.5"),
    ({"first": 1, "last": 4, "bauds": [9600]}, "no baud rate"),
    ({"first": 1, "last": 4, "bauds": "9600"}, "list of baud rates"),
    ({"first": 1, "last": 4, "bauds": [9600, 19200, 9600]}, "9600 is given twice"),  # no longer scan
])
def test_scan_bounds_are_checked(body, error):
    """Addresses 1..255 (GP66), a time-out of 0.01..0.5 s per address (issue 28: a stop waits for
    at most one address), baud rates only on a serial link: anything else is a 400 with a one-line
    message and no scan starts."""
    with bench(("TMCM-6212", 1)) as b:
        status, data = call(b.handle, "POST", "/api/scan", body)
        assert status == 400 and error in data["error"] and "\n" not in data["error"]
        assert call(b.handle, "GET", "/api/scan")[1]["total"] == 0


def test_scan_edges_are_accepted():
    """The last valid values: address 255 alone with a 0.01 s time-out, and 255 itself answered
    when a module has GP66 = 255 (TMCM-6212 manual 5.1)."""
    with bench(("TMCM-6212", 255)) as b:
        out = scan_to_end(b.handle, {"first": 255, "last": 255, "timeout": 0.01})
        assert out["total"] == 1 and [f["address"] for f in out["found"]] == [255]


def test_one_scan_at_a_time_and_cancel():
    """A second scan while one runs is refused; cancel ends the running one between two requests
    (fewer addresses asked than the range holds). The dashboard talks to the bus over TCP, where
    an address without a module costs the scan its time-out (on the server's own bus the silence
    is known at once and the scan is over in a moment)."""
    from opentmcl.web import start_dashboard

    with bench(("TMCM-6212", 1)) as b:
        handle = start_dashboard(b.client(1), "127.0.0.1", 0, poll=False)
        try:
            assert call(handle, "POST", "/api/scan", {"first": 1, "last": 255, "timeout": 0.05})[0] == 200
            status, data = call(handle, "POST", "/api/scan", {"first": 1, "last": 2})
            assert status == 400 and "already running" in data["error"]
            assert call(handle, "POST", "/api/scan/cancel", {})[0] == 200
            out: dict = {}
            wait_until(lambda: not out.update(call(handle, "GET", "/api/scan")[1]) and not out["running"], "ended")
            assert out["cancelled"] and out["done"] < out["total"] == 255
            assert [f["address"] for f in out["found"]] == [1]
        finally:
            handle.stop()


def test_a_scan_of_the_servers_own_bus_does_not_wait_for_silent_addresses():
    """`serve --web`: the served modules answer while the request is handled, so an address
    without a module is known to be silent at once: scanning 1..255 at the longest time-out per
    address (0.5 s) ends long before 254 time-outs would (127 s; issue 28: a stop waited for such
    a time-out), and finds the two modules."""
    with bench(("TMCM-6212", 1), ("PD86-1180", 7)) as b:
        out = scan_to_end(b.handle, {"first": 1, "last": 255, "timeout": 0.5})
        assert out["done"] == out["total"] == 255 and not out["cancelled"]
        assert [f["address"] for f in out["found"]] == [1, 7]


@pytest.mark.parametrize("path", ["/api/scan", "/api/scan/cancel", "/api/scan/open"])
def test_scan_routes_refuse_a_foreign_origin(path):
    """docs/dashboard.md "Threat model": another site's Origin gets 403 on every mutating route."""
    with bench(("TMCM-6212", 1)) as b:
        status, data = call(b.handle, "POST", path, {"first": 1, "last": 2, "address": 1},
                            origin="http://evil.example")
        assert status == 403 and "Origin" in data["error"]
        assert call(b.handle, "GET", "/api/scan")[1]["total"] == 0


def test_open_refuses_an_address_the_scan_did_not_find():
    """Only a module the scan found can be opened."""
    with bench(("TMCM-6212", 1)) as b:
        status, data = call(b.handle, "POST", "/api/scan/open", {"address": 7})
        assert status == 400 and "found no module at address 7" in data["error"]


def test_serial_link_scans_baud_rates_and_returns_to_its_own():
    """A serial link (a real pseudo-terminal served by `opentmcl serve`) can change its baud rate:
    the scan asks each address at each rate chosen, GP65's 9600 and 19200 (manual 5.1), and the
    link is back at its own rate afterwards. (A pty passes bytes whatever the rate, so the module
    answers at both.) The one-module pty is a USB link that answers every address byte
    (docs/endpoints.md): GGP 66 (manual 3.6.8) shows address 2's answer was module 1's, so
    module 1 is listed once per rate."""
    import opentmcl
    from opentmcl import VirtualModule
    from opentmcl.server.app import Server
    from opentmcl.server.pty import PtyServer
    from opentmcl.web.scan import Scanner

    server = Server([VirtualModule("TMCM-6212", address=1)])
    pty = server.add(PtyServer(server.bus))
    server.start()
    try:
        module = opentmcl.connect(f"serial://{pty.path}?baud=9600")
        try:
            scanner = Scanner(module.client, lambda: [1])
            assert scanner.kind == "serial"
            scanner.start(1, 2, 0.05, [9600, 19200])
            end = time.monotonic() + 30
            while scanner.status()["running"] and time.monotonic() < end:
                time.sleep(0.05)
            st = scanner.status()
            assert [(f["address"], f["baud"], f["version"]) for f in st["found"]] == \
                [(1, 9600, "6212V105"), (1, 19200, "6212V105")]
            assert st["any_address"]  # the pty is a USB link (docs/endpoints.md): 2 answered for 1
            assert st["total"] == 4 and module.client.transport.baud == 9600
            assert module.firmware_version() == "6212V105"  # the link still works
        finally:
            module.close()
    finally:
        server.stop()


def test_a_scan_cancelled_while_it_waits_for_its_turn_asks_nothing_more():
    """Issue 28 item 2, "a running module scan holds the link": STOP ALL cancels the scan and then
    waits for its current address only. A scan that is waiting for its turn on the link when it is
    cancelled asks no address when the turn comes (before, it asked one more, and STOP ALL waited
    up to another time-out per address for it)."""
    from opentmcl.web.link import link_gate
    from opentmcl.web.scan import Scanner

    with bench(("TMCM-6212", 1)) as b:
        module = b.client(1)
        scanner = Scanner(module.client, lambda: [1])
        gate = link_gate(module.client)
        gate.acquire()  # another turn holds the link
        try:
            scanner.start(1, 255, 0.5)
            wait_until(lambda: gate.waiting() == 1, "the scan waiting for its turn")
            scanner.cancel()
        finally:
            gate.release()
        scanner.join(30)
        status = scanner.status()
        assert not status["running"] and status["cancelled"] and status["done"] == 0
