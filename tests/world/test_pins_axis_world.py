"""Axis-world edges left unpinned by the firmware mutation sample of round 22 (docs/mutation.md):
the refusal of an unknown switch name, the TMC429 velocity unit in the torque fall-off, and a
GP79 polarity change taking effect on a moving motor."""
import pytest

from opentmcl.motion.stallguard import load_value


def test_force_switch_names_the_switches_it_knows(rig):
    """docs/world.md (Python API): `force_switch` takes left, right or home; another name is a
    ValueError that names it and the three valid ones."""
    r = rig("TMCM-6212", {})
    with pytest.raises(ValueError, match=r"no switch 'middle' \(left, right, home\)"):
        r.vm.world.axis(0).force_switch("middle", 1)


def test_tmc429_speed_unit_in_the_torque_falloff(rig):
    """PD86-1180 5 AP3 "Actual speed" in units of 16 MHz / 65536 * 2^-AP154 microsteps/s;
    docs/world.md: capacity C = (CS + 1) / 32 * (1 - |v| / v_falloff) with v in pps, and
    AP206 = round(1023 * (1 - L / C)). 1000 units at AP154 = 3 are 30517.578125 pps."""
    falloff = 33908
    r = rig("PD86-1180", {"axis": {"0": {"load": 0.099, "torque_falloff_speed": falloff}}})
    r.sap(6, 255)                           # CS 31: full capacity at rest
    r.sap(154, 3)
    r.cmd(1, 0, 0, 1000)
    r.vm.advance(2)
    assert r.gap(3) == 1000
    pps = 1000 * 16_000_000 / (65536 * 2**3)
    assert pps == 30517.578125
    assert r.gap(206) == load_value(0.099, 1 - pps / falloff, 0)


def test_gp79_polarity_change_stops_a_moving_motor(rig):
    """PD86-1180 6 GP79 "End switch polarity 1: reverse polarity": an open right switch then
    reads active (AP10 = 1), and a motor running right into it stops at once (AP149 = 0: "the
    motor will stop immediately"), not only where the stage's switch is."""
    r = rig("PD86-1180", {"axis": {"0": {"right": {"position": 10**6}}}})
    r.cmd(1, 0, 0, 500)
    r.vm.advance(0.5)
    assert r.gap(3) == 500
    r.cmd(9, 79, 0, 1)
    r.vm.advance(0.01)
    at = r.gap(1)
    assert (r.gap(3), r.gap(10)) == (0, 1)
    r.vm.advance(1)
    assert r.gap(1) == at < 10**6

