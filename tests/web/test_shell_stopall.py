"""Stop-all (issue 14 item 1, docs/dashboard.md "Stop all"): the header's STOP ALL button and the
Escape key stop the program and every axis of every module on the bus; its result chip stays in
the header until the program or a motor runs again (issue 31 item 6). The motors are watched
through a TCP client of the same bus, as TMCL-IDE would watch them."""
from __future__ import annotations

import pytest

from .benchkit import store_program
from .shellkit import ACTUAL_SPEED, TIMEOUT_MS, bench, open_view, wait_until, watched_page

# Keeps turning motor 2: a stop-all that left the program running would see it start again.
PROGRAM = "Loop:\n    ROR 2, 30000\n    WAIT TICKS, 0, 5\n    JA Loop\n"


def _program_running(module) -> None:
    from opentmcl.host.loader import Loader, VerifyError
    from opentmcl.lang import assemble

    loader = Loader(module)
    for attempt in range(3):  # the dashboard polls the same module meanwhile: in download mode
        try:                  # (132, manual 3.6.36) its GGP/GAP are stored too, the verify sees it
            loader.download(assemble(PROGRAM, module="TMCM-6212").instructions)
            break
        except VerifyError:
            if attempt == 2:
                raise
    loader.run()


def _speed(module, axis: int) -> int:
    return module.client.reply(6, ACTUAL_SPEED, axis, address=module.address).value


@pytest.mark.parametrize("how", ["escape-in-input", "click"])
def test_stop_all_stops_three_rotating_axes_and_the_program(browser, how):
    """TMCM-6212 manual 3.6.1 ROR turns motors 0 and 1 of the TMCM-6212 and motor 0 of the
    PD86-1180 (4.6.1); a program (3.6.36 command 129 runs it) keeps turning motor 2 (ROR in a loop).
    Escape, with the focus in the console's input, or a click on STOP ALL: GAP 3 "actual speed"
    (manual 4.1) falls to 0 on every axis of both modules and command 135 reports the program
    stopped (mode 0); the header shows each module's result."""
    with bench(("TMCM-6212", 1), ("PD86-1180", 2)) as b:
        six, one = b.client(1), b.client(2)
        six.request(1, 0, 0, 30000)
        six.request(1, 0, 1, 20000)
        one.request(1, 0, 0, 1000)
        _program_running(six)
        spinning = [(six, 0), (six, 1), (six, 2), (one, 0)]
        wait_until(lambda: all(_speed(m, a) != 0 for m, a in spinning), "four axes turning")
        messages: list[str] = []
        page = watched_page(browser, b.handle.module_url(1), messages)
        try:
            if how == "click":
                open_view(page, "charts")  # the button is there on every view
                page.click("#btn-stop-all")
            else:
                page.click("#console-input")
                page.keyboard.press("Escape")
            page.wait_for_function("document.getElementById('stop-all-result').className === 'ok'",
                                   timeout=TIMEOUT_MS)
            shown = page.inner_text("#stop-all-result")
            assert "TMCM-6212 @1: stopped" in shown and "PD86-1180 @2: stopped" in shown
            assert "STOP ALL" in page.inner_text("#console-log")
        finally:
            page.close()
        from opentmcl.host.loader import Loader

        assert Loader(six).status().mode == 0  # 135 type 0: 0 = stop
        wait_until(lambda: all(_speed(m, a) == 0 for m, a in [(six, n) for n in range(6)] + [(one, 0)]),
                   "every axis at speed 0")
        assert Loader(six).status().mode == 0
        assert not messages, messages


def test_stop_all_route_refuses_a_foreign_origin():
    """docs/dashboard.md "Threat model": a POST with another site's Origin is refused with 403 before
    the route runs, and the motor (manual 3.6.1 ROR) keeps its target speed; the same POST with the
    dashboard's own Origin stops it (3.6.3 MST sets the target speed to zero)."""
    import http.client

    def post(origin: str) -> int:
        conn = http.client.HTTPConnection(b.handle.host, b.handle.port, timeout=10)
        conn.request("POST", "/api/stop-all", body=b"{}", headers={
            "Content-Type": "application/json", "X-OpenTMCL": "1", "Origin": origin})
        status = conn.getresponse().status
        conn.close()
        return status

    with bench(("TMCM-6212", 1)) as b:
        six = b.client(1)
        six.request(1, 0, 0, 30000)
        assert post("http://evil.example") == 403
        assert six.client.reply(6, 2, 0).value == 30000  # target speed untouched
        assert post(f"http://127.0.0.1:{b.handle.port}") == 200
        assert six.client.reply(6, 2, 0).value == 0


# One WAIT of 300 s (WAIT TICKS: "one tick is 10 milliseconds", manual 3.6.20): a Step of it stays
# under way until the WAIT ends or the program is stopped.
LONG_WAIT = "Loop:\n    WAIT TICKS, 0, 30000\n    JA Loop\n"


def test_stop_all_is_not_queued_behind_pending_requests(browser):
    """Issue 14 item 1: stop-all "works while a program runs". A browser opens at most six
    connections to one server; six Steps (130) of a 300 s WAIT keep all six busy. STOP ALL still
    reaches the module: GAP 2 (target speed, manual 4.1) of motor 0 turned by ROR (3.6.1) reads 0,
    command 135 reports the program stopped, and the six Steps end as "cancelled by STOP ALL"."""
    from opentmcl.host.loader import Loader

    with bench(("TMCM-6212", 1)) as b:
        six = b.client(1)
        messages: list[str] = []
        page = watched_page(browser, b.handle.module_url(1), messages)
        try:
            page.evaluate("""source => OpenTMCL.api('api/program/download', {source})""", LONG_WAIT)
            six.request(1, 0, 0, 30000)
            page.evaluate("""() => { window.stepped = [];
                for (let i = 0; i < 6; i++) OpenTMCL.api('api/program/step', {}).then(
                    () => window.stepped.push('done'), e => window.stepped.push(e.message)); }""")
            wait_until(lambda: Loader(six).status().waiting, "a Step waiting in the WAIT")
            page.keyboard.press("Escape")
            page.wait_for_function("document.getElementById('stop-all-result').className === 'ok'",
                                   timeout=TIMEOUT_MS)
            assert six.client.reply(6, 2, 0).value == 0
            assert Loader(six).status().mode == 0
            page.wait_for_function("window.stepped.length === 6", timeout=TIMEOUT_MS)
            assert page.evaluate("window.stepped") == ["cancelled by STOP ALL"] * 6
        finally:
            page.close()
        assert not messages, messages


# A program that runs until stopped (WAIT TICKS: "one tick is 10 milliseconds", manual 3.6.20).
LOOP = "Loop:\n    WAIT TICKS, 0, 10\n    JA Loop\n"


def _overlap(a: dict, b: dict) -> bool:
    return a["left"] < b["right"] and b["left"] < a["right"] and a["top"] < b["bottom"] and b["top"] < a["bottom"]


def _rect(page, selector: str) -> dict:
    return page.eval_on_selector(selector, "e => e.getBoundingClientRect().toJSON()")


def test_stopped_chip_goes_when_the_program_runs_or_a_motor_moves_again(browser):
    """Issue 31 item 6. STOP ALL stops the program (128) and every axis (MST, manual 3.6.3); its
    result chip sits in the header, clear of the Direct-mode panel, and goes away once the program
    runs again (129 from another host, manual 3.6.36) or, after a second STOP ALL, once a motor turns
    again (ROR, 3.6.1)."""
    from opentmcl.lang import assemble

    with bench(("TMCM-6212", 1)) as b:
        m = b.client(1)
        messages: list[str] = []
        page = watched_page(browser, b.handle.module_url(1), messages)
        try:
            page.set_viewport_size({"width": 1366, "height": 768})
            store_program(b, assemble(LOOP, module="TMCM-6212").instructions)
            m.client.request(129, 0, 0, 0)
            wait_until(lambda: m.client.request(135, 1, 0, 0).value >> 24 == 1, "the program runs")
            page.click("#btn-stop-all")
            page.wait_for_function("document.getElementById('stop-all-result').className === 'ok'", timeout=TIMEOUT_MS)
            chip, header = _rect(page, "#stop-all-result"), _rect(page, "header")
            assert not _overlap(chip, _rect(page, "#console-section h2"))
            assert not _overlap(chip, _rect(page, "#btn-stop-all"))
            assert header["top"] <= chip["top"] and chip["bottom"] <= header["bottom"]
            page.wait_for_timeout(600)  # a few state updates: the stopped program and motors keep the chip
            assert page.inner_text("#stop-all-result") == "TMCM-6212 @1: stopped"
            m.client.request(129, 0, 0, 0)
            page.wait_for_function("document.getElementById('stop-all-result').textContent === ''", timeout=TIMEOUT_MS)
            page.click("#btn-stop-all")
            page.wait_for_function("document.getElementById('stop-all-result').className === 'ok'", timeout=TIMEOUT_MS)
            page.wait_for_timeout(600)
            assert page.inner_text("#stop-all-result") == "TMCM-6212 @1: stopped"
            m.client.request(1, 0, 2, 10000)  # ROR 2, 10000
            page.wait_for_function("document.getElementById('stop-all-result').textContent === ''", timeout=TIMEOUT_MS)
            m.client.request(3, 0, 2, 0)
        finally:
            page.close()
        assert not messages, messages
