"""What the motor driver measures and does to the stage: AP29 measured speed, AP167 (TOFF) = 0
free-wheeling (TMCM-6212 manual 4.1), AP215 absolute encoder value (PD86-1180 manual 5)."""
from __future__ import annotations

V = 51200  # pps; the TMCM-6212's default AP5 accelerates to it in one second


def test_6212_measured_speed_follows_the_motor_signed(rig):
    """TMCM-6212 4.1 AP29 "Measured speed - Speed measured by the motor driver", 0 .. 7999774
    [pps]: the speed of the motor, 0 at rest; turning left reads negative like AP3 (the Range
    column gives the magnitude)."""
    r = rig("TMCM-6212", {})
    assert r.gap(29) == 0
    r.cmd(1, 0, 0, V)
    r.vm.advance(0.5)
    half = r.gap(29)
    assert 0 < half < V and half == r.gap(3)
    r.vm.advance(1.0)
    assert r.gap(29) == V
    r.cmd(2, 0, 0, V)
    r.vm.advance(3.0)
    assert r.gap(29) == -V
    r.cmd(3)
    r.vm.advance(2.0)
    assert r.gap(29) == 0


def test_6212_measured_speed_is_0_while_the_motor_is_blocked(rig):
    """AP29 is the real motor's speed: pushed into a mechanical end the step counter runs on
    (AP3 = V) while the rotor stands (docs/world.md step loss)."""
    r = rig("TMCM-6212", {"axis": {"0": {"ends": [None, 100000]}}})
    r.cmd(1, 0, 0, V)
    r.vm.advance(1.5)                            # 25600 + 25600: still free
    assert r.gap(29) == V
    r.vm.advance(2.0)
    assert r.gap(3) == V and r.phys() == 100000
    assert r.gap(29) == 0


def test_6212_toff_0_free_wheels_and_reenabling_continues_from_the_stage(rig):
    """TMCM-6212 4.1 AP167: "Setting this parameter to zero completely disables all driver
    transistors and the motor can free-wheel": the counter (AP1) moves, the stage and the encoder
    (AP209) stay; after re-enabling, motion continues from where the stage is."""
    r = rig("TMCM-6212", {})
    r.cmd(4, 1, 0, 20000)
    r.vm.advance(2.0)
    assert (r.gap(1), r.phys(), r.gap(209)) == (20000, 20000, 20000)
    r.sap(167, 0)
    r.cmd(4, 1, 0, 100000)
    r.vm.advance(1.0)
    assert r.gap(3) != 0 and r.gap(29) == 0      # the ramp runs, the rotor does not
    r.vm.advance(4.0)
    assert (r.gap(1), r.phys(), r.gap(209)) == (120000, 20000, 20000)
    r.sap(167, 3)                                # the default again
    r.cmd(4, 1, 0, 5000)
    r.vm.advance(2.0)
    assert (r.gap(1), r.phys(), r.gap(209)) == (125000, 25000, 25000)


def test_6212_toff_0_during_a_move_leaves_the_stage_where_it_was(rig):
    """AP167 = 0 in the middle of a rotation: the stage keeps the position it had at that
    moment, while the counter runs on; 1 (the last valid value above 0) re-enables."""
    r = rig("TMCM-6212", {})
    r.cmd(1, 0, 0, V)
    r.vm.advance(2.0)                            # 25600 + 51200
    r.sap(167, 0)
    at = r.gap(1)
    assert at == r.phys() == 76800
    r.vm.advance(1.0)
    assert r.gap(1) == at + V and r.phys() == at
    r.sap(167, 1)
    r.vm.advance(1.0)
    assert r.phys() == at + V and r.gap(1) == at + 2 * V


def test_6212_free_wheeling_stage_does_not_reach_its_limit_switch(rig):
    """With the driver off the stage does not move, so the right limit switch it would reach is
    not actuated and does not stop the ramp (AP10 stays 0)."""
    r = rig("TMCM-6212", {"axis": {"0": {"right": {"position": 30000}}}})
    r.sap(167, 0)
    r.cmd(1, 0, 0, V)
    r.vm.advance(2.0)
    assert r.gap(10) == 0 and r.gap(1) == 76800 and r.phys() == 0


def _removing(tmp_path, number: int):
    path = tmp_path / f"no{number}.toml"
    path.write_text(f'extends = "TMCM-6212"\n[module]\nname = "NO{number}-6212"\n'
                    f"[remove]\naxis_parameter = [{number}]\n")
    return str(path)


def test_toff_0_free_wheels_on_a_profile_without_ap168(rig, tmp_path):
    """TMCM-6212 manual 4.1 AP167 "Setting this parameter to zero completely disables all driver
    transistors and the motor can free-wheel" - a property of AP167 alone; a profile that removes the
    smartEnergy parameter AP168 (docs/profiles.md `[remove]`; GAP 168 is status 3) keeps it: with
    AP167 = 0 the counter moves 20000 and the stage and AP209 stay at 0; with AP167 = 1 (the last
    value that still drives) the stage follows the next 20000."""
    r = rig(_removing(tmp_path, 168), {})
    assert r.vm.request(6, 168, 0).status == 3
    r.sap(167, 0)
    r.cmd(4, 1, 0, 20000)
    r.vm.advance(2.0)
    assert (r.gap(1), r.phys(), r.gap(209)) == (20000, 0, 0)
    r.sap(167, 1)
    r.cmd(4, 1, 0, 20000)
    r.vm.advance(2.0)
    assert (r.gap(1), r.phys(), r.gap(209)) == (40000, 20000, 20000)


CASES = [(0, 0), (1000, 80), (3187, 254), (3199, 255), (3200, 0), (3200 + 800, 64), (-12, 255)]


def test_1180_absolute_encoder_value_follows_the_encoder(rig):
    """PD86-1180 5 AP215 "Absolute value of the encoder. 0... 255 [encoder steps]": the angle of
    the rotor in one round of the sensOstep encoder (256 counts, docs/world.md); with the default
    AP140 = 4 (16 microsteps) a round is 200 * 16 = 3200 microsteps, so 1000 microsteps read
    1000 * 256 // 3200 = 80; 255 is the last value before the round closes at 0."""
    r = rig("PD86-1180", {})
    seen = []
    for steps, _ in CASES:
        r.cmd(4, 0, 0, steps)
        r.vm.advance(10.0)
        assert r.phys() == steps
        seen.append((steps, r.gap(215)))
    assert seen == CASES


def test_1180_absolute_encoder_value_ignores_an_encoder_position_write(rig):
    """AP209 (encoder position, RW) can be overwritten; the absolute value AP215 (R) is the
    sensor's angle and stays."""
    r = rig("PD86-1180", {})
    r.cmd(4, 0, 0, 1000)
    r.vm.advance(10.0)
    r.sap(209, 12345)
    assert r.gap(209) == 12345 and r.gap(215) == 80


def test_1180_toff_0_free_wheels_too(rig):
    """PD86-1180 5 AP167 "Setting this parameter to zero completely disables all driver transistors
    and the motor can free-wheel" (range "0 / 2… 15"): the counter moves, the stage and AP209 stay;
    2, the first value after the gap, re-enables the driver from where the stage is."""
    r = rig("PD86-1180", {})
    r.sap(167, 0)
    r.cmd(4, 0, 0, 3200)
    r.vm.advance(10.0)
    assert (r.gap(1), r.phys(), r.gap(209)) == (3200, 0, 0)
    r.sap(167, 2)
    r.cmd(4, 0, 0, 6400)
    r.vm.advance(10.0)
    assert (r.gap(1), r.phys()) == (6400, 3200)
    assert r.gap(209) == 3200 * 256 // 3200 * 6400 // 512    # one round of 256 counts, prescaler 12.5
