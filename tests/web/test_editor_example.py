"""The program view's starting program (static/editor.js `example`) runs on every module: its SAP
values lie within the module's own manual range, so Download and Run set them, as GAP over the wire
confirms (a value out of range is refused with status 4 and the motor stays at rest)."""
from __future__ import annotations

import pytest

from .shellkit import GAP, TIMEOUT_MS, bench, open_view, wait_until, watched_page

MAX_SPEED, MAX_ACCELERATION = 4, 5


@pytest.mark.parametrize(("name", "speed", "acceleration"), [
    ("PD86-1180", 500, 50),       # PD86-1180 manual 3.2: "SAP 4, 0, 500 //Set max. Velocity", "SAP 5, 0, 50"
    ("TMCM-6212", 51200, 51200),  # TMCM-6212 manual 2.4: "SAP 4, 0, 51200 //Set max. Velocity", "SAP 5, 0, 51200"
])
def test_the_starting_program_sets_its_values_on_the_module(browser, name, speed, acceleration):
    """PD86-1180 manual 4.1 (AP4 maximum positioning speed "0… 2047"): the first program a new user
    downloads and runs carries the values of that module's manual example, so GAP 4 and GAP 5 of
    axis 0 read them back and the motor leaves position 0 (GAP 1)."""
    with bench((name, 1)) as b:
        module = b.client(1)
        messages: list[str] = []
        page = watched_page(browser, b.handle.module_url(1), messages)
        try:
            open_view(page, "program")
            page.wait_for_selector("#program-editor .CodeMirror", state="visible", timeout=TIMEOUT_MS)
            page.click("#btn-download")
            page.wait_for_function(
                "document.getElementById('prog-message').textContent.startsWith('downloaded')", timeout=TIMEOUT_MS)
            page.click("#btn-run")
            wait_until(lambda: module.reply(GAP, MAX_SPEED, 0).value == speed, f"GAP 4 = {speed}")
            assert module.reply(GAP, MAX_ACCELERATION, 0).value == acceleration
            wait_until(lambda: module.reply(GAP, 1, 0).value != 0, "motor 0 moving")
        finally:
            page.close()
        assert not [m for m in messages if m.startswith(("error", "pageerror"))], messages
