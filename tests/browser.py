"""The one headless Chromium of the test session (Debian's `chromium` package driven by Playwright),
shared by the dashboard's and the HTML report's browser tests: one Playwright per process, since a
second sync Playwright in the same process refuses to start beside the first."""
from __future__ import annotations

import importlib
import os
import shutil
import tempfile
from collections.abc import Iterator

import pytest

CHROMIUM = os.environ.get("OPENTMCL_CHROMIUM", "/usr/bin/chromium")
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                 "--disable-background-networking", "--disable-component-update", "--disable-sync",
                 "--disable-dev-shm-usage",
                 # names that resolve to loopback, as a rebound or another local site's name would
                 "--host-resolver-rules=MAP *.opentmcl.test 127.0.0.1"]


def chromium_context() -> Iterator:
    """Yields a persistent browser context with a fresh profile directory; skips when Chromium
    itself (a system package, installed by .ci/run) is missing."""
    if not (os.path.exists(CHROMIUM) and os.access(CHROMIUM, os.X_OK)):
        pytest.skip(f"browser tests need Chromium at {CHROMIUM} (Debian: apt-get install chromium)")
    sync_api = importlib.import_module("playwright.sync_api")
    profile = tempfile.mkdtemp(prefix="opentmcl-chromium-")
    with sync_api.sync_playwright() as pw:
        context = pw.chromium.launch_persistent_context(
            profile, executable_path=CHROMIUM, headless=True, args=CHROMIUM_ARGS,
            viewport={"width": 1400, "height": 1000})
        try:
            yield context
        finally:
            context.close()
            shutil.rmtree(profile, ignore_errors=True)
