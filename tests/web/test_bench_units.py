"""Units everywhere (issue 31 item 4, docs/dashboard.md "Units"): rps/rpm and a user scale (mm with a
lead and a gear) per axis, currents in mA from the module's current scale, analog inputs in volts
where a profile gives the scale, and a logarithmic jog slider. Every command's effect is confirmed
with GAP over a TCP connection of the same bus."""
from __future__ import annotations

import math

import pytest

from .benchkit import TIMEOUT_MS, console_has, fresh_page, open_view, served, wait_until

GAP = 6


@pytest.fixture(scope="module")
def bus():
    with served(("TMCM-6212", 1, None)) as b:
        yield b


@pytest.fixture
def motion(browser, bus):
    with fresh_page(browser, bus, view="motion") as (page, messages):
        page.wait_for_function("document.getElementById('motion-5-rfs').textContent !== '-'", timeout=TIMEOUT_MS)
        yield page, bus.client(1)
        assert not messages, messages


def gap(m, number: int, axis: int) -> int:
    return m.client.reply(GAP, number, axis).value


def set_units(page, axis: int, kind: str, **user: object) -> None:
    page.select_option(f"#units-{axis}-kind", kind)
    for key, value in user.items():
        page.fill(f"#units-{axis}-{key.replace('_', '-')}", str(value))
    page.click(f"#units-{axis}-save")
    page.wait_for_function(f"OpenTMCL.units.setting({axis}).kind === {kind!r}", timeout=TIMEOUT_MS)


def test_velocity_in_rpm(motion):
    """TMCM-6212 manual 6.5: 200 full steps, 256 microsteps: "51200pps will result in 1rps (60rpm)".
    With rpm chosen for axis 0 the velocity field shows AP4's 51200 pps as 60 rpm, and 30 rpm
    turns the motor at 25600 pps (ROR 0, 25600; manual 3.6.1); the axis card follows in rpm."""
    page, six = motion
    set_units(page, 0, "rpm")
    page.wait_for_function("document.getElementById('motion-0-unit').textContent === 'rpm'", timeout=TIMEOUT_MS)
    assert page.input_value("#motion-0-velocity") == "60"
    assert page.inner_text("#motion-0-velocity-raw") == "= 51200 pps"
    page.fill("#motion-0-velocity", "30")
    page.click("#motion-0-ror")
    console_has(page, "> ROR 0, 25600")
    wait_until(lambda: gap(six, 3, 0) == 25600, "axis 0 at 25600 pps")
    page.wait_for_function("document.getElementById('axis-0-velocity').textContent === '30'", timeout=TIMEOUT_MS)
    assert page.inner_text("#axis-0-velocity-unit") == "[rpm]"
    page.click("#motion-0-mst")
    wait_until(lambda: gap(six, 3, 0) == 0, "axis 0 stopped")


def test_positions_in_a_user_scale_kept_with_the_export(motion):
    """A lead screw of 5 mm per round behind a 2:1 gear: 1 mm is 0.4 motor rounds, 0.4 * 51200 =
    20480 microsteps (MVP ABS, 1, 20480; manual 3.6.4); the read-outs show mm, and the parameter
    export carries the setting (a "units" list beside the parameters)."""
    page, six = motion
    set_units(page, 1, "user", name="mm", per_round=5, gear=2)
    page.wait_for_function("document.getElementById('motion-1-target-unit').textContent === 'mm'", timeout=TIMEOUT_MS)
    page.fill("#motion-1-target", "1")
    page.click("#motion-1-abs")
    console_has(page, "> MVP ABS, 1, 20480")
    wait_until(lambda: gap(six, 1, 1) == 20480, "axis 1 at 20480 microsteps")
    page.wait_for_function("document.getElementById('motion-1-position').textContent === '1 mm'", timeout=TIMEOUT_MS)
    exported = page.evaluate("fetch('api/params/export?format=json').then(r => r.json())")
    assert exported["units"] == [{"axis": 1, "kind": "user", "name": "mm", "per_round": 5.0, "gear": 2.0}]


def test_jog_slider_is_logarithmic(motion):
    """Issue 31 item 4: the linear slider over 0...7999774 (AP2's range, manual 4.1) put 51200 at
    0.6 % of its travel. Now 0 is standstill, the other 1000 steps spread from 1 pps to 7999774:
    51200 sits at ln(51200)/ln(7999774) = 68 % of the travel, the middle is sqrt(7999774) = 2828
    pps (ROR 2, 2828), the right end the maximum."""
    page, six = motion
    assert page.input_value("#motion-2-slider") == str(round(math.log(51200) / math.log(7999774) * 1000))

    def slide(value: int) -> str:
        page.evaluate(f"(() => {{ const s = document.getElementById('motion-2-slider'); s.value = '{value}';"
                      f" s.dispatchEvent(new Event('input')); }})()")
        return page.input_value("#motion-2-velocity")

    assert (slide(0), slide(1), slide(1000)) == ("0", "1", "7999774")
    assert slide(500) == str(round(math.sqrt(7999774)))
    page.click("#motion-2-ror")
    console_has(page, "> ROR 2, 2828")
    wait_until(lambda: gap(six, 2, 2) == 2828, "AP2 = 2828")
    page.click("#motion-2-mst")


def test_currents_in_ma_on_the_cards_and_the_parameter_table(motion):
    """TMCM-6212 manual 1 "up to 1.1A RMS"; 4.1 AP6 "255 means 100%", 32 steps; AP180 "0...31: 1/32,
    2/32, ... 32/32": the default AP6 = 128 (step 16) is 17/32 of 1100 mA = 584 mA, 255 (the last
    valid value) 1100 mA; AP180 n is (n + 1)/32 of 1100 mA. The parameter table shows them too."""
    page, six = motion
    open_view(page, "overview")
    page.wait_for_function("document.getElementById('axis-3-max_current').textContent === '584 mA (128)'", timeout=TIMEOUT_MS)
    six.client.request(5, 6, 3, 255)
    page.wait_for_function("document.getElementById('axis-3-max_current').textContent === '1100 mA (255)'", timeout=TIMEOUT_MS)
    n = gap(six, 180, 4)
    assert page.inner_text("#axis-4-current") == f"{round((n + 1) / 32 * 1100)} mA ({n})"
    set_units_in_motion = page.evaluate("OpenTMCL.units.set(4, {kind: 'rps'})")
    assert set_units_in_motion is None
    open_view(page, "parameters")
    page.select_option("#param-axis", "4")
    page.wait_for_function("document.getElementById('param-axis-4-phys') && "
                           "document.getElementById('param-axis-4-phys').textContent === '1 rps'", timeout=TIMEOUT_MS)
    assert page.inner_text("#param-axis-6-phys") == "584 mA"
    assert page.inner_text("#param-axis-5-phys") == "1 rps²"


def test_analog_inputs_in_counts_without_a_scale(motion):
    """TMCM-6212 manual 3.6.13: the ADC channels "deliver their 16 bit result in the range of
    0...65535", with no voltage scale: the page says so and shows counts."""
    page, _ = motion
    open_view(page, "io")
    page.wait_for_function("document.getElementById('io-val-1-0').textContent.endsWith('counts')", timeout=TIMEOUT_MS)
    assert page.inner_text("#io-analog-scale") == "Analog inputs in ADC counts: the TMCM-6212 manual gives no voltage scale for them."


def test_analog_inputs_in_volts_where_a_profile_gives_the_scale(browser, tmp_path):
    """A user profile (docs/profiles.md) that gives `analog_full_scale_volts = 10`: the analog input
    forced to 32768 of 65535 reads 5 V."""
    path = tmp_path / "my6212.toml"
    path.write_text('extends = "TMCM-6212"\n[module]\nname = "MY-6212"\nanalog_full_scale_volts = 10.0\n')
    with served((str(path), 1, None)) as b, fresh_page(browser, b, view="io") as (page, messages):
        page.fill("#io-force-1-0", "32768")
        page.click("#io-force-1-0 + button")
        console_has(page, "> force IN0 (bank 1, port 0) to 32768 (virtual module)")
        page.wait_for_function("document.getElementById('io-val-1-0').textContent === '5 V (32768) (forced)'", timeout=TIMEOUT_MS)
        assert b.client(1).client.reply(15, 0, 1).value == 32768
        assert "full scale 10 V" in page.inner_text("#io-analog-scale")
        assert not messages, messages
