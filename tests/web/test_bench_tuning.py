"""The tuning view (issue 31 item 1, docs/dashboard.md "Tuning"): the stallGuard2 and coolStep tools
of a virtual TMCM-6212 driven through their UI, every effect confirmed with GAP over a TCP
connection of the same bus (not through the dashboard). The load comes from the world of the
virtual module (docs/world.md: AP206 = 1023 * (1 - L / C) + 16 * AP174, clamped to 0..1023)."""
from __future__ import annotations

import re

import pytest

from .benchkit import TIMEOUT_MS, console_has, fresh_page, open_view, served, wait_until

GAP = 6


@pytest.fixture(scope="module")
def bus():
    with served(("TMCM-6212", 1, None)) as b:
        yield b


@pytest.fixture
def tuning(browser, bus):
    with fresh_page(browser, bus, view="tuning") as (page, messages):
        yield page, bus.client(1)
        assert not messages, messages


def gap(m, number: int, axis: int) -> int:
    return m.client.reply(GAP, number, axis).value


def choose_axis(page, axis: int) -> None:
    page.select_option("#tune-axis", str(axis))
    page.wait_for_function(f"window.dashboard.tuning.axis === {axis} && window.dashboard.tuning.values[174] !== undefined",
                           timeout=TIMEOUT_MS)


def test_stallguard2_tuned_so_that_an_applied_load_stops_the_axis(tuning):
    """Manual 6.3 / 4.1: stall detection "is configured mainly using axis parameters #174 and #181";
    AP181: "Above this speed motor will stop in case stallGuard2 load value reaches zero", AP173
    enables the filter. The guided steps on axis 2: run at 51200 pps, apply a load of 0.45 of the
    full-current torque (AP206 falls to about 127 with AP174 = 0), lower the threshold to -8 (AP206
    reads 0, the axis still turns: AP181 = 0 stops nothing), then AP181 = half the working speed
    stops the axis; the stall indicator shows it (AP207 bit 0, "stallGuard error")."""
    page, six = tuning
    choose_axis(page, 2)
    page.fill("#sg-work-speed", "51200")
    page.click("#sg-run")
    console_has(page, "> ROR 2, 51200")
    wait_until(lambda: gap(six, 3, 2) == 51200, "axis 2 at the working speed")
    page.fill("#sg-load", "0.45")
    page.click("#sg-load-apply")
    wait_until(lambda: 0 < gap(six, 206, 2) < 200, "the load value falls under the load")
    page.check("#sg-filter")
    wait_until(lambda: gap(six, 173, 2) == 1, "AP173 = 1 (filtered mode)")
    page.uncheck("#sg-filter")
    wait_until(lambda: gap(six, 173, 2) == 0, "AP173 = 0 (standard mode)")
    page.fill("#sg-threshold", "-8")
    page.click("#sg-threshold-set")
    console_has(page, "> SAP 174, 2, -8")
    wait_until(lambda: gap(six, 174, 2) == -8, "AP174 = -8")
    assert gap(six, 206, 2) == 0 and gap(six, 3, 2) == 51200  # a stall reading, not stopped yet
    page.wait_for_function("document.getElementById('tune-sg').textContent === '0'", timeout=TIMEOUT_MS)
    page.click("#sg-stop-half")
    wait_until(lambda: gap(six, 181, 2) == 25600, "AP181 = 25600")
    wait_until(lambda: gap(six, 3, 2) == 0, "the stall stops axis 2")
    page.wait_for_function("document.getElementById('tune-stall').textContent === 'STALL'", timeout=TIMEOUT_MS)
    assert page.evaluate("window.dashboard.tuning.rows.some(r => r.sg === 0 && Math.abs(r.v) >= 25600)")


def test_false_stall_check(tuning):
    """The manual's last step, "check for false stalls": without a load, from standstill, at the
    working speed. AP174 = -64 (its last valid value, the most sensitive) takes 1024 from every
    reading, so even the free motor reads 0 and stops: the check reports a false stall. With -8 it
    reports none, and the axis is stopped (MST) at its end."""
    page, six = tuning
    choose_axis(page, 1)
    page.fill("#sg-work-speed", "51200")
    page.fill("#sg-check-seconds", "1")
    page.fill("#sg-threshold", "-64")
    page.click("#sg-threshold-set")
    wait_until(lambda: gap(six, 174, 1) == -64, "AP174 = -64")
    page.click("#sg-stop-half")
    wait_until(lambda: gap(six, 181, 1) == 25600, "AP181 = 25600")
    page.click("#sg-check")
    page.wait_for_function("document.getElementById('sg-check-result').className === 'err'", timeout=TIMEOUT_MS)
    assert "false stall" in page.inner_text("#sg-check-result")
    page.fill("#sg-threshold", "-8")
    page.click("#sg-threshold-set")
    wait_until(lambda: gap(six, 174, 1) == -8, "AP174 = -8")
    page.click("#sg-check")
    page.wait_for_function("document.getElementById('sg-check-result').className === 'ok'", timeout=TIMEOUT_MS)
    assert page.inner_text("#sg-check-result") == "no stall in 1 s at the working speed"
    console_has(page, "> ROR 1, 51200")
    wait_until(lambda: gap(six, 2, 1) == 0 and gap(six, 3, 1) == 0, "MST at the end of the check")


def test_coolstep_fields_chosen_survive_a_read_until_applied(tuning):
    """docs/dashboard.md "Tuning": coolStep's fields (SEMIN AP172, SEMAX AP170, manual 4.1) are
    written together by Apply. Choices made before it stay on the page when the view reads the
    module's values again (here: another view and back), and nothing is written meanwhile; the
    meaning follows them: (1 + 2 + 1) * 32 = 128."""
    page, six = tuning
    choose_axis(page, 2)
    page.wait_for_selector("#cs-semin", timeout=TIMEOUT_MS)
    page.select_option("#cs-semin", "1")
    page.select_option("#cs-semax", "2")
    page.evaluate("document.getElementById('cs-semin').dataset.before = 'yes'")  # gone once the table is drawn again
    open_view(page, "motion")
    open_view(page, "tuning")
    page.wait_for_function("document.getElementById('cs-semin') && !document.getElementById('cs-semin').dataset.before",
                           timeout=TIMEOUT_MS)
    assert page.input_value("#cs-semin") == "1" and page.input_value("#cs-semax") == "2"
    assert page.inner_text("#cs-semax-meaning").startswith("upper threshold 128")
    assert [gap(six, n, 2) for n in (172, 170)] == [0, 0]


def test_coolstep_lowers_the_current_and_shows_the_energy_saved(tuning):
    """Manual 4.1 AP168-172 and 1.2: "coolStep is a load-adaptive automatic current scaling". SEMIN
    = AP172 = 1 (lower threshold 32), SEMAX = AP170 = 2 (upper threshold (1 + 2 + 1) * 32 = 128),
    SEDN = AP169 = 3 (a decrement per reading above it): an unloaded motor reads 1023, so the actual
    current AP180 falls below the run current scale (AP6 = 128: 16) towards SEIMIN's 1/2 of it. The
    energy line is 1 - mean(I^2) / I_run^2 over the samples while turning, I from AP180 and AP6 in
    mA (1100 mA RMS full scale, 32 steps)."""
    page, six = tuning
    choose_axis(page, 3)
    page.wait_for_selector("#cs-semin", timeout=TIMEOUT_MS)
    for name, value in (("semin", "1"), ("semax", "2"), ("sedn", "3"), ("seup", "0"), ("seimin", "0")):
        page.select_option(f"#cs-{name}", value)
    assert page.inner_text("#cs-semax-meaning").startswith("upper threshold 128")
    page.fill("#cs-speed", "0")
    page.click("#cs-apply")
    console_has(page, "coolStep settings applied (6 SAP)")
    assert [gap(six, n, 3) for n in (172, 170, 171, 169, 168, 182)] == [1, 2, 0, 3, 0, 0]
    page.fill("#sg-work-speed", "51200")
    page.click("#sg-run")
    wait_until(lambda: gap(six, 180, 3) < 16, "coolStep lowers AP180 below the run current scale")
    page.wait_for_function("/% lower/.test(document.getElementById('cs-energy').textContent) && "
                           "window.dashboard.tuning.saving > 0.1", timeout=TIMEOUT_MS)
    text = page.inner_text("#cs-energy")
    rows = page.evaluate("window.dashboard.tuning.rows.filter(s => s.v && s.cs !== null && s.run !== null)")

    def ma(n: int) -> float:
        return (n + 1) / 32 * 1100  # manual 4.1 AP180: "0...31: 1/32, 2/32, ... 32/32" of the full scale

    saving = 1 - sum(ma(r["cs"]) ** 2 for r in rows) / sum(ma(r["run"] >> 3) ** 2 for r in rows)
    shown = int(re.search(r"(-?\d+) % lower", text).group(1))
    assert abs(shown - round(saving * 100)) <= 3, (text, saving)  # samples may arrive between the two reads
    page.click("#sg-stop")
    wait_until(lambda: gap(six, 3, 3) == 0, "axis 3 stopped")


def test_seimin_meaning_and_write(tuning):
    """Manual 4.1 AP168 SEIMIN: "0 - 1/2 of CS, 1 - 1/4 of CS": the meaning follows the choice in
    mA of the run current (AP6 = 128: 17/32 of 1100 mA = 584 mA), and Apply writes it."""
    page, six = tuning
    choose_axis(page, 4)
    page.wait_for_selector("#cs-seimin", timeout=TIMEOUT_MS)
    assert page.inner_text("#cs-seimin-meaning") == "minimum current 1/2 of CS (about 292 mA of 584 mA)"
    page.select_option("#cs-seimin", "1")
    assert page.inner_text("#cs-seimin-meaning") == "minimum current 1/4 of CS (about 146 mA of 584 mA)"
    page.click("#cs-apply")
    wait_until(lambda: gap(six, 168, 4) == 1, "AP168 = 1")
