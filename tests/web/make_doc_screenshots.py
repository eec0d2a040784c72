"""Regenerate the dashboard screenshots in docs/img/ (not a test): one per view,
docs/img/dashboard-VIEW.png, at 1366x768 (the laptop screen of issue 14).

    .venv/bin/python -m tests.web.make_doc_screenshots

Two virtual modules on one bus (TMCM-6212 at 1, PD86-1180 at 2), with motors turning and the
editor's example program running, so every view has something to show.
"""
from __future__ import annotations

import tempfile
import time
from pathlib import Path

from .conftest import CHROMIUM, CHROMIUM_ARGS

DOCS = Path(__file__).resolve().parents[2] / "docs" / "img"
VIEWS = ("overview", "motion", "parameters", "charts", "program", "io")


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


def main() -> None:
    from playwright.sync_api import sync_playwright

    from opentmcl import VirtualModule
    from opentmcl.server.app import Server
    from opentmcl.web import start_dashboard_for_bus

    server = Server([VirtualModule("TMCM-6212", address=1), VirtualModule("PD86-1180", address=2)])
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
            ctx.close()
    finally:
        handle.stop()
        server.stop()


if __name__ == "__main__":
    main()
