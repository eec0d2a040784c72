"""End-to-end: the dashboard page in headless Chromium against a virtual TMCM-6212.

Screenshots go to test-artifacts/ (CI keeps them). Skipped without /usr/bin/chromium or playwright.
"""
from __future__ import annotations

from .benchkit import console_has
from .conftest import ARTIFACTS
from .shellkit import bench, wait_until, watched_page

TIMEOUT_MS = 60000  # only a guard against hanging: the tests wait for a state, they do not time anything


def test_single_module_has_no_selector(page, served):
    """One module: the page is at /m/ADDRESS/ (global parameter 66, default 1, TMCM-6212 manual 5.1)
    and the module selector stays hidden."""
    assert page.url == served.module_url(1)
    page.wait_for_function("document.getElementById('module-select').options.length === 1", timeout=TIMEOUT_MS)
    assert not page.is_visible("#module-select")


def open_view(page, name: str) -> None:
    """Click the view's entry in the navigation (docs/dashboard.md "Views") and wait until it shows."""
    page.click(f"#views-nav a[data-view='{name}']")
    page.wait_for_selector(f"#view-{name}", state="visible", timeout=TIMEOUT_MS)


def move_from_console(page, position: int) -> None:
    """Type "MVP ABS, 0, <position>" into the console; wait for status 100 and the axis card."""
    page.fill("#console-input", f"MVP ABS, 0, {position}")
    page.press("#console-input", "Enter")
    page.wait_for_function("document.getElementById('console-log').textContent.includes('status 100')",
                           timeout=TIMEOUT_MS)
    page.wait_for_function(f"document.getElementById('axis-0-position').textContent === '{position}'",
                           timeout=TIMEOUT_MS)


def test_page_shows_module_overview(page, served):
    """TMCM-6212 manual 3.6.36 command 136: the overview shows the version string "6212V105" and the
    module's six axes (manual 1 "Features": six axes)."""
    page.wait_for_function("document.getElementById('ov-version').textContent === '6212V105'", timeout=TIMEOUT_MS)
    assert page.inner_text("#ov-module") == "TMCM-6212"
    assert page.locator(".axis-card").count() == 6
    page.wait_for_function("document.getElementById('ov-connection').textContent === 'connected'",
                           timeout=TIMEOUT_MS)
    page.screenshot(path=str(ARTIFACTS / "dashboard-overview.png"), full_page=True)


def test_console_move_changes_the_position(page, served):
    """Manual 3.6.4 MVP ABS: "MVP ABS, 0, 51200" moves motor 0 to 51200; the axis card and the live
    chart follow the actual position (axis parameter 1) until it equals the target."""
    move_from_console(page, 51200)
    points = page.evaluate("window.dashboard.charts.position.series[0].y")
    assert points[-1] == 51200 and min(points) < 51200  # the chart saw the motor on its way
    assert served.dashboard.module.axes[0].position == 51200
    page.screenshot(path=str(ARTIFACTS / "dashboard-after-move.png"), full_page=True)


def test_console_shows_status_text_of_an_error(page):
    """Manual 3.2 status 4 "Invalid value": SAP 4 beyond 7999774 (manual 4.1, parameter 4 range)."""
    page.fill("#console-input", "SAP 4, 0, 9999999")
    page.press("#console-input", "Enter")
    page.wait_for_function("document.getElementById('console-log').textContent.includes('Invalid value')",
                           timeout=TIMEOUT_MS)


def test_edit_axis_parameter(page, served):
    """Manual 3.6.5 SAP: editing "Maximum positioning speed" (axis parameter 4) writes it to the module."""
    open_view(page, "parameters")
    page.wait_for_selector("#param-axis-4")
    page.fill("#param-axis-4", "20000")
    page.press("#param-axis-4", "Enter")
    page.wait_for_selector("#param-axis-4.saved", timeout=TIMEOUT_MS)
    assert served.dashboard.module.axes[0].get(4) == 20000
    title = page.locator("#param-axis-table td[title]").first.get_attribute("title")
    assert title  # the manual's description on hover


def test_switch_output_and_force_input(page, served):
    """TMCM-6212 manual 3.6.12 SIO / 3.6.13 GIO: OUT2 (bank 2) is switched from the page; the
    virtual module's IN1 (bank 0) is forced to 1 and read back by GIO."""
    open_view(page, "io")
    page.check("#io-out-2-2")
    page.wait_for_function("document.getElementById('io-val-2-2').textContent === '1'", timeout=TIMEOUT_MS)
    assert served.dashboard.module.output(2) == 1
    page.fill("#io-force-0-1", "1")
    page.locator("#io-force-0-1 + button").click()
    page.wait_for_function("document.getElementById('io-val-0-1').textContent === '1 (forced)'",
                           timeout=TIMEOUT_MS)
    assert served.dashboard.module.digital_input(1) == 1


def test_io_actions_are_logged_in_the_console(browser):
    """Issue 31 item 6: like the motion tools, I/O actions show in the console: SIO 1, 2, 1 (manual
    3.6.12) with the value read back, and forcing/releasing an input of the virtual module; GIO over
    a TCP connection of the same bus (3.6.13) confirms them."""
    with bench(("TMCM-6212", 1)) as b:
        m = b.client(1)
        messages: list[str] = []
        page = watched_page(browser, b.handle.module_url(1), messages)
        try:
            open_view(page, "io")
            page.click("#io-out-2-1")
            console_has(page, "> SIO 1, 2, 1")
            console_has(page, "OUT1 = 1")
            assert m.client.reply(15, 1, 2).value == 1
            page.fill("#io-force-0-2", "1")
            page.click("#io-force-0-2 + button")
            console_has(page, "> force IN2 (bank 0, port 2) to 1 (virtual module)")
            wait_until(lambda: m.client.reply(15, 2, 0).value == 1, "IN2 forced to 1")
            page.click("#io-force-0-2 + button + button")
            console_has(page, "> release IN2 (bank 0, port 2; virtual module)")
            wait_until(lambda: m.client.reply(15, 2, 0).value == 0, "IN2 released")
            page.click("#io-out-2-1")
            console_has(page, "> SIO 1, 2, 0")
        finally:
            page.close()
        assert not messages, messages


def test_bus_with_two_modules_has_a_selector(browser, served_bus):
    """Two modules on one bus, at serial addresses 1 and 2 (global parameter 66, TMCM-6212 manual 5.1).
    Choosing the PD86-1180 opens its page: command 136 gives its version (PD86-1180 manual 4.6.39,
    "1180V445" for firmware V4.45) and it has one motor (manual 4.6.4 MVP: "only one motor is
    involved"). "MVP ABS, 0, 1000" there moves that motor to 1000; the TMCM-6212's motor 0 stays."""
    ARTIFACTS.mkdir(exist_ok=True)
    page = browser.new_page()
    errors: list[str] = []
    page.on("pageerror", lambda exc: errors.append(str(exc)))
    try:
        page.goto(served_bus.url)
        page.wait_for_selector("#axis-0")
        page.wait_for_selector("#module-select", state="visible", timeout=TIMEOUT_MS)
        assert page.inner_text("#ov-module") == "TMCM-6212"
        labels = page.locator("#module-select option").all_inner_texts()
        assert labels == ["TMCM-6212 (address 1)", "PD86-1180 (address 2)"]
        page.select_option("#module-select", label="PD86-1180 (address 2)")
        page.wait_for_url(served_bus.module_url(2), timeout=TIMEOUT_MS)
        page.wait_for_function("document.getElementById('ov-version').textContent === '1180V445'",
                               timeout=TIMEOUT_MS)
        assert page.inner_text("#ov-module") == "PD86-1180" and page.inner_text("#ov-address") == "2"
        assert page.locator(".axis-card").count() == 1
        assert page.eval_on_selector("#module-select", "s => s.value") == "/m/2/"
        move_from_console(page, 1000)
        first, second = served_bus.dashboards
        assert second.module.axes[0].position == 1000
        assert first.module.axes[0].position == 0 and first.module.axes[0].target_position == 0
        page.screenshot(path=str(ARTIFACTS / "dashboard-two-modules.png"), full_page=True)
    finally:
        page.close()
    assert not errors, f"JavaScript errors on the page: {errors}"


def test_the_page_sends_the_header_and_the_subprotocol(page, served):
    """The page's own requests carry what the guard asks for (docs/dashboard.md "Threat model"):
    X-OpenTMCL: 1 on a POST, and a console command (manual 3.6.4 MVP ABS) goes through."""
    with page.expect_request("**/api/console") as info:
        page.fill("#console-input", "MVP ABS, 0, 3200")
        page.press("#console-input", "Enter")
    assert info.value.headers.get("x-opentmcl") == "1"
    page.wait_for_function("document.getElementById('console-log').textContent.includes('status 100')",
                           timeout=TIMEOUT_MS)
    assert served.dashboard.module.axes[0].target_position == 3200
    page.wait_for_function("document.getElementById('ov-connection').textContent === 'connected'",
                           timeout=TIMEOUT_MS)  # the WebSocket opened with the subprotocol


LOOP = "    CALC LOAD, 0\nLoop:\n    CALC ADD, 1\n    JA Loop\n"


def evil_site(dashboard: str):
    """Another web site (its own origin, evil.opentmcl.test:PORT) whose page tries to drive the
    dashboard: a form that POSTs to program/run, a no-cors fetch and a fetch with the header."""
    import http.server
    import threading

    html = f"""<!doctype html><title>evil</title>
<form id="f" method="POST" action="{dashboard}m/1/api/program/run"><input name="x" value="1"></form>
<script>
window.results = {{}};
const body = JSON.stringify({{line: "MVP ABS, 0, 5555"}});
fetch("{dashboard}m/1/api/console", {{method: "POST", mode: "no-cors", body,
      headers: {{"Content-Type": "text/plain"}}}}).then(r => results.nocors = r.type, () => results.nocors = "error");
fetch("{dashboard}m/1/api/console", {{method: "POST", body,
      headers: {{"Content-Type": "application/json", "X-OpenTMCL": "1"}}}})
  .then(r => results.cors = r.status, () => results.cors = "blocked");
</script>""".encode()

    class Handler(http.server.BaseHTTPRequestHandler):
        def do_GET(self):
            self.send_response(200)
            self.send_header("Content-Type", "text/html")
            self.send_header("Content-Length", str(len(html)))
            self.end_headers()
            self.wfile.write(html)

        def log_message(self, *args):
            pass

    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), Handler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    return server


def test_a_page_on_another_origin_cannot_post(browser, served):
    """Issue 11 problem 1: a page on another site submits a form to program/run (manual 3.6.36
    command 129) and fetches the console with MVP ABS (3.6.4). The form gets 403, the fetches are
    refused (the one with the header never passes the CORS preflight); the program does not run
    and the motor's target stays."""
    served.dashboard.download(LOOP)
    evil = evil_site(served.url)
    page = browser.new_page()
    try:
        page.goto(f"http://evil.opentmcl.test:{evil.server_address[1]}/")
        page.wait_for_function("window.results.nocors !== undefined && window.results.cors !== undefined",
                               timeout=TIMEOUT_MS)
        assert page.evaluate("window.results.cors") == "blocked"
        with page.expect_navigation() as nav:
            page.evaluate("document.getElementById('f').submit()")
        assert nav.value.status == 403
        assert "Origin" in page.inner_text("body")
        assert served.dashboard.program_state()["mode_name"] != "run"
        assert served.dashboard.module.axes[0].target_position != 5555
    finally:
        page.close()
        evil.shutdown()
        evil.server_close()


def test_a_rebound_name_cannot_use_the_dashboard(browser, served):
    """Issue 11 problem 2, DNS rebinding: rebind.opentmcl.test resolves to 127.0.0.1, so a page under
    that name is same-origin with the dashboard for the browser. The page, the global parameters
    (manual 3.6.8 GGP) and a console MVP ABS (3.6.4) are all refused with 403."""
    port = served.port
    page = browser.new_page()
    try:
        response = page.goto(f"http://rebind.opentmcl.test:{port}/m/1/")
        assert response.status == 403 and "Host" in page.inner_text("body")
        statuses = page.evaluate("""async () => [
            (await fetch('/m/1/api/params/global')).status,
            (await fetch('/m/1/api/console', {method: 'POST', body: JSON.stringify({line: 'MVP ABS, 0, 6666'}),
                          headers: {'Content-Type': 'application/json', 'X-OpenTMCL': '1'}})).status]""")
        assert statuses == [403, 403]
        assert served.dashboard.module.axes[0].target_position != 6666
    finally:
        page.close()


def test_the_page_works_on_a_lan_name_with_the_token(browser):
    """--allow-host for a LAN (docs/dashboard.md): the page opened once with the printed ?token= URL
    keeps the token in its cookie; the console (manual 3.6.4 MVP ABS) and the live WebSocket work
    under the allowed name, and the same name without the token is refused."""
    import opentmcl
    from opentmcl.web import start_dashboard

    module = opentmcl.connect("sim://TMCM-6212?clock=real")
    t = module.client.transport
    name = "box.opentmcl.test"
    with start_dashboard(module, "127.0.0.1", 0, vm=t.module, vm_lock=t.lock, on_stop=module.close,
                         allow_hosts=[name]) as handle:
        page = browser.new_page()
        errors: list[str] = []
        page.on("pageerror", lambda exc: errors.append(str(exc)))
        try:
            assert page.goto(f"http://{name}:{handle.port}/m/1/").status == 403
            page.goto(f"http://{name}:{handle.port}/?token={handle.token}")
            page.wait_for_selector("#axis-0")
            assert page.url == f"http://{name}:{handle.port}/m/1/"  # the token left the address bar
            move_from_console(page, 2400)
            page.wait_for_function("document.getElementById('ov-connection').textContent === 'connected'",
                                   timeout=TIMEOUT_MS)
            assert handle.dashboard.module.axes[0].target_position == 2400
        finally:
            page.close()
            page.context.clear_cookies()
    assert not errors, f"JavaScript errors on the page: {errors}"
