"""Issue 28 item 4: "The parameters view can write to the wrong axis. After choosing axis 5, the
axis-0 table stays editable until the axis-5 values arrive; a value typed in that window is sent
as SAP n, 0. On a 9600-baud link the window is long."

Real processes and a real slow link: `opentmcl serve --pty --pace` (request and reply bytes paced
at GP65's 9600 baud, TMCM-6212 manual 5.1) with `opentmcl dashboard --to serial://PTY?baud=9600`
in front of it, the page in headless Chromium. Reading the axis-5 table takes a GAP (manual
3.6.6) per parameter, each at least 2 x 9 bytes on the wire (about 19 ms), shared with the
dashboard's own polling: the window lasts seconds, so the test looks into it without racing.
The module is watched with GAP over its TCP endpoint, a second connection, not the dashboard.
"""
from __future__ import annotations

import importlib

import pytest

from .processes import served_module
from .processes import watcher as watch

TIMEOUT_MS = 120000  # a guard against hanging: a 9600-baud link reads a table in seconds
GAP, SAP = 6, 5
MAX_POSITIONING_SPEED = 4  # axis parameter 4, 0...7999774 pps (manual 4.1)
TABLE = "#param-axis-table"


@pytest.fixture(scope="module")
def paced():
    """A TMCM-6212 on a paced pty with `opentmcl dashboard --to` in front (tests/web/processes.py)."""
    importlib.import_module("uvicorn")
    with served_module("paced") as served:
        yield served


@pytest.fixture
def watcher(paced):
    with watch(paced) as client:
        yield client


@pytest.fixture(scope="module")
def page(browser, paced):
    """The dashboard page on the parameters view, its tables read once for all the tests here."""
    page = browser.new_page()
    errors: list[str] = []
    page.on("pageerror", lambda exc: errors.append(str(exc)))
    page.goto(f"http://127.0.0.1:{paced.port}/")
    page.wait_for_selector("#axis-0", timeout=TIMEOUT_MS)
    page.click("#views-nav a[data-view='parameters']")
    page.wait_for_selector(f"{TABLE}[data-index]:not(.loading) #param-axis-4", timeout=TIMEOUT_MS)
    yield page
    page.close()
    assert not errors, errors


def shown_axis(page) -> int:
    """The axis of the table shown, once it is not being replaced."""
    page.wait_for_selector(f"{TABLE}[data-index]:not(.loading) #param-axis-4", timeout=TIMEOUT_MS)
    return int(page.get_attribute(TABLE, "data-index"))


def table_of(page, axis: int) -> None:
    """Wait until the axis table shows the values of `axis` (data-index, not loading)."""
    page.wait_for_selector(f"{TABLE}[data-index='{axis}']:not(.loading) #param-axis-4", timeout=TIMEOUT_MS)


WINDOW = """() => {
  const table = document.getElementById("param-axis-table");
  const inputs = [...table.querySelectorAll("input")];
  return {index: table.dataset.index, loading: table.dataset.loading ?? null,
          inputs: inputs.length, editable: inputs.filter(i => !i.disabled).length};
}"""

TYPE_AND_ENTER = """value => {  // what a user's typing and Enter do, sent to the field whatever its state
  const input = document.getElementById("param-axis-4");
  input.value = value;
  input.dispatchEvent(new Event("input"));
  input.dispatchEvent(new KeyboardEvent("keydown", {key: "Enter"}));
}"""


def test_the_table_being_replaced_is_read_only_and_nothing_reaches_the_old_axis(page, watcher):
    """Choose axis 5 with another axis's table shown: at once every field of that table is
    read-only (data-loading="5"), and a value typed with Enter in that window sends nothing (GAP 4
    of both axes unchanged, no SAP in the console log). Once the axis-5 values arrive, the same
    field writes axis 5: SAP 4, 5 (manual 3.6.5), read back with GAP over TCP; the old axis keeps
    its value."""
    old = shown_axis(page)
    if old == 5:
        page.select_option("#param-axis", "0")
        table_of(page, 0)
        old = 0
    before_old = watcher.reply(GAP, MAX_POSITIONING_SPEED, old).value
    before5 = watcher.reply(GAP, MAX_POSITIONING_SPEED, 5).value
    assert page.evaluate(WINDOW)["editable"] > 0
    page.select_option("#param-axis", "5")
    window = page.evaluate(WINDOW)
    assert window["index"] == str(old) and window["loading"] == "5", window  # still the old rows...
    assert window["inputs"] > 0 and window["editable"] == 0, window         # ...none of them editable
    page.evaluate(TYPE_AND_ENTER, "1234")
    assert page.evaluate(WINDOW)["loading"] == "5"                          # still in the window
    table_of(page, 5)
    assert watcher.reply(GAP, MAX_POSITIONING_SPEED, old).value == before_old
    assert watcher.reply(GAP, MAX_POSITIONING_SPEED, 5).value == before5
    assert f"SAP 4, {old}, 1234" not in page.inner_text("#console-log")
    assert page.inner_text("#param-axis-title") == "Axis parameters of axis 5"
    new = 1234 if before5 != 1234 else 4321
    page.fill("#param-axis-4", str(new))
    page.press("#param-axis-4", "Enter")
    page.wait_for_selector("#param-axis-4.saved", timeout=TIMEOUT_MS)
    assert f"SAP 4, 5, {new}" in page.inner_text("#console-log")
    assert watcher.reply(GAP, MAX_POSITIONING_SPEED, 5).value == new
    assert watcher.reply(GAP, MAX_POSITIONING_SPEED, old).value == before_old


def test_the_last_axis_chosen_is_the_one_shown_and_written(page, watcher):
    """Choose one axis, then axis 3 before the first one's values arrive: the table that ends up
    shown is axis 3's (its GAP 4 value, not the other's), and Enter there writes axis 3 only."""
    first = 4 if shown_axis(page) != 4 else 2
    watcher.request(SAP, MAX_POSITIONING_SPEED, 3, 3333)
    watcher.request(SAP, MAX_POSITIONING_SPEED, first, 5555)
    page.select_option("#param-axis", str(first))
    page.select_option("#param-axis", "3")
    assert page.evaluate(WINDOW)["loading"] == "3"
    table_of(page, 3)
    assert page.input_value("#param-axis-4") == "3333"
    page.fill("#param-axis-4", "3334")
    page.press("#param-axis-4", "Enter")
    page.wait_for_selector("#param-axis-4.saved", timeout=TIMEOUT_MS)
    assert watcher.reply(GAP, MAX_POSITIONING_SPEED, 3).value == 3334
    assert watcher.reply(GAP, MAX_POSITIONING_SPEED, first).value == 5555
    assert page.evaluate(WINDOW)["index"] == "3"


def test_a_write_naming_another_module_is_refused(paced, watcher):
    """Rows carry their module: the page sends its module's address with each write, and a write
    that names another module than the page's is refused with 400; nothing is written."""
    from .rawhttp import post_json

    port = paced.port
    before = watcher.reply(GAP, MAX_POSITIONING_SPEED, 1).value
    r = post_json(port, "/m/1/api/params/axis", {"axis": 1, "number": 4, "value": 4242, "module": 2})
    assert r.status == 400 and "module 2" in r.error and "\n" not in r.error
    assert watcher.reply(GAP, MAX_POSITIONING_SPEED, 1).value == before
    r = post_json(port, "/m/1/api/params/axis", {"axis": 1, "number": 4, "value": 4242, "module": 1})
    assert r.status == 200 and r.json()["value"] == 4242
    assert watcher.reply(GAP, MAX_POSITIONING_SPEED, 1).value == 4242
