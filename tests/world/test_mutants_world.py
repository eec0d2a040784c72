"""Edges of the axis world left unpinned by the seeded firmware mutation sample of round 21
(docs/mutation.md, `python bench/mutation.py --layer firmware --sample 150 --seed 12`)."""
from __future__ import annotations


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


def test_stop_on_stall_speed_in_internal_units(rig):
    """TMCM-6212 manual 4.1 AP181 "Above this speed motor will stop in case stallGuard2 load value
    reaches zero" and AP255 "0 - the internal units of the TMC5130 are used directly": with
    AP255 = 0 the stall speed is an internal velocity like the ROR speed (v * 16 MHz / 2^24 pps). ROR
    20000 (19073 pps) into a load step at 10000 stops there with AP181 = 19500 (18597 pps, below the
    speed; AP207 bit 0 "stallGuard error"), and runs on with AP181 = 21000 (above it)."""
    got = {}
    for limit in (19500, 21000):
        r = rig("TMCM-6212", {"axis": {"0": {"load": {"steps": [[10000, 0.6]], "before": 0.1}}}})
        r.sap(255, 0)
        r.sap(181, limit)
        r.sap(174, 0)
        r.cmd(1, 0, 0, 20000)
        r.vm.advance(2)
        got[limit] = (r.gap(3) == 0, r.gap(1) == 10000, r.gap(207))
    assert got == {19500: (True, True, 1), 21000: (False, False, 0)}


def test_a_stall_moving_left_stops_at_the_first_position_of_the_heavier_load(rig):
    """TMCM-6212 manual 4.1 AP181 "Above this speed motor will stop in case stallGuard2 load value
    reaches zero"; docs/world.md "Time: events, never steps": the positions where a load over
    position steps are events, in both directions. The stage starts at 20000 above a step at 10000
    whose load below (0.6) the motor cannot hold (C = 17/32): ROL stops it exactly at 9999, the
    first position of the heavier load, with AP207 bit 0 "stallGuard error" - as moving right over
    a step up stops at 10000 (tests/world/test_load.py)."""
    r = rig("TMCM-6212", {"axis": {"0": {"start": 20000, "load": {"steps": [[10000, 0.1]], "before": 0.6}}}})
    r.sap(181, 1000)
    r.sap(174, 0)
    r.cmd(2, 0, 0, 20000)
    r.vm.advance(2)
    assert (r.gap(3), r.phys(), r.gap(1), r.gap(207)) == (0, 9999, 9999 - 20000, 1)


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
