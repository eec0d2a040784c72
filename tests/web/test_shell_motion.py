"""The motion view (issue 14 item 2, docs/dashboard.md "Motion"): per-axis tools that send ROR, ROL,
MST, MVP ABS/REL and RFS, each logged in the console; the motion is confirmed with GAP through a TCP
client of the same bus."""
from __future__ import annotations

import pytest

from .shellkit import (
    ACTUAL_POSITION,
    ACTUAL_SPEED,
    TARGET_SPEED,
    TIMEOUT_MS,
    bench,
    open_view,
    wait_until,
    watched_page,
)


@pytest.fixture
def motion(browser):
    """(page, TCP module at address 1, console messages) on the motion view of a TMCM-6212."""
    with bench(("TMCM-6212", 1)) as b:
        messages: list[str] = []
        page = watched_page(browser, b.handle.module_url(1), messages)
        open_view(page, "motion")
        page.wait_for_function("document.getElementById('motion-5-rfs').textContent !== '-'", timeout=TIMEOUT_MS)  # all read
        try:
            yield page, b.client(1), messages
        finally:
            page.close()
        assert not messages, messages


def gap(module, number: int, axis: int = 0) -> int:
    return module.client.reply(6, number, axis).value


def logged(page, text: str) -> None:
    page.wait_for_function(f"document.getElementById('console-log').textContent.includes({text!r})",
                           timeout=TIMEOUT_MS)


def test_rotate_right_with_the_velocity_given(motion):
    """Manual 3.6.1 ROR: "ROR 1, 20000" sets target velocity AP2 and turns motor 1 to the right
    (increasing position): GAP 2 = 20000 and GAP 3 reaches it; the console shows the instruction."""
    page, six, _ = motion
    page.fill("#motion-1-velocity", "20000")
    page.click("#motion-1-ror")
    logged(page, "> ROR 1, 20000")
    logged(page, "status 100")
    wait_until(lambda: gap(six, ACTUAL_SPEED, 1) == 20000, "axis 1 at 20000 pps")
    assert gap(six, TARGET_SPEED, 1) == 20000 and gap(six, ACTUAL_POSITION, 1) > 0


def test_rotate_left_then_stop(motion):
    """Manual 3.6.2 ROL turns to the left ("decreasing the position counter"), 3.6.3 MST stops with a
    soft stop: GAP 3 goes negative, then back to 0."""
    page, six, _ = motion
    page.fill("#motion-0-velocity", "30000")
    page.click("#motion-0-rol")
    logged(page, "> ROL 0, 30000")
    wait_until(lambda: gap(six, ACTUAL_SPEED) == -30000, "axis 0 at -30000 pps")
    assert gap(six, ACTUAL_POSITION) < 0
    page.click("#motion-0-mst")
    logged(page, "> MST 0")
    wait_until(lambda: gap(six, ACTUAL_SPEED) == 0, "axis 0 stopped")


def test_move_absolute_then_relative(motion):
    """Manual 3.6.4 MVP: "MVP ABS, 2, 12800" moves motor 2 to 12800, then "MVP REL, 2, -2800" by
    -2800 from there: GAP 1 ends at 12800, then at 10000."""
    page, six, _ = motion
    page.fill("#motion-2-target", "12800")
    page.click("#motion-2-abs")
    logged(page, "> MVP ABS, 2, 12800")
    wait_until(lambda: gap(six, ACTUAL_POSITION, 2) == 12800, "axis 2 at 12800")
    page.fill("#motion-2-target", "-2800")
    page.click("#motion-2-rel")
    logged(page, "> MVP REL, 2, -2800")
    wait_until(lambda: gap(six, ACTUAL_POSITION, 2) == 10000, "axis 2 at 10000")


def test_reference_search_start_status_stop(motion):
    """Manual 3.6.11 RFS: START starts the search, STATUS answers 0 "no ref. search active" or
    another value "reference search active", STOP stops it. The view shows the status read back."""
    page, six, _ = motion
    assert page.inner_text("#motion-3-rfs") == "not active"
    page.click("#motion-3-rfs-start")
    logged(page, "> RFS START, 3")
    wait_until(lambda: six.client.reply(13, 2, 3).value != 0, "RFS STATUS active")
    page.wait_for_function("document.getElementById('motion-3-rfs').textContent.startsWith('active')",
                           timeout=TIMEOUT_MS)
    page.click("#motion-3-rfs-stop")
    logged(page, "> RFS STOP, 3")
    wait_until(lambda: six.client.reply(13, 2, 3).value == 0, "RFS STATUS not active")
    page.wait_for_function("document.getElementById('motion-3-rfs').textContent === 'not active'",
                           timeout=TIMEOUT_MS)


def test_velocity_range_is_the_target_speed_range(motion):
    """Manual 4.1 AP2 "Target (next) speed" range ±7999774 (ROR's value): 7999774, the last valid
    one, is sent; 7999775, the first invalid one, is refused in the page and nothing is sent."""
    page, six, _ = motion
    page.fill("#motion-4-velocity", "7999775")
    page.click("#motion-4-ror")
    logged(page, "velocity must be a whole number 0…7999774")
    assert "ROR 4" not in page.inner_text("#console-log") and gap(six, TARGET_SPEED, 4) == 0
    page.fill("#motion-4-velocity", "7999774")
    page.click("#motion-4-ror")
    logged(page, "> ROR 4, 7999774")
    wait_until(lambda: gap(six, TARGET_SPEED, 4) == 7999774, "AP2 = 7999774")


def test_a_poll_keeps_what_the_user_typed(motion):
    """docs/dashboard.md "Motion": the view reads every axis again periodically; the velocity field
    keeps what the user typed across those reads, even a value the module would refuse (the poll
    rewrote it with the last valid one, so the click after it sent that one instead of refusing)."""
    page, _, _ = motion
    page.fill("#motion-4-velocity", "7999775")
    for _ in range(2):  # two whole rounds of reads of axis 4 after the typing
        with page.expect_response(lambda r: r.url.endswith("api/motion/4"), timeout=TIMEOUT_MS):
            pass
    assert page.input_value("#motion-4-velocity") == "7999775"


def test_velocity_unit_follows_unit_mode(motion):
    """TMCM-6212 manual 4.1 AP255 "Unit mode": 1 (default) pps, 0 "the internal units of the TMC5130
    are used directly". The velocity field stays in pps (issue 31: physical units), and the module
    value beside it says the module now takes internal units (16 MHz / 2^24 pps each, docs/sources.md)."""
    page, six, _ = motion
    assert page.inner_text("#motion-5-unit") == "pps" and page.inner_text("#motion-5-velocity-raw") == ""
    six.client.request(5, 255, 5, 0)
    page.wait_for_function("document.getElementById('motion-5-velocity-raw').textContent.endsWith('internal units')",
                           timeout=TIMEOUT_MS)
    assert page.inner_text("#motion-5-unit") == "pps" and page.inner_text("#motion-0-velocity-raw") == ""  # per axis


def test_pd86_1180_velocity_is_in_internal_units(browser):
    """PD86-1180 (TMC429, docs/profiles.md capability velocity_unit = "tmc429"): the module takes
    internal units, range 0…2047 (manual 4.6.1 ROR "0… 2047"); the field shows pps from them (manual
    5: 16 MHz * v / (65536 * 2^pulse_divisor)) with the module value beside it. The slider's right
    end is 2047: ROR with it turns the motor at 2047."""
    with bench(("PD86-1180", 1)) as b:
        messages: list[str] = []
        page = watched_page(browser, b.handle.module_url(1), messages)
        try:
            open_view(page, "motion")
            page.wait_for_function("document.getElementById('motion-0-velocity-raw').textContent.endsWith('internal units')",
                                   timeout=TIMEOUT_MS)
            assert page.inner_text("#motion-0-unit") == "pps"
            page.evaluate("(() => { const s = document.getElementById('motion-0-slider'); s.value = s.max;"
                          " s.dispatchEvent(new Event('input')); })()")
            assert page.inner_text("#motion-0-velocity-raw") == "= 2047 internal units"
            assert float(page.input_value("#motion-0-velocity")) == pytest.approx(16e6 * 2047 / (65536 * 8), rel=1e-4)
            page.click("#motion-0-ror")
            one = b.client(1)
            wait_until(lambda: gap(one, ACTUAL_SPEED) == 2047, "PD86-1180 motor at 2047")
        finally:
            page.close()
        assert not messages, messages
