"""Regenerate the dashboard screenshots in docs/img/ (not a test):

    .venv/bin/python -m tests.web.make_doc_screenshots
"""
from __future__ import annotations

import tempfile
import time
from pathlib import Path

import opentmcl
from opentmcl.web import start_dashboard

from .conftest import CHROMIUM, CHROMIUM_ARGS

DOCS = Path(__file__).resolve().parents[2] / "docs" / "img"


def main() -> None:
    from playwright.sync_api import sync_playwright

    module = opentmcl.connect("sim://TMCM-6212?clock=real")
    t = module.client.transport
    handle = start_dashboard(module, "127.0.0.1", 0, vm=t.module, vm_lock=t.lock, url="sim://TMCM-6212")
    DOCS.mkdir(parents=True, exist_ok=True)
    try:
        with sync_playwright() as pw:
            ctx = pw.chromium.launch_persistent_context(tempfile.mkdtemp(), executable_path=CHROMIUM,
                                                        headless=True, args=CHROMIUM_ARGS,
                                                        viewport={"width": 1300, "height": 900})
            page = ctx.new_page()
            page.goto(handle.url)
            page.wait_for_selector("#axis-0")
            # the editor opens with the page's own example program (a fresh profile has none saved)
            page.click("#btn-download")
            page.wait_for_function("document.getElementById('prog-message').textContent.startsWith('downloaded')")
            page.click("#btn-run")
            for line in ("SAP 5, 1, 20000", "MVP ABS, 1, -80000", "ROR 2, 20000"):
                page.fill("#console-input", line)
                page.press("#console-input", "Enter")
            time.sleep(6)
            page.evaluate("window.scrollTo(0, 0)")
            page.screenshot(path=str(DOCS / "dashboard.png"))
            page.click("#gutter-8")
            time.sleep(1.5)
            page.locator("#program-section").screenshot(path=str(DOCS / "dashboard-program.png"))
            page.locator("#console-section").screenshot(path=str(DOCS / "dashboard-console.png"))
            page.fill("#param-filter", "speed")
            page.locator("#params-section").screenshot(path=str(DOCS / "dashboard-params.png"))
            ctx.close()
    finally:
        handle.stop()


if __name__ == "__main__":
    main()
