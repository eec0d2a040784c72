"""The Faults panel of the dashboard in headless Chromium against a real `opentmcl serve --faults
FILE --web` (issue 34: "a control that triggers a named fault while serving, from the CLI and from
the dashboard"; "faults that fired are recorded"; docs/dashboard.md "Faults")."""
from __future__ import annotations

import sys
from contextlib import contextmanager

import pytest
import yaml

from ..capture.helpers import Tool

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="opentmcl serve --web as a process")

TIMEOUT_MS = 60000  # only a guard against hanging: the tests wait for a state


@contextmanager
def served_page(browser, tmp_path, faults: list[dict]):
    """The dashboard page of `opentmcl serve --faults FILE --web` with the Faults panel shown; the
    process and the page end however the test does. Yields the page; no JavaScript error may occur."""
    plan = tmp_path / "faults.yaml"
    plan.write_text(yaml.safe_dump({"seed": 5, "fault": faults}), encoding="utf-8")
    errors: list[str] = []
    with Tool("serve", "-m", "TMCM-6212", "--tcp", "127.0.0.1:0", "--web", "127.0.0.1:0", "--faults", str(plan)) as tool:
        page = browser.new_page()
        try:
            page.on("pageerror", lambda exc: errors.append(str(exc)))
            page.goto(tool.endpoint("dashboard"))
            page.wait_for_selector("#faults-panel", timeout=TIMEOUT_MS)
            yield page
        finally:
            page.close()
    assert not errors, errors


def fired_text(page, needle: str) -> None:
    page.wait_for_function(f"document.getElementById('faults-fired').textContent.includes({needle!r})",
                           timeout=TIMEOUT_MS)


def test_trigger_a_named_fault_and_see_it_end(browser, tmp_path):
    """Choose the named power loss, Trigger: the list shows it, and, with no further click, the
    power coming back half a second later (TMCM-6212 manual 5.1: RAM parameters from the EEPROM)."""
    with served_page(browser, tmp_path, [{"name": "lost", "kind": "drop_reply"},
                                         {"name": "cut", "kind": "power_loss", "duration": 0.5}]) as page:
        assert page.eval_on_selector_all("#fault-name option", "os => os.map(o => o.value)") == ["lost", "cut"]
        assert "seed 5" in page.inner_text("#faults-panel")
        page.select_option("#fault-name", "cut")
        page.click("#btn-fault")
        fired_text(page, "cut (power_loss): power lost for 0.5 s (triggered by name)")
        fired_text(page, "cut (power_loss): power back")


def test_a_plan_without_names_still_shows_what_fired(browser, tmp_path):
    """A plan whose only fault fires at its time: no list to trigger from, but the panel shows the
    seed and, as it happens, the fault that fired."""
    with served_page(browser, tmp_path, [{"kind": "stuck_switch", "switch": "left", "at": 1.0,
                                          "duration": 0.5}]) as page:
        assert page.locator("#fault-name").count() == 0
        fired_text(page, "stuck_switch: axis 0 left switch stuck at 1 (at its time)")
        fired_text(page, "left switch follows the stage again")
