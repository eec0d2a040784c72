"""The bus overview (issue 31 item 5, docs/dashboard.md "Bus overview"): every module on the link side
by side with its axes' state, and STOP ALL across them; confirmed with GAP over TCP connections of
the same bus."""
from __future__ import annotations

import pytest

from .benchkit import TIMEOUT_MS, fresh_page, served, wait_until

GAP = 6


@pytest.fixture(scope="module")
def bus():
    with served(("TMCM-6212", 1, None), ("PD86-1180", 2, None)) as b:
        yield b


def test_modules_side_by_side_and_stop_all_across_them(browser, bus):
    """Both modules of the bus (TMCM-6212 at address 1, PD86-1180 at 2) in one row, each with its
    axes (six and one, manual 1 of each); a motor turned by another host (ROR over TCP, manual
    3.6.1 / 4.6.1) shows its velocity there; the view's STOP ALL sends MST to every axis of both
    (AP2 and AP3 read 0 on each, manual 3.6.3)."""
    six, one = bus.client(1), bus.client(2)
    with fresh_page(browser, bus, 1, view="bus") as (page, messages):
        page.wait_for_selector("#bus-module-2 table", timeout=TIMEOUT_MS)
        a, b = (page.eval_on_selector(f"#bus-module-{n}", "e => e.getBoundingClientRect().toJSON()") for n in (1, 2))
        assert a["top"] == b["top"] and b["left"] >= a["right"]  # side by side
        assert page.eval_on_selector_all("#bus-module-1 tr[id]", "rs => rs.length") == 6
        assert page.eval_on_selector_all("#bus-module-2 tr[id]", "rs => rs.length") == 1
        six.client.request(1, 0, 3, 20000)
        one.client.request(1, 0, 0, 300)
        page.wait_for_function("document.getElementById('bus-1-3-velocity').textContent === '20000' && "
                               "document.getElementById('bus-2-0-velocity').textContent === '300'", timeout=TIMEOUT_MS)
        page.click("#bus-stop-all")
        page.wait_for_function("document.getElementById('stop-all-result').className === 'ok'", timeout=TIMEOUT_MS)
        assert page.inner_text("#stop-all-result").split("\n") == ["TMCM-6212 @1: stopped", "PD86-1180 @2: stopped"]
        assert six.client.reply(GAP, 2, 3).value == 0 and one.client.reply(GAP, 2, 0).value == 0
        wait_until(lambda: six.client.reply(GAP, 3, 3).value == 0 and one.client.reply(GAP, 3, 0).value == 0,
                   "both motors at rest")
        page.click("#bus-open-2")
        page.wait_for_function("document.getElementById('ov-module').textContent === 'PD86-1180'", timeout=TIMEOUT_MS)
        assert not messages, messages
