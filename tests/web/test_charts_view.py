"""The charts view (static/charts.js on the vendored uPlot, docs/dashboard-charts.md) in headless
Chromium against a virtual TMCM-6212. The charted values are compared with what the module
answers over the wire (GAP/GGP, TMCM-6212 manual 3.6.6 and 3.6.8)."""
from __future__ import annotations

import csv
import io

from .conftest import ARTIFACTS

TIMEOUT_MS = 60000  # only a guard against hanging: the tests wait for a state, they do not time anything


def open_charts(page) -> None:
    page.click("#views-nav a[data-view='charts']")
    page.wait_for_selector("#view-charts", state="visible", timeout=TIMEOUT_MS)
    page.wait_for_selector("#chart-position .uplot", timeout=TIMEOUT_MS)


def add_chart(page, source: str) -> str:
    """Add a chart and choose `source` in its selector; the new chart's id."""
    before = set(page.evaluate("Object.keys(window.dashboard.charts)"))
    page.click("#btn-chart-add")
    page.wait_for_function(f"Object.keys(window.dashboard.charts).length === {len(before) + 1}", timeout=TIMEOUT_MS)
    new = (set(page.evaluate("Object.keys(window.dashboard.charts)")) - before).pop()
    page.select_option(f"#chart-{new} .chart-source", source)
    return new


def count(page, chart: str) -> int:
    return page.evaluate(f"window.dashboard.charts['{chart}'].t.length")


def wait_count(page, chart: str, n: int) -> None:
    page.wait_for_function(f"window.dashboard.charts['{chart}'].t.length >= {n}", timeout=TIMEOUT_MS)


def download_text(page, selector: str) -> str:
    with page.expect_download(timeout=TIMEOUT_MS) as info:
        page.click(selector)
    return open(info.value.path(), encoding="utf-8").read()


def test_uplot_is_served_from_the_package(page, served):
    """No CDN: the vendored library is served with the page (static/vendor/uplot/README.md)."""
    assert page.evaluate("typeof window.uPlot") == "function"
    r = page.request.get(served.url.rstrip("/").rsplit("/m/", 1)[0] + "/static/vendor/uplot/uPlot.iife.min.js")
    assert r.status == 200


def test_a_chart_of_the_load_value_shows_samples_pause_stops_them_csv_has_them(page, served):
    """Manual 4.1 axis parameter 206 "Actual load value" (R): charted from the server's sampler,
    its samples equal GAP 206 of the standing motor. Pause stops new samples while the position
    chart goes on; Resume takes them again; the CSV export holds the chart's samples."""
    open_charts(page)
    chart = add_chart(page, "axis:206")
    wait_count(page, chart, 5)
    load = served.dashboard.module.reply(6, 206, 0).value
    assert set(page.evaluate(f"window.dashboard.charts['{chart}'].series[0].y")) == {load}
    page.click(f"#chart-{chart} .btn-pause")
    paused_at = count(page, chart)
    moving = count(page, "position")
    wait_count(page, "position", moving + 10)  # the live rate went on for 10 samples
    assert count(page, chart) == paused_at
    text = download_text(page, f"#chart-{chart} .btn-csv")
    rows = list(csv.reader(io.StringIO(text)))
    assert rows[0] == ["t_s", "axis 0 actual_load_value"]
    assert len(rows) - 1 == paused_at and all(int(r[1]) == load for r in rows[1:])
    times = [float(r[0]) for r in rows[1:]]
    assert times == sorted(times) and times[-1] - times[0] <= 60
    page.click(f"#chart-{chart} .btn-pause")  # resume
    wait_count(page, chart, paused_at + 3)
    page.screenshot(path=str(ARTIFACTS / "dashboard-charts.png"), full_page=True)


def test_a_global_parameter_chart_follows_the_tick_timer(page, served):
    """Manual 5.1 global parameter 132 "TMCL tick timer" [ms] counts up: its chart rises and its
    last sample is at most what GGP 132 answers afterwards (3.6.8)."""
    open_charts(page)
    chart = add_chart(page, "global:0:132")
    wait_count(page, chart, 5)
    ys = page.evaluate(f"window.dashboard.charts['{chart}'].series[0].y")
    after = served.dashboard.module.reply(10, 132, 0).value
    ys = [y for y in ys if y is not None]   # a read that failed (a loaded machine) is a gap, not a value
    assert len(ys) >= 2 and ys == sorted(ys) and ys[-1] > ys[0] and ys[-1] <= after


def test_several_charts_axes_and_removal(page, served):
    """Two sampled charts at once; choosing axis 1 adds its series (AP 4 of axis 1, set by SAP
    3.6.5); removing a chart removes it and its series."""
    served.dashboard.module.request(5, 4, 1, 4321)
    open_charts(page)
    a = add_chart(page, "axis:4")
    b = add_chart(page, "axis:206")
    page.check(f"#chart-{a} .chart-axis[data-axis='1']")
    page.wait_for_function(f"window.dashboard.charts['{a}'].series.length === 2 && "
                           f"window.dashboard.charts['{a}'].series[1].y.length > 2", timeout=TIMEOUT_MS)
    assert page.evaluate(f"window.dashboard.charts['{a}'].series[1].y.slice(-1)[0]") == 4321
    for axis in ("2", "3", "2"):  # each change subscribes again: time still only moves forward
        page.click(f"#chart-{a} .chart-axis[data-axis='{axis}']")
    wait_count(page, a, 5)
    times = page.evaluate(f"window.dashboard.charts['{a}'].t")
    assert all(t1 < t2 for t1, t2 in zip(times, times[1:], strict=False))
    wait_count(page, b, 3)
    page.click(f"#chart-{b} .btn-remove")
    assert page.locator(f"#chart-{b}").count() == 0
    assert b not in page.evaluate("Object.keys(window.dashboard.charts)")


def test_a_new_chart_is_brought_into_view_at_1366x768(page):
    """Issue 31 item 6: Add chart at 1366x768 (two charts shown already): the new one is scrolled
    into the viewport, with no console error or warning."""
    messages: list[str] = []
    page.on("console", lambda m: messages.append(f"{m.type}: {m.text}") if m.type in ("error", "warning") else None)
    page.set_viewport_size({"width": 1366, "height": 768})
    page.click("#views-nav a[data-view='charts']")
    page.wait_for_selector("#view-charts", state="visible", timeout=TIMEOUT_MS)
    page.wait_for_selector("#chart-velocity .uplot", timeout=TIMEOUT_MS)
    page.click("#btn-chart-add")
    page.wait_for_function("document.querySelectorAll('.chart-card').length === 3", timeout=TIMEOUT_MS)
    page.wait_for_timeout(300)
    box = page.eval_on_selector(".chart-card:last-child", "e => e.getBoundingClientRect().toJSON()")
    assert box["top"] >= 0 and box["bottom"] <= 768, box
    page.click(".chart-card:last-child .btn-remove")
    assert not messages, messages


def test_png_export_is_a_png(page, served):
    open_charts(page)
    wait_count(page, "position", 3)
    with page.expect_download(timeout=TIMEOUT_MS) as info:
        page.click("#chart-position .btn-png")
    assert open(info.value.path(), "rb").read(8) == b"\x89PNG\r\n\x1a\n"


def test_zoom_holds_the_window_and_live_follows_again(page, served):
    """Dragging across the plot zooms the time axis; new samples do not move it; Live follows again."""
    open_charts(page)
    wait_count(page, "position", 30)
    box = page.locator("#chart-position .u-over").bounding_box()
    page.mouse.move(box["x"] + box["width"] * 0.3, box["y"] + 20)
    page.mouse.down()
    page.mouse.move(box["x"] + box["width"] * 0.6, box["y"] + 20, steps=5)
    page.mouse.up()
    page.wait_for_function("window.dashboard.charts.position.zoomed === true", timeout=TIMEOUT_MS)
    span = page.evaluate("[window.dashboard.charts.position.plot.scales.x.min, window.dashboard.charts.position.plot.scales.x.max]")
    wait_count(page, "position", count(page, "position") + 10)
    assert page.evaluate("[window.dashboard.charts.position.plot.scales.x.min, "
                         "window.dashboard.charts.position.plot.scales.x.max]") == span
    page.click("#chart-position .btn-live")
    page.wait_for_function(f"window.dashboard.charts.position.plot.scales.x.max > {span[1]}", timeout=TIMEOUT_MS)


def test_a_failing_poll_is_reported_once_in_the_console_log(page, served):
    """Issue 14 item 7 ("no console errors" hidden, none swallowed) and docs/dashboard-charts.md: when
    the dashboard goes away under a live chart, the failing sample poll is named once in the
    console log ("charts: ..."), not at every poll, and not silently dropped."""
    open_charts(page)
    chart = add_chart(page, "global:0:132")
    wait_count(page, chart, 3)
    served.stop()
    page.wait_for_function("document.getElementById('console-log').innerText.includes('charts: ')",
                           timeout=TIMEOUT_MS)
    page.wait_for_timeout(2000)  # several more polls (POLL_MS) fail the same way
    lines = [t for t in page.inner_text("#console-log").splitlines() if t.startswith("charts: ")]
    assert len(lines) == 1, lines
