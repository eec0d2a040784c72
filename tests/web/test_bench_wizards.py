"""The set-up wizards (issue 31 item 2, docs/dashboard.md "Set-up wizards") through their UI on virtual
modules, confirmed with GAP/GGP over a TCP connection of the same bus: the motor in rpm and mA,
the reference search run on a stage with switches, the encoder; nothing sent before Apply, Cancel
writes back what Apply changed, Finish stores in the EEPROM where the module has STAP."""
from __future__ import annotations

import pytest

from .benchkit import STAGE, TIMEOUT_MS, console_has, fresh_page, served, wait_until

GAP, GGP = 6, 10


@pytest.fixture(scope="module")
def bus():
    with served(("TMCM-6212", 1, STAGE), ("PD86-1180", 2, None)) as b:
        yield b


@pytest.fixture
def six(browser, bus):
    with fresh_page(browser, bus, 1, view="setup") as (page, messages):
        yield page, bus.client(1)
        assert not messages, messages


@pytest.fixture
def pd86(browser, bus):
    with fresh_page(browser, bus, 2, view="setup") as (page, messages):
        yield page, bus.client(2)
        assert not messages, messages


def gap(m, number: int, axis: int) -> int:
    return m.client.reply(GAP, number, axis).value


def start(page, wizard: str, axis: int) -> None:
    page.select_option("#wizard-axis", str(axis))
    page.click(f"#wizard-open-{wizard}")
    page.wait_for_selector("#wizard-next", timeout=TIMEOUT_MS)


def next_step(page, wait_for: str) -> None:
    page.click("#wizard-next")
    page.wait_for_selector(wait_for, timeout=TIMEOUT_MS)


def commands(page) -> list[str]:
    return page.eval_on_selector_all("#wizard-commands code", "cs => cs.map(c => c.textContent)")


def test_motor_set_up_in_rpm_and_ma(six):
    """TMCM-6212 manual 1: "up to 1.1A RMS", AP6 "255 means 100%", "adjusted in 32 steps": 550 mA is
    step 15 of 32 (16/32 of 1100 mA), AP6 = 127, its top; 100 mA is step 2 (103 mA), AP7 = 23.
    Manual 6.5: with 200 full steps and 256 microsteps "51200pps will result in 1rps (60rpm)": 120 rpm
    is AP4 = 102400 pps, 120 rpm/s (2 rps^2) AP5 = 102400 pps^2. The review lists exactly these SAPs;
    nothing reaches the module before Apply."""
    page, m = six
    start(page, "motor", 1)
    next_step(page, "#wiz-run-ma")
    assert "1100 mA RMS" in page.inner_text("#wiz-current-scale")
    page.fill("#wiz-run-ma", "550")
    page.fill("#wiz-standby-ma", "100")
    next_step(page, "#wiz-velocity")
    page.select_option("#wiz-units-1-kind", "rpm")
    page.click("#wiz-units-1-save")
    page.wait_for_function("document.querySelector('#wiz-velocity').parentElement.textContent.includes('rpm')", timeout=TIMEOUT_MS)
    assert page.input_value("#wiz-velocity") == "60"   # AP4's default 51200 pps
    page.fill("#wiz-velocity", "120")
    page.fill("#wiz-accel", "120")
    next_step(page, "#wizard-apply")
    assert commands(page) == ["SAP 6, 1, 127", "SAP 7, 1, 23", "SAP 4, 1, 102400", "SAP 5, 1, 102400"]
    assert [gap(m, n, 1) for n in (6, 7, 4, 5)] == [128, 8, 51200, 51200]   # nothing sent yet
    page.click("#wizard-apply")
    page.wait_for_selector("#wizard-finish", timeout=TIMEOUT_MS)
    assert [gap(m, n, 1) for n in (6, 7, 4, 5)] == [127, 23, 102400, 102400]
    assert page.is_disabled("#wizard-store") and "no STAP" in page.inner_text("#wizard-panel")
    page.click("#wizard-finish")
    console_has(page, "Motor wizard finished")
    page.wait_for_function("document.getElementById('axis-1-max_current').textContent === '550 mA (127)'", timeout=TIMEOUT_MS)


def test_microstep_resolution_changes_the_pps_of_an_rpm(six):
    """Manual 6.5: v_pps = v_rps * r_fullstep * r_microstep. At 16 microsteps (AP140 = 4) 60 rpm is
    200 * 16 = 3200 pps, and the wizard sends AP140 with it."""
    page, m = six
    start(page, "motor", 3)
    page.select_option("#wiz-microsteps", "4")
    next_step(page, "#wiz-run-ma")
    next_step(page, "#wiz-velocity")
    page.select_option("#wiz-units-3-kind", "rpm")
    page.click("#wiz-units-3-save")
    page.wait_for_function("document.querySelector('#wiz-velocity').parentElement.textContent.includes('rpm')", timeout=TIMEOUT_MS)
    page.fill("#wiz-velocity", "60")
    next_step(page, "#wizard-apply")
    assert commands(page) == ["SAP 140, 3, 4", "SAP 4, 3, 3200", "SAP 5, 3, 3200"]  # currents as they were
    page.click("#wizard-apply")
    page.wait_for_selector("#wizard-finish", timeout=TIMEOUT_MS)
    assert [gap(m, n, 3) for n in (140, 4, 6)] == [4, 3200, 128]
    page.click("#wizard-finish")


def test_cancel_at_any_step_leaves_nothing_applied(six):
    """Issue 31: a wizard "can be cancelled at any step without leaving anything half-applied".
    Cancel before Apply sends nothing; Cancel after Apply writes the old values back."""
    page, m = six
    start(page, "motor", 2)
    next_step(page, "#wiz-run-ma")
    page.fill("#wiz-run-ma", "1100")
    page.click("#wizard-cancel")
    console_has(page, "Motor cancelled: nothing was sent")
    assert "SAP" not in page.inner_text("#console-log") and gap(m, 6, 2) == 128
    start(page, "motor", 2)
    next_step(page, "#wiz-run-ma")
    page.fill("#wiz-run-ma", "1100")
    next_step(page, "#wiz-velocity")
    next_step(page, "#wizard-apply")
    assert commands(page) == ["SAP 6, 2, 255"]  # the last valid value: 100 % of the maximum
    page.click("#wizard-apply")
    wait_until(lambda: gap(m, 6, 2) == 255, "AP6 = 255 applied")
    page.wait_for_selector("#wizard-applied", timeout=TIMEOUT_MS)  # the page has the old values to write back
    page.click("#wizard-cancel")
    console_has(page, "Motor cancelled: 1 value(s) written back")
    assert gap(m, 6, 2) == 128


def test_reference_search_set_up_and_run(six):
    """TMCM-6212 manual 6.1: AP193 mode 1 "search left stop switch only"; AP194 search speed, AP195
    "It should be slower than parameter 194". The stage of examples/scenarios/tmcm6212_stage.toml has
    its left switch at -50000: the wizard sets mode 1 and the speeds in rpm (90 rpm = 76800 pps,
    12 rpm = 10240 pps), runs RFS START, the left switch's lamp comes on during the search, and at
    its end RFS STATUS is 0, the position 0 and AP197 (last reference position) -50000."""
    page, m = six
    start(page, "reference", 0)
    assert "search left stop switch only" in page.inner_text("#wiz-modes")
    page.check("#wiz-mode-1")
    next_step(page, "#wiz-polarity-24")
    page.wait_for_selector("#wiz-switch-left", timeout=TIMEOUT_MS)
    next_step(page, "#wiz-search-speed")
    page.select_option("#wiz-units-0-kind", "rpm")
    page.click("#wiz-units-0-save")
    page.wait_for_function("document.querySelector('#wiz-search-speed').parentElement.textContent.includes('rpm')", timeout=TIMEOUT_MS)
    page.fill("#wiz-search-speed", "12")
    page.fill("#wiz-switch-speed", "90")
    page.click("#wizard-next")
    assert "slower than the search speed" in page.inner_text("#wizard-error")
    page.fill("#wiz-search-speed", "90")
    page.fill("#wiz-switch-speed", "12")
    next_step(page, "#wizard-apply")
    assert commands(page) == ["SAP 194, 0, 76800", "SAP 195, 0, 10240"]  # mode 1 and polarities: already so
    page.click("#wizard-apply")
    page.wait_for_selector("#wiz-rfs-start", timeout=TIMEOUT_MS)
    assert [gap(m, n, 0) for n in (193, 194, 195)] == [1, 76800, 10240]
    page.click("#wiz-rfs-start")
    console_has(page, "> RFS START, 0")
    page.wait_for_selector("#wiz-switch-left.on", timeout=TIMEOUT_MS)  # the search reaches the switch
    wait_until(lambda: m.client.reply(13, 2, 0).value == 0 and gap(m, 1, 0) == 0, "the search ends at the origin")
    assert abs(gap(m, 197, 0) + 50000) <= 1
    page.wait_for_function("document.getElementById('wiz-rfs-status').textContent === 'done: the origin is set'",
                           timeout=TIMEOUT_MS)
    page.click("#wizard-finish")
    console_has(page, "Reference search wizard finished")


def test_reference_search_switch_polarity_of_the_pd86_1180(pd86):
    """PD86-1180 manual 5/6: the end switch polarity is GP79 (bank 0), modes 1..3 (7.1). The
    wizard writes SAP 193 and SGP 79 together; Cancel after Apply writes both back."""
    page, m = pd86
    start(page, "reference", 0)
    page.check("#wiz-mode-2")
    next_step(page, "#wiz-polarity-79")
    page.check("#wiz-polarity-79")
    next_step(page, "#wiz-search-speed")
    next_step(page, "#wizard-apply")
    assert commands(page) == ["SAP 193, 0, 2", "SGP 79, 0, 1"]
    page.click("#wizard-apply")
    wait_until(lambda: m.client.reply(GGP, 79, 0).value == 1 and gap(m, 193, 0) == 2, "mode 2 and GP79 = 1")
    page.wait_for_selector("#wizard-applied", timeout=TIMEOUT_MS)  # the page has the old values to write back
    page.click("#wizard-cancel")
    console_has(page, "Reference search cancelled: 2 value(s) written back")
    assert m.client.reply(GGP, 79, 0).value == 0 and gap(m, 193, 0) == 1


def test_motor_currents_stored_in_the_eeprom_of_the_pd86_1180(pd86):
    """PD86-1180 manual 5 AP6: I_RMS = value * 6.6 A / 255, so 2000 mA is AP6 = 77 (1993 mA); the
    module has STAP (4.6.7): Finish with "store" sends STAP 6, 0 and RSAP 6 (4.6.8) after another
    value brings 77 back."""
    page, m = pd86
    start(page, "motor", 0)
    next_step(page, "#wiz-run-ma")
    assert "6600 mA RMS" in page.inner_text("#wiz-current-scale")
    page.fill("#wiz-run-ma", "2000")
    next_step(page, "#wiz-velocity")
    next_step(page, "#wizard-apply")
    assert commands(page) == ["SAP 6, 0, 77"]
    page.click("#wizard-apply")
    page.wait_for_selector("#wizard-finish", timeout=TIMEOUT_MS)
    assert "STAP 6, 0" in page.inner_text("#wizard-panel")
    page.check("#wizard-store")
    page.click("#wizard-finish")
    console_has(page, "stored: STAP 6, 0")
    m.client.request(5, 6, 0, 10)
    m.client.request(8, 6, 0, 0)  # RSAP 6, 0
    assert gap(m, 6, 0) == 77


def test_encoder_resolution_and_deviation(six):
    """TMCM-6212 manual 6.2: AP210 "encoder resolution (as encoder counts per round)", AP212 stops
    the motor beyond the deviation (0: off). The check step compares AP1 and AP209."""
    page, m = six
    start(page, "encoder", 4)
    page.fill("#wiz-encoder", "4000")
    next_step(page, "#wiz-deviation")
    page.fill("#wiz-deviation", "500")
    next_step(page, "#wizard-apply")
    assert commands(page) == ["SAP 210, 4, 4000", "SAP 212, 4, 500"]
    page.click("#wizard-apply")
    page.wait_for_function("document.getElementById('wiz-enc-diff') && document.getElementById('wiz-enc-diff').textContent !== '-'",
                           timeout=TIMEOUT_MS)
    assert [gap(m, 210, 4), gap(m, 212, 4)] == [4000, 500]
    page.click("#wizard-finish")


def test_encoder_prescaler_of_the_pd86_1180(pd86):
    """PD86-1180 manual 7.2: the prescaler is p/512; the sensOstep encoder has 256 counts per round,
    so at 16 microsteps (AP140 = 4, 3200 per round) p = 6400 ("6400 default 12.5 ... 4 (16
    microsteps)"); + 4 "Clear encoder with next null channel event"."""
    page, m = pd86
    start(page, "encoder", 0)
    page.fill("#wiz-encoder", "0")
    page.click("#wiz-encoder-match")
    assert page.input_value("#wiz-encoder") == "6400"
    page.check("#wiz-encoder-null")
    next_step(page, "#wiz-deviation")
    page.fill("#wiz-deviation", "100")
    next_step(page, "#wizard-apply")
    assert commands(page) == ["SAP 210, 0, 6404", "SAP 212, 0, 100"]
    page.click("#wizard-apply")
    wait_until(lambda: gap(m, 210, 0) == 6404 and gap(m, 212, 0) == 100, "AP210 = 6404, AP212 = 100")
    page.wait_for_selector("#wizard-applied", timeout=TIMEOUT_MS)  # the page has the old values to write back
    page.click("#wizard-cancel")
    wait_until(lambda: gap(m, 210, 0) == 6400 and gap(m, 212, 0) == 0, "written back")
