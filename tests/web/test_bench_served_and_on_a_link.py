"""The tuning bench's four jobs end to end, the same on a module the dashboard serves and on one it
reaches over a link (issue 31 "Done when"): in the browser against `opentmcl serve --module
TMCM-6212 --web`, and against the same module reached through `opentmcl dashboard --to tcp://...`,
an engineer sets up a motor in rpm and mA, tunes stallGuard2 so that a load stops the axis, sets up
and runs a reference search, and reads back the stored program. Real processes; every effect is
confirmed with GAP over the test's own TCP connection to the module (processes.watcher), never
through the dashboard."""
from __future__ import annotations

import urllib.parse
from contextlib import contextmanager

import pytest

from .benchkit import ROOT, TIMEOUT_MS, console_has, open_view
from .processes import Served, wait_for, watcher
from .rawhttp import start_cli, stop_cli

# Axis 0: the stage of examples/scenarios/tmcm6212_stage.toml (left switch at -50000). Axis 2: a load of
# 0.45 of the full-current torque from 30000 microsteps on (docs/scenarios.md "Signals"), the load a
# module on a link meets without the dashboard's load control.
SCENARIO = (ROOT / "examples" / "scenarios" / "tmcm6212_stage.toml").read_text().split("[axis.1]")[0] + """
[axis.2]
load = { by = "position", steps = [[30000, 0.45]], before = 0 }
"""
PROGRAM = "    SAP 4, 0, 51200\nLoop:\n    MVP ABS, 0, 1000\n    WAIT POS, 0, 0\n    MVP ABS, 0, 0\n    WAIT POS, 0, 0\n    JA Loop\n"


@contextmanager
def module(mode: str, scenario: str):
    """"serve": `opentmcl serve --web`; "dashboard": `opentmcl dashboard --to tcp://` in front of
    `opentmcl serve`. Both with the scenario; yields (Served, dashboard page URL)."""
    serve = ["serve", "--module", "TMCM-6212", "--scenario", scenario, "--tcp", "127.0.0.1:0"]
    if mode == "serve":
        proc, url, lines = start_cli([*serve, "--web", "127.0.0.1:0"], "dashboard http")
        tcp = next(line.split()[-1] for line in lines if line.strip().startswith("tcp "))
        try:
            yield Served(urllib.parse.urlsplit(url).port or 0, tcp), url
        finally:
            assert "Traceback" not in stop_cli(proc)
        return
    proc, _, lines = start_cli([*serve, "--web", "127.0.0.1:0"], "dashboard http")  # the TCP endpoint is what counts
    tcp = next(line.split()[-1] for line in lines if line.strip().startswith("tcp "))
    try:
        front, url, _ = start_cli(["dashboard", "--to", tcp, "--web", "127.0.0.1:0"], "dashboard for")
        try:
            yield Served(urllib.parse.urlsplit(url).port or 0, tcp), url
        finally:
            assert "Traceback" not in stop_cli(front)
    finally:
        assert "Traceback" not in stop_cli(proc)


@pytest.fixture(scope="module", params=["serve", "dashboard"])
def workbench(request, browser, tmp_path_factory):
    """The bench's page on the module served one way or the other ("serve" or "dashboard"), and the
    test's own TCP connection to the module; yields (mode, page, tcp)."""
    path = tmp_path_factory.mktemp("scenario") / "bench.toml"
    path.write_text(SCENARIO)
    with module(request.param, str(path)) as (served, url), watcher(served) as tcp:
        messages: list[str] = []
        page = browser.new_page()
        page.on("console", lambda m: messages.append(f"{m.type}: {m.text}") if m.type in ("error", "warning") else None)
        page.on("pageerror", lambda exc: messages.append(f"pageerror: {exc}"))
        page.goto(url)
        page.wait_for_selector("#axis-0", timeout=TIMEOUT_MS)
        page.wait_for_function("window.OpenTMCL.units && window.OpenTMCL.units.info !== null", timeout=TIMEOUT_MS)
        try:
            yield request.param, page, tcp
        finally:
            page.close()
        assert not messages, messages


def gap(tcp, number: int, axis: int) -> int:
    return tcp.reply(6, number, axis, address=1).value


def wizard(page, name: str, axis: int) -> None:
    open_view(page, "setup")
    page.select_option("#wizard-axis", str(axis))
    page.click(f"#wizard-open-{name}")
    page.wait_for_selector("#wizard-next", timeout=TIMEOUT_MS)


def next_step(page, selector: str) -> None:
    page.click("#wizard-next")
    page.wait_for_selector(selector, timeout=TIMEOUT_MS)


def test_set_up_a_motor_in_rpm_and_ma(workbench):
    """TMCM-6212 manual 1 / 4.1 (1.1 A RMS at AP6 = 255, 32 steps) and 6.5 (51200 pps = 60 rpm):
    800 mA is nearest to step 23 of 32 (23/32 of 1100 mA = 791 mA): AP6 = 183, its top; 90 rpm is
    AP4 = 76800."""
    _, page, tcp = workbench
    wizard(page, "motor", 1)
    next_step(page, "#wiz-run-ma")
    page.fill("#wiz-run-ma", "800")
    next_step(page, "#wiz-velocity")
    page.select_option("#wiz-units-1-kind", "rpm")
    page.click("#wiz-units-1-save")
    page.wait_for_function("document.querySelector('#wiz-velocity').parentElement.textContent.includes('rpm')", timeout=TIMEOUT_MS)
    page.fill("#wiz-velocity", "90")
    next_step(page, "#wizard-apply")
    page.click("#wizard-apply")
    page.wait_for_selector("#wizard-finish", timeout=TIMEOUT_MS)
    page.click("#wizard-finish")
    assert (gap(tcp, 6, 1), gap(tcp, 4, 1)) == (183, 76800)
    open_view(page, "overview")
    page.wait_for_function("document.getElementById('axis-1-max_current').textContent === '791 mA (183)'", timeout=TIMEOUT_MS)


def test_tune_stallguard2_so_that_a_load_stops_the_axis(workbench):
    """Manual 6.3: stall detection with AP174 and AP181. Served in this process, the load comes
    from the page's load control (axis 3); through `dashboard --to` the page has no such control
    (a module on a link) and the load comes from the machine, here the scenario's 0.45 from
    30000 microsteps on (axis 2). AP174 = -8 and AP181 = 25600 set from the tool; the axis stops."""
    mode, page, tcp = workbench
    axis = 3 if mode == "serve" else 2
    open_view(page, "tuning")
    page.select_option("#tune-axis", str(axis))
    page.wait_for_function(f"window.dashboard.tuning.axis === {axis} && window.dashboard.tuning.values[174] !== undefined",
                           timeout=TIMEOUT_MS)
    page.fill("#sg-threshold", "-8")
    page.click("#sg-threshold-set")
    page.fill("#sg-work-speed", "51200")
    page.click("#sg-stop-half")
    wait_for(lambda: gap(tcp, 174, axis) == -8 and gap(tcp, 181, axis) == 25600, "AP174 = -8, AP181 = 25600")
    page.click("#sg-run")
    # At the working speed; through `dashboard --to`, the scenario's load may stop it before a poll of
    # a busy machine sees that speed, so having run into the load (30000 microsteps) counts too.
    wait_for(lambda: gap(tcp, 3, axis) == 51200 or (mode != "serve" and gap(tcp, 1, axis) >= 30000),
             "the axis at the working speed")
    if mode == "serve":
        page.fill("#sg-load", "0.45")
        page.click("#sg-load-apply")
    else:
        assert page.is_visible("#sg-load-real") and not page.is_visible("#sg-load-apply")
    wait_for(lambda: gap(tcp, 3, axis) == 0, "the stall stops the axis")
    assert gap(tcp, 2, axis) == 0 or gap(tcp, 206, axis) == 0
    page.wait_for_function("document.getElementById('tune-stall').textContent === 'STALL'", timeout=TIMEOUT_MS)


def test_set_up_and_run_a_reference_search(workbench):
    """Manual 6.1 mode 1 "search left stop switch only" on the stage: the origin is set at the left
    switch (-50000 from the start): RFS STATUS 0, AP1 = 0, AP197 = -50000."""
    _, page, tcp = workbench
    wizard(page, "reference", 0)
    page.check("#wiz-mode-1")
    next_step(page, "#wiz-switch-left")
    next_step(page, "#wiz-search-speed")
    page.fill("#wiz-search-speed", "102400")
    next_step(page, "#wizard-apply")
    page.click("#wizard-apply")
    page.wait_for_selector("#wiz-rfs-start", timeout=TIMEOUT_MS)
    page.click("#wiz-rfs-start")
    console_has(page, "> RFS START, 0")
    wait_for(lambda: tcp.reply(13, 2, 0, address=1).value == 0 and gap(tcp, 1, 0) == 0 and gap(tcp, 197, 0) != 0,
             "the reference search ends at the origin")
    assert abs(gap(tcp, 197, 0) + 50000) <= 1 and gap(tcp, 194, 0) == 102400
    page.wait_for_function("document.getElementById('wiz-rfs-status').textContent === 'done: the origin is set'",
                           timeout=TIMEOUT_MS)
    page.click("#wizard-finish")


def test_read_back_the_stored_program(workbench):
    """Manual 3.6.36: the program downloaded from the editor (132 ... 133) is read back with 134 and
    is the same as the editor's; the test's own 134 over TCP reads the instructions assembled."""
    from opentmcl.host.loader import Loader
    from opentmcl.lang import assemble

    _, page, tcp = workbench
    open_view(page, "program")
    page.wait_for_selector(".CodeMirror", timeout=TIMEOUT_MS)
    page.evaluate(f"OpenTMCL.programEditor.setSource({PROGRAM!r})")
    page.click("#btn-download")
    try:
        page.wait_for_function("document.getElementById('prog-message').textContent.startsWith('downloaded')",
                               timeout=TIMEOUT_MS)
    except Exception as exc:   # say what the page said instead (a rare time-out under load)
        raise AssertionError(f"no 'downloaded': {page.inner_text('#prog-message')!r}, "
                             f"console {page.inner_text('#console-log')[-600:]!r}") from exc
    page.evaluate("OpenTMCL.programEditor.setSource('')")
    page.click("#btn-readback")
    page.wait_for_selector("#btn-readback-open", timeout=TIMEOUT_MS)
    page.click("#btn-readback-open")
    text = page.evaluate("OpenTMCL.programEditor.cm.getValue()")
    code = [tuple(i) for i in assemble(text, module="TMCM-6212").instructions]
    assert code == [tuple(i) for i in assemble(PROGRAM, module="TMCM-6212").instructions]
    assert [tuple(i) for i in Loader(tcp.module(1)).read(0, len(code))] == code
    assert "L1:" in text and "JA L1" in text
