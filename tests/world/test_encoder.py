"""The encoder of a virtual axis: AP209 encoder position, AP210 encoder prescaler and the full steps
of AP202 it converts with (TMCM-6212 manual 6.2), the PD86-1180's sensOstep prescaler p / 512 and its
"Clear encoder with next null channel event" (PD86-1180 manual 7.2)."""
from __future__ import annotations


def test_encoder_follows_the_stage_and_is_writable(rig):
    """TMCM-6212 manual 6.2: with AP202 and AP210 set "the encoder position is the same as the
    motor position"; AP209 "is also writable, e.g. for setting a new origin"."""
    r = rig("TMCM-6212", {})
    r.cmd(4, 0, 0, 12345)
    r.vm.advance(2)
    assert r.gap(209) == 12345
    r.sap(209, 100)
    assert r.gap(209) == 100
    r.sap(210, 4000)                   # a 1000-line encoder: 4000 counts per round
    r.cmd(4, 0, 0, 12345 + 1000)
    r.vm.advance(1)
    assert abs(r.gap(209) - (100 + 1000)) < 13   # resolution 51200 / 4000 = 12.8 microsteps


def test_encoder_matches_the_motor_only_with_the_right_ap210(rig):
    """TMCM-6212 manual 6.2: "When parameters #202 and #210 are set to the right values the
    module will automatically convert the encoder resolution to the motor microstep resolution
    so that the encoder position is the same as the motor position" - a 1000-line encoder
    (4000 counts per round, scenario) read with the default AP210 = 51200 counts one round of
    51200 microsteps as 4000; AP210 = 4000 makes it read 51200; the wrong value trips AP212."""
    sc = {"axis": {"0": {"encoder": {"counts_per_round": 4000}}}}
    r = rig("TMCM-6212", sc)
    r.cmd(4, 0, 0, 51200)
    r.vm.advance(3)
    assert r.gap(1) == 51200
    assert r.gap(209) == 4000
    r.sap(210, 4000)
    assert r.gap(209) == 51200
    r = rig("TMCM-6212", sc)
    r.sap(212, 1000)
    r.cmd(4, 0, 0, 51200)
    r.vm.advance(3)
    assert r.gap(3) == 0 and r.gap(1) < 51200
    assert r.gap(207) == 2


def test_6212_encoder_conversion_uses_the_full_steps_of_ap202(rig):
    """TMCM-6212 manual 6.2: "Set the motor full step resolution using parameter #202 (for 1.8°
    motors this is 200 which is also the default value ...)" and "When parameters #202 and #210 are
    set to the right values the module will automatically convert the encoder resolution to the
    motor microstep resolution so that the encoder position is the same as the motor position": a
    0.9° motor (400 full steps, scenario) with a 4000-count encoder, AP202 = 400 and AP210 = 4000,
    reads one round (400 * 256 = 102400 microsteps) as 102400; with the default AP202 = 200 the
    conversion turns the 4000 counts of a round into 200 * 256 = 51200 microsteps: half the motor
    position."""
    sc = {"axis": {"0": {"fullsteps_per_round": 400, "encoder": {"counts_per_round": 4000}}}}
    r = rig("TMCM-6212", sc)
    r.sap(210, 4000)
    r.sap(4, 100000)
    r.cmd(4, 0, 0, 102400)
    r.vm.advance(4)
    assert r.gap(1) == 102400
    assert r.gap(209) == 102400 // 2    # AP202 still 200: wrong value, wrong reading
    r.sap(202, 400)
    assert r.gap(202) == 400
    assert r.gap(209) == 102400
    r.cmd(4, 0, 0, 102400 + 25600)     # a quarter round more
    r.vm.advance(2)
    assert r.gap(1) == r.gap(209) == 128000


def test_6212_encoder_without_ap202_converts_with_200_full_steps(rig, tmp_path):
    """TMCM-6212 manual 6.2: "Set the motor full step resolution using parameter #202 (for 1.8°
    motors this is 200 which is also the default value ...)". A profile that removes AP202
    (docs/profiles.md `[remove]`; GAP 202 is then status 3, "wrong type") keeps the encoder
    conversion of the default: one round of 200 * 256 = 51200 microsteps with AP210 = 51200 reads
    51200, the same as the built-in TMCM-6212."""
    path = tmp_path / "no202.toml"
    path.write_text('extends = "TMCM-6212"\n[module]\nname = "NO202-6212"\n'
                    "[remove]\naxis_parameter = [202]\n")
    for name in ("TMCM-6212", str(path)):
        r = rig(name, {})
        r.sap(4, 100000)
        r.cmd(4, 0, 0, 51200)
        r.vm.advance(4)
        assert (r.gap(1), r.gap(210), r.gap(209)) == (51200, 51200, 51200), name
    assert r.vm.request(6, 202, 0).status == 3


def test_1180_encoder_prescaler(rig):
    """PD86-1180 manual 7.2: prescaler = p / 512 on the 256-count sensOstep encoder; p = 6400
    (12.5) with 16 microsteps makes the encoder read microsteps; p = 3200 reads half of it."""
    r = rig("TMCM-1180", {})
    r.cmd(4, 0, 0, 3200)               # one round at 16 microsteps
    r.vm.advance(20)
    assert r.gap(1) == 3200
    assert r.gap(209) == 3200
    r.sap(210, 3200)
    assert r.gap(209) == 1600


def test_1180_an_odd_encoder_prescaler_counts_with_its_own_value(rig):
    """PD86-1180 manual 7.2: "Other values between those given in the table can be used" for the
    encoder prescaler `<p>` (AP210), prescaler = p / 512, 6400 the default. p = 6401 (odd: bit 0
    is part of the value, only the special-function bits are flags) reads 100000 microsteps as
    floor(100000 * 6401 / 6400) = 100015, p = 6400 as 100000."""
    got = {}
    for p in (6400, 6401):
        r = rig("PD86-1180", {})
        r.sap(210, p)
        r.cmd(4, 0, 0, 100000)
        r.vm.advance(5)
        got[p] = (r.gap(1), r.gap(209))
    assert got == {6400: (100000, 100000), 6401: (100000, 100015)}


def test_1180_clear_encoder_on_null_channel(rig):
    """PD86-1180 manual 7.2: adding 4 to p "Clear encoder with next null channel event" (the
    null channel comes once per round)."""
    r = rig("TMCM-1180", {"axis": {"0": {"start": 100}}})
    r.sap(210, 6400 + 4)
    r.cmd(4, 0, 0, 5000)
    r.vm.advance(30)
    assert r.gap(1) == 5000
    assert r.gap(209) == 5000 + 100 - 3200   # cleared where the stage passed 3200


def test_1180_null_channel_clear_keeps_an_odd_prescaler(rig):
    """PD86-1180 manual 7.2: "Other values between those given in the table can be used" for the
    prescaler <p>, and "just add the following value to <p>: ... 4 Clear encoder with next null
    channel event": once the encoder is cleared, AP210 is the prescaler 6401 without the adder."""
    r = rig("TMCM-1180", {"axis": {"0": {"start": 100}}})
    r.sap(210, 6401 + 4)
    r.cmd(4, 0, 0, 5000)
    r.vm.advance(30)
    assert r.gap(1) == 5000
    assert r.gap(210) == 6401
