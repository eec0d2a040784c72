"""Issue 30 "Done when": the HTML report is looked at in a browser (headless Chromium from Debian's
`chromium` package through Playwright, as tests/web does): root causes first, knock-ons folded
beneath their cause, the move-duration table, and per axis the module's against the twin's
position and speed, drawn (capture/html.py)."""
from __future__ import annotations

from pathlib import Path

from opentmcl.capture import replay
from opentmcl.capture.html import write_html

from .recorder import planted_session

ARTIFACTS = Path(__file__).resolve().parents[2] / "test-artifacts"


def test_the_html_report_shows_causes_first_folds_knock_ons_and_draws_both_curves(browser, tmp_path):
    report = replay(planted_session(tmp_path), "TMCM-6212")
    index = write_html(report, tmp_path / "html")
    page = browser.new_page()
    errors: list[str] = []
    page.on("pageerror", lambda exc: errors.append(str(exc)))
    page.goto(index.as_uri())
    assert page.locator("h2").first.inner_text() == "Root causes"
    causes = page.locator("#causes > li")
    assert causes.count() == 4
    assert "firmware string" in causes.nth(0).inner_text() and "reference_search_speed" in causes.nth(1).inner_text()
    motion = causes.nth(3)
    knock = motion.locator(".knock").first
    assert not knock.is_visible()   # folded beneath its cause
    motion.locator("summary").click()
    assert knock.is_visible() and "knock-on" in motion.locator("summary").inner_text()
    rows = page.locator("#moves tr.bad")
    assert rows.count() >= 3 and "+" in rows.first.inner_text()
    for key in ("position", "speed"):
        figure = page.locator(f"figure.plot-{key}[data-axis='0']")
        box = figure.locator("svg").bounding_box()
        assert box is not None and box["width"] > 300 and box["height"] > 150
        points = figure.locator("polyline.twin").get_attribute("points").split()
        assert len(points) > 20 and figure.locator("circle.module").count() >= 15
    ARTIFACTS.mkdir(exist_ok=True)
    page.screenshot(path=str(ARTIFACTS / "replay-report.png"), full_page=True)
    page.close()
    assert not errors, errors
