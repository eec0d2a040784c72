"""Regenerate the dashboard screenshots in docs/img/ (not a test): one per view,
docs/img/dashboard-VIEW.png, at 1366x768 (the laptop screen of issue 14), and one per tool of the
tuning bench (issue 31): dashboard-stallguard.png, dashboard-coolstep.png, dashboard-wizard-motor.png,
dashboard-wizard-reference.png, dashboard-readback.png, dashboard-units.png, and the overview at
1920x1080 (dashboard-overview-1920.png).

    .venv/bin/python -m tests.web.make_doc_screenshots

Two virtual modules on one bus (TMCM-6212 at 1 on the stage of examples/scenarios/tmcm6212_stage.toml,
PD86-1180 at 2), with motors turning and the editor's example program running, so every view has
something to show.
"""
from __future__ import annotations

import tempfile
import time
from pathlib import Path

from .conftest import CHROMIUM, CHROMIUM_ARGS

DOCS = Path(__file__).resolve().parents[2] / "docs" / "img"
VIEWS = ("overview", "motion", "parameters", "charts", "program", "io", "bus")
STAGE = Path(__file__).resolve().parents[2] / "examples" / "scenarios" / "tmcm6212_stage.toml"


def _console(page, line: str) -> None:
    page.fill("#console-input", line)
    page.press("#console-input", "Enter")
    page.wait_for_function(f"document.getElementById('console-log').textContent.includes({('> ' + line)!r})")


def _prepare(page) -> None:
    """The example program running, motors 1 and 2 moving, a scan of addresses 1-4 done."""
    page.click("#views-nav a[data-view='program']")
    page.click("#btn-download")
    page.wait_for_function("document.getElementById('prog-message').textContent.startsWith('downloaded')")
    page.click("#btn-run")
    for line in ("SAP 5, 1, 20000", "MVP ABS, 1, -80000", "ROR 2, 20000"):
        _console(page, line)
    page.click("#views-nav a[data-view='overview']")
    page.fill("#scan-last", "4")
    page.fill("#scan-timeout", "0.05")
    page.click("#btn-scan")
    page.wait_for_function("document.getElementById('scan-progress').textContent.startsWith('done')")
    time.sleep(5)  # let the charts fill


def _js(page, script: str) -> None:
    page.evaluate(f"(() => {{ {script} }})()")


def _select(page, selector: str, value: str) -> None:
    page.select_option(selector, value)
    time.sleep(0.8)


def _tools(page) -> None:
    """The tuning bench: stallGuard2 stopping axis 2 under a load, coolStep on axis 3, the motor and
    reference search wizards, the read-back with a difference, units in the motion view."""
    page.click("#views-nav a[data-view='tuning']")
    time.sleep(1)
    _select(page, "#tune-axis", "2")
    page.fill("#sg-work-speed", "51200")
    page.click("#sg-run")
    time.sleep(1.5)
    page.fill("#sg-load", "0.45")
    page.click("#sg-load-apply")
    page.fill("#sg-threshold", "-8")
    page.click("#sg-threshold-set")
    time.sleep(1)
    page.click("#sg-stop-half")
    time.sleep(1.5)
    page.screenshot(path=str(DOCS / "dashboard-stallguard.png"))
    _select(page, "#tune-axis", "3")
    for name, value in (("semin", "1"), ("semax", "2"), ("sedn", "3")):
        page.select_option(f"#cs-{name}", value)
    page.click("#cs-apply")
    page.fill("#sg-work-speed", "51200")
    page.click("#sg-run")
    time.sleep(4)
    page.eval_on_selector("#cs-panel", "e => e.scrollIntoView({block: 'end'})")
    time.sleep(0.5)
    page.screenshot(path=str(DOCS / "dashboard-coolstep.png"))
    page.click("#sg-stop")
    page.click("#views-nav a[data-view='setup']")
    time.sleep(1)
    page.click("#wizard-open-motor")
    time.sleep(0.5)
    page.click("#wizard-next")
    page.fill("#wiz-run-ma", "550")
    page.fill("#wiz-standby-ma", "100")
    page.click("#wizard-next")
    page.select_option("#wiz-units-0-kind", "rpm")
    page.click("#wiz-units-0-save")
    time.sleep(0.5)
    page.fill("#wiz-velocity", "120")
    page.click("#wizard-next")
    time.sleep(0.5)
    page.screenshot(path=str(DOCS / "dashboard-wizard-motor.png"))
    page.click("#wizard-cancel")
    page.click("#wizard-open-reference")
    time.sleep(0.5)
    page.check("#wiz-mode-1")
    for _ in range(3):
        page.click("#wizard-next")
        time.sleep(0.3)
    page.click("#wizard-apply")
    time.sleep(0.5)
    page.click("#wiz-rfs-start")
    time.sleep(1.2)
    page.screenshot(path=str(DOCS / "dashboard-wizard-reference.png"))
    page.click("#wiz-rfs-stop")
    page.click("#wizard-cancel")
    page.click("#views-nav a[data-view='program']")
    time.sleep(1)
    _js(page, "OpenTMCL.programEditor.setSource(OpenTMCL.programEditor.cm.getValue()"
              ".replace('SAP 5, 0, 51200', 'SAP 5, 0, 40000'))")
    page.click("#btn-readback")
    page.wait_for_selector("#readback-summary")
    time.sleep(0.5)
    page.screenshot(path=str(DOCS / "dashboard-readback.png"))
    page.click("#btn-readback-close")
    page.click("#views-nav a[data-view='motion']")
    time.sleep(1)
    page.select_option("#units-1-kind", "user")
    page.click("#units-1-save")
    page.fill("#motion-1-target", "20")
    page.click("#motion-1-abs")
    time.sleep(1.5)
    page.screenshot(path=str(DOCS / "dashboard-units.png"))


def main() -> None:
    from playwright.sync_api import sync_playwright

    from opentmcl import VirtualModule
    from opentmcl.server.app import Server
    from opentmcl.web import start_dashboard_for_bus

    server = Server([VirtualModule("TMCM-6212", address=1, scenario=str(STAGE)), VirtualModule("PD86-1180", address=2)])
    server.start()
    handle = start_dashboard_for_bus(server.bus, "127.0.0.1", 0)
    DOCS.mkdir(parents=True, exist_ok=True)
    try:
        with sync_playwright() as pw:
            ctx = pw.chromium.launch_persistent_context(tempfile.mkdtemp(), executable_path=CHROMIUM,
                                                        headless=True, args=CHROMIUM_ARGS,
                                                        viewport={"width": 1366, "height": 768})
            page = ctx.new_page()
            page.goto(handle.module_url(1))
            page.wait_for_selector("#axis-0")
            _prepare(page)
            for view in VIEWS:
                page.click(f"#views-nav a[data-view='{view}']")
                if view == "parameters":
                    page.wait_for_selector("#param-axis-4")
                if view == "program":
                    # line 8's number; its breakpoint marker is re-drawn at every state update, never "stable"
                    page.click(".CodeMirror-code > div:nth-child(8) .CodeMirror-linenumber", force=True)
                time.sleep(1.5)
                page.screenshot(path=str(DOCS / f"dashboard-{view}.png"))
            page.click("#btn-stop-all")
            page.wait_for_function("document.getElementById('stop-all-result').className === 'ok'")
            page.click("#views-nav a[data-view='motion']")
            time.sleep(1)
            page.screenshot(path=str(DOCS / "dashboard-stop-all.png"))
            _tools(page)
            page.set_viewport_size({"width": 1920, "height": 1080})
            page.click("#views-nav a[data-view='overview']")
            time.sleep(1.5)
            page.screenshot(path=str(DOCS / "dashboard-overview-1920.png"))
            ctx.close()
    finally:
        handle.stop()
        server.stop()


if __name__ == "__main__":
    main()
