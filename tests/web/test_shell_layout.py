"""The workbench layout (issue 14 item 7, docs/dashboard.md "Views"): a navigation of six views,
the overview on a 1366x768 screen without scrolling, most of a 1920x1080 screen used (issue 31
item 6), readable status lamps, currents in the manual's terms with the raw value, a favicon, and
no console error or warning on any view."""
from __future__ import annotations

import http.client

import pytest

from .shellkit import TIMEOUT_MS, bench, open_view, wait_until, watched_page

VIEWS = ["overview", "motion", "parameters", "charts", "program", "io"]


@pytest.fixture
def shell(browser):
    """(page, TCP module at 1, console messages, bench) for a bus of a TMCM-6212 and a PD86-1180."""
    with bench(("TMCM-6212", 1), ("PD86-1180", 2)) as b:
        messages: list[str] = []
        page = watched_page(browser, b.handle.module_url(1), messages)
        try:
            yield page, b.client(1), messages, b
        finally:
            page.close()


def test_navigation_shows_one_view_at_a_time(shell):
    """Each entry of the navigation (and its #hash) shows its view alone; STOP ALL and the console
    stay visible on every view."""
    page, _, messages, _ = shell
    for name in VIEWS:
        open_view(page, name)
        assert page.evaluate("location.hash") == f"#{name}"
        shown = page.evaluate("[...document.querySelectorAll('section.view')].filter(s => !s.hidden)"
                              ".map(s => s.dataset.view)")
        assert shown == [name]
        assert page.is_visible("#btn-stop-all") and page.is_visible("#console-input")
        assert page.get_attribute(f"#views-nav a[data-view='{name}']", "aria-current") == "page"
    page.goto(page.url.split("#")[0] + "#program")  # a link straight to a view
    page.wait_for_selector("#view-program", state="visible", timeout=TIMEOUT_MS)
    assert not page.is_visible("#view-overview")
    assert not messages, messages


def test_overview_fits_a_1366x768_screen(shell):
    """Issue 14 item 7: the overview of the six-axis TMCM-6212 (manual 1, "Features") fits
    1366x768 without scrolling: the document is no taller than the viewport."""
    page, _, _, _ = shell
    page.set_viewport_size({"width": 1366, "height": 768})
    page.goto(page.url.split("#")[0] + "#overview")
    page.wait_for_selector("#axis-5", timeout=TIMEOUT_MS)
    page.wait_for_function("document.getElementById('axis-5-current').textContent.includes('mA')",
                           timeout=TIMEOUT_MS)
    height, viewport = page.evaluate("[document.documentElement.scrollHeight, window.innerHeight]")
    assert viewport == 768 and height <= viewport
    width, vw = page.evaluate("[document.documentElement.scrollWidth, window.innerWidth]")
    assert width <= vw


@pytest.mark.parametrize("view", ["overview", "motion"])
def test_a_1920x1080_screen_is_mostly_used(shell, view):
    """Issue 31 item 6: "at 1920x1080 more than half the screen is empty". The header, the view and
    the Direct-mode panel now cover at least 60 % of the screen (the overview's six axis cards and
    the six motion tools grow, the console takes the height; before: 38 % and 51 %)."""
    page, _, messages, _ = shell
    page.set_viewport_size({"width": 1920, "height": 1080})
    open_view(page, view)
    page.wait_for_timeout(300)
    covered = page.evaluate("""(() => {
        const boxes = ['header', '#views-nav', 'section.view:not([hidden])', '#console-section']
          .map(s => document.querySelector(s).getBoundingClientRect());
        const clip = (lo, hi, max) => Math.max(0, Math.min(hi, max) - Math.max(lo, 0));
        return boxes.reduce((sum, r) => sum + clip(r.left, r.right, innerWidth) * clip(r.top, r.bottom, innerHeight), 0)
               / (innerWidth * innerHeight); })()""")
    assert covered >= 0.6, covered
    assert not messages, messages


def _luminance(rgb: str) -> float:
    parts = [int(x) / 255 for x in rgb[rgb.index("(") + 1:rgb.index(")")].split(",")[:3]]
    lin = [c / 12.92 if c <= 0.03928 else ((c + 0.055) / 1.055) ** 2.4 for c in parts]
    return 0.2126 * lin[0] + 0.7152 * lin[1] + 0.0722 * lin[2]


def _contrast(page, selector: str) -> tuple[float, float]:
    fg, bg, size = page.eval_on_selector(selector, "e => { const s = getComputedStyle(e); "
                                                   "return [s.color, s.backgroundColor, parseFloat(s.fontSize)]; }")
    a, b = sorted((_luminance(fg), _luminance(bg)), reverse=True)
    return (a + 0.05) / (b + 0.05), size


def test_status_lamps_are_readable(shell):
    """The lamps of axis parameters 8 (target position reached), 9 (home), 10/11 (right/left limit
    switch; manual 4.1) carry words, at least 12 px, with a text contrast of at least 4.5:1 (WCAG AA)
    whether on or off; "reached" is on for a motor at its target."""
    page, _, _, _ = shell
    page.wait_for_selector("#axis-0-reached.on", timeout=TIMEOUT_MS)
    assert [page.inner_text(f"#axis-0-{k}") for k in ("reached", "home", "left", "right")] == \
        ["reached", "home", "left", "right"]
    for selector in ("#axis-0-reached", "#axis-0-home"):   # on, off
        ratio, size = _contrast(page, selector)
        assert ratio >= 4.5 and size >= 12, (selector, ratio, size)
    assert page.get_attribute("#axis-0-home", "aria-label") == "home switch (AP 9): off"


def test_currents_in_ma_with_the_raw_value(shell):
    """TMCM-6212 manual 4.1: AP6 "255 means 100% of the maximum current of the module" (manual 1: "up
    to 1.1A RMS"), AP180 "0...31: 1/32, 2/32, ... 32/32". SAP 6, 0, 255 (the last valid value)
    through the wire: the card shows "1100 mA (255)"; AP180 is shown as (n+1)/32 of 1100 mA beside
    its raw n read with GAP 180 (issue 31 item 4: currents in mA, no longer "(n+1)/32")."""
    page, six, _, _ = shell
    six.client.request(5, 6, 0, 255)
    page.wait_for_function("document.getElementById('axis-0-max_current').textContent === '1100 mA (255)'",
                           timeout=TIMEOUT_MS)
    n = six.client.reply(6, 180, 1).value
    page.wait_for_function(f"document.getElementById('axis-1-current').textContent === '{round((n + 1) / 32 * 1100)} mA ({n})'",
                           timeout=TIMEOUT_MS)


def test_favicon_is_served_and_linked(shell):
    """The page links an SVG icon and /favicon.ico (what browsers ask for anyway) is no 404."""
    page, _, _, b = shell
    assert page.get_attribute("link[rel=icon]", "href") == "../../static/favicon.svg"
    for path in ("/favicon.ico", "/static/favicon.svg"):
        conn = http.client.HTTPConnection(b.handle.host, b.handle.port, timeout=10)
        conn.request("GET", path)
        r = conn.getresponse()
        body = r.read()
        conn.close()
        assert r.status == 200 and r.getheader("content-type").startswith("image/svg+xml") and b"<svg" in body


def test_no_console_errors_or_warnings_on_any_view(shell):
    """Every view opened in turn, each doing its first work (motion read-outs, parameter tables, the
    program state, the I/O table): the browser logs no error and no warning."""
    page, _, messages, _ = shell
    ready = {"overview": "#scan-results tr", "motion": "#motion-0-rfs:not(:empty)",
             "parameters": "#param-axis-4", "charts": "#chart-position", "program": "#prog-mode",
             "io": "#io-val-0-1"}
    for name in VIEWS:
        open_view(page, name)
        page.wait_for_selector(ready[name], timeout=TIMEOUT_MS)
    wait_until(lambda: page.inner_text("#motion-0-rfs") != "-", "motion read-out")
    page.select_option("#module-select", label="PD86-1180 (address 2)")
    page.wait_for_function("document.getElementById('ov-module').textContent === 'PD86-1180'", timeout=TIMEOUT_MS)
    for name in VIEWS:
        open_view(page, name)
        page.wait_for_selector(ready[name], timeout=TIMEOUT_MS)
    assert not messages, messages


@pytest.mark.parametrize("view", ["motion", "parameters"])
def test_stop_all_stays_on_screen_when_a_view_scrolls(shell, view):
    """Issue 14 item 1: "a stop-all button always visible on every page". The parameter table and
    the six axes' motion tools are taller than a 1366x768 screen; scrolled to their end, STOP ALL is
    still inside the viewport and on top (the element at its centre), and a mouse click at that
    point (no scrolling first) stops motor 0 turned by ROR (manual 3.6.1): GAP 2 reads 0 (3.6.3)."""
    page, six, messages, _ = shell
    page.set_viewport_size({"width": 1366, "height": 768})
    open_view(page, view)
    page.wait_for_selector("#motion-5-rfs:not(:empty)" if view == "motion" else "#param-axis-4",
                           timeout=TIMEOUT_MS)
    assert page.evaluate("document.documentElement.scrollHeight") > 768  # the view does scroll
    six.client.request(1, 0, 0, 30000)
    page.evaluate("window.scrollTo(0, document.documentElement.scrollHeight)")
    x, y, top, bottom, on_top = page.evaluate("""(() => {
        const r = document.getElementById('btn-stop-all').getBoundingClientRect();
        const x = r.x + r.width / 2, y = r.y + r.height / 2;
        return [x, y, r.top, r.bottom, document.elementFromPoint(x, y)?.id ?? null]; })()""")
    assert 0 <= top and bottom <= 768 and on_top == "btn-stop-all", (top, bottom, on_top)
    page.mouse.click(x, y)
    page.wait_for_function("document.getElementById('stop-all-result').className === 'ok'", timeout=TIMEOUT_MS)
    assert six.client.reply(6, 2, 0).value == 0
    assert not messages, messages
