"""The parameters view (static/params.js, docs/dashboard-parameters.md) in headless Chromium against
a virtual TMCM-6212: every outcome is checked on the module through the wire (GAP, TMCM-6212
manual 3.6.6), not only on the page."""
from __future__ import annotations

import json

from .conftest import ARTIFACTS

TIMEOUT_MS = 60000  # only a guard against hanging: the tests wait for a state, they do not time anything


def open_parameters(page) -> None:
    page.click("#views-nav a[data-view='parameters']")
    page.wait_for_selector("#view-parameters", state="visible", timeout=TIMEOUT_MS)
    page.wait_for_selector("#param-axis-table[data-index]:not(.loading) #param-axis-4", timeout=TIMEOUT_MS)


def gap(served, number: int, axis: int = 0) -> int:
    return served.dashboard.module.reply(6, number, axis).value


def test_edit_in_place_within_the_manuals_range(page, served):
    """Manual 4.1 axis parameter 4 "Maximum positioning speed": 0...7999774 [pps]. The last valid
    value is written (SAP, 3.6.5) and GAP answers it; the first invalid one, 7999775, is refused
    on the page with the range and nothing is sent. The console shows the command sent."""
    open_parameters(page)
    page.fill("#param-axis-4", "7999774")
    page.press("#param-axis-4", "Enter")
    page.wait_for_selector("#param-axis-4.saved", timeout=TIMEOUT_MS)
    assert gap(served, 4) == 7999774
    assert "SAP 4, 0, 7999774" in page.inner_text("#console-log")
    page.fill("#param-axis-4", "7999775")
    page.press("#param-axis-4", "Enter")
    page.wait_for_selector("#param-axis-4.failed", timeout=TIMEOUT_MS)
    assert "0 … 7999774" in page.get_attribute("#param-axis-4", "title")
    assert "SAP 4, 0, 7999775" not in page.inner_text("#console-log")
    assert gap(served, 4) == 7999774


def test_edit_on_another_axis_and_a_global_parameter(page, served):
    """Axis 5 (the last of six, manual 1) is edited when chosen; global parameter 77 "auto start
    mode" (manual 5.1, bank 0) is written with SGP (3.6.7) and read back with GGP (3.6.8).
    The test waits for the table of axis 5 itself (issue 28 item 4: the axis-0 table, shown until
    then, is read-only meanwhile; test_params_paced.py looks into that window)."""
    open_parameters(page)
    page.select_option("#param-axis", "5")
    page.wait_for_selector("#param-axis-table[data-index='5']:not(.loading) #param-axis-4", timeout=TIMEOUT_MS)
    page.fill("#param-axis-4", "1234")
    page.press("#param-axis-4", "Enter")
    page.wait_for_selector("#param-axis-4.saved", timeout=TIMEOUT_MS)
    assert gap(served, 4, 5) == 1234 and gap(served, 4, 0) != 1234
    page.fill("#param-global-0-77", "1")
    page.press("#param-global-0-77", "Enter")
    page.wait_for_selector("#param-global-0-77.saved", timeout=TIMEOUT_MS)
    assert served.dashboard.module.reply(10, 77, 0).value == 1
    assert page.locator("#param-global-table-3").count() == 1  # bank 3: interrupt configuration


def test_a_wire_side_change_is_refreshed_and_highlighted(page, served):
    """While the view is shown the values refresh: a SAP sent by another client (manual 3.6.5)
    shows up in the table and is highlighted; a read-only value (3 "Actual speed") follows a
    rotation (ROR, 3.6.1)."""
    open_parameters(page)
    served.dashboard.module.request(5, 7, 0, 42)       # SAP 7, 0, 42: standby current
    page.wait_for_selector("#param-axis-7.changed", timeout=TIMEOUT_MS)
    assert page.input_value("#param-axis-7") == "42"
    served.dashboard.module.request(1, 0, 0, 1000)     # ROR 0, 1000
    page.wait_for_selector("#param-axis-3.changed", timeout=TIMEOUT_MS)
    page.wait_for_function("document.getElementById('param-axis-3').textContent === '1000'", timeout=TIMEOUT_MS)
    served.dashboard.module.request(3, 0, 0, 0)        # MST 0
    page.screenshot(path=str(ARTIFACTS / "dashboard-parameters.png"), full_page=True)


def export_json(page) -> dict:
    with page.expect_download(timeout=TIMEOUT_MS) as info:
        page.click("#btn-params-export-json")
    return json.loads(open(info.value.path(), encoding="utf-8").read())


def import_file(page, data: dict, name: str = "set.json") -> None:
    page.set_input_files("#param-import", files=[{"name": name, "mimeType": "application/json",
                                                  "buffer": json.dumps(data).encode()}])


def test_export_then_import_of_a_modified_file_applies_only_after_confirm(page, served):
    """Export (numbers, names, module, firmware "6212V105", manual 3.6.36), change axis 0's
    parameter 4, import: the diff shows number, name, current and file value and nothing is
    written; Cancel writes nothing; Apply writes it (GAP confirms)."""
    open_parameters(page)
    data = export_json(page)
    assert data["module"] == "TMCM-6212" and data["firmware"] == "6212V105"
    entry = next(e for e in data["axis"] if e["axis"] == 0 and e["number"] == 4)
    assert entry["name"] == "max_positioning_speed"
    before = gap(served, 4)
    entry["value"] = 30000
    import_file(page, data)
    page.wait_for_selector("#param-import-diff", timeout=TIMEOUT_MS)
    row = page.inner_text("#param-import-diff")
    assert "max_positioning_speed" in row and str(before) in row and "30000" in row
    assert gap(served, 4) == before
    page.click("#btn-import-cancel")
    assert gap(served, 4) == before
    import_file(page, data)
    page.wait_for_selector("#btn-import-apply", timeout=TIMEOUT_MS)
    page.screenshot(path=str(ARTIFACTS / "dashboard-parameters-import.png"), full_page=True)
    assert gap(served, 4) == before
    page.click("#btn-import-apply")
    page.wait_for_function("document.getElementById('param-import-summary').textContent.includes('applied 1')",
                           timeout=TIMEOUT_MS)
    assert gap(served, 4) == 30000
    page.wait_for_function("document.getElementById('param-axis-4').value === '30000'", timeout=TIMEOUT_MS)


def test_a_foreign_module_file_is_refused(page, served):
    """A PD86-1180 file is refused with a message naming it; nothing is applied."""
    open_parameters(page)
    data = export_json(page)
    data["module"] = "PD86-1180"
    next(e for e in data["axis"] if e["axis"] == 0 and e["number"] == 4)["value"] = 1000
    import_file(page, data)
    page.wait_for_selector("#param-import-error", timeout=TIMEOUT_MS)
    assert "PD86-1180" in page.inner_text("#param-import-error")
    assert page.locator("#btn-import-apply").count() == 0
    assert gap(served, 4) != 1000


def test_an_out_of_range_file_is_refused(page, served):
    """Manual 4.1: 7999775 is past parameter 4's range: the import is refused with the value, and
    the file's valid change of parameter 7 is not applied either."""
    open_parameters(page)
    data = export_json(page)
    before7 = gap(served, 7)
    for e in data["axis"]:
        if e["axis"] == 0 and e["number"] == 4:
            e["value"] = 7999775
        if e["axis"] == 0 and e["number"] == 7:
            e["value"] = (before7 + 8) % 256
    import_file(page, data)
    page.wait_for_selector("#param-import-error", timeout=TIMEOUT_MS)
    assert "7999775" in page.inner_text("#param-import-error")
    assert gap(served, 7) == before7 and gap(served, 4) != 7999775


def test_store_and_restore_on_a_module_with_stap(browser, served_bus):
    """PD86-1180 manual 4.6.7 STAP "Store the maximum speed of motor: STAP 4, 0" and 4.6.8 RSAP
    (the parameter is copied from the EEPROM to its RAM location): set 4 to 1500, store, set it to
    900 over the wire, restore: GAP answers 1500 again and the table shows it. The TMCM-6212 has
    no STAP/RSAP (its command list), so its axis table has no store button."""
    page = browser.new_page()
    errors: list[str] = []
    page.on("pageerror", lambda exc: errors.append(str(exc)))
    try:
        page.goto(served_bus.module_url(1))
        open_parameters(page)
        assert page.locator("#param-axis-4-store").count() == 0
        assert page.locator("#param-global-0-77-store").count() == 1   # STGP: TMCM-6212 manual 3.6.9
        page.goto(served_bus.module_url(2))
        open_parameters(page)
        pd86 = served_bus.dashboards[1].module
        page.fill("#param-axis-4", "1500")
        page.press("#param-axis-4", "Enter")
        page.wait_for_selector("#param-axis-4.saved", timeout=TIMEOUT_MS)
        page.click("#param-axis-4-store")
        page.wait_for_function("document.getElementById('console-log').textContent.includes('stored max_positioning_speed')",
                               timeout=TIMEOUT_MS)
        assert "STAP 4, 0" in page.inner_text("#console-log")
        pd86.request(5, 4, 0, 900)                                      # SAP 4, 0, 900 from another client
        page.wait_for_function("document.getElementById('param-axis-4').value === '900'", timeout=TIMEOUT_MS)
        page.click("#param-axis-4-restore")
        page.wait_for_function("document.getElementById('param-axis-4').value === '1500'", timeout=TIMEOUT_MS)
        assert pd86.reply(6, 4, 0).value == 1500
        assert "RSAP 4, 0" in page.inner_text("#console-log")
    finally:
        page.close()
    assert not errors, f"JavaScript errors on the page: {errors}"


def test_a_value_the_manual_forbids_inside_the_range_is_refused_on_the_page(browser):
    """PD86-1180 manual 7.2 (encoder prescaler, axis parameter 210): "The values 1, 2, 4, and 16
    must not be used for <p>." The range shown names them; 16 is refused on the page and no SAP is
    sent (GAP 210 over the wire keeps its value); 17, the next value, is written and read back."""
    from .shellkit import bench, open_view, watched_page

    with bench(("PD86-1180", 1)) as b:
        module = b.client(1)
        before = module.reply(6, 210, 0).value
        messages: list[str] = []
        page = watched_page(browser, b.handle.module_url(1), messages)
        try:
            open_view(page, "parameters")
            page.wait_for_selector("#param-axis-210", timeout=TIMEOUT_MS)
            row = page.inner_text("xpath=//input[@id='param-axis-210']/ancestor::tr")
            assert "except 1, 2, 4, 16" in row
            page.fill("#param-axis-210", "16")
            page.press("#param-axis-210", "Enter")
            page.wait_for_selector("#param-axis-210.failed", timeout=TIMEOUT_MS)
            assert "except 1, 2, 4, 16" in page.get_attribute("#param-axis-210", "title")
            assert "SAP 210, 0, 16" not in page.inner_text("#console-log")
            assert module.reply(6, 210, 0).value == before
            page.fill("#param-axis-210", "17")
            page.press("#param-axis-210", "Enter")
            page.wait_for_selector("#param-axis-210.saved", timeout=TIMEOUT_MS)
            assert module.reply(6, 210, 0).value == 17
        finally:
            page.close()
