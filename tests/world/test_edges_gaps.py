"""Edges of the axis world left unpinned by the firmware mutation sample (docs/mutation.md, "firmware
(4736, after this round's refactoring)"): the tick at which a motion started into an active switch
is caught, the PD86-1180 velocity unit in the torque fall-off, and AP202 in the TMCM-6212 encoder
conversion."""
from __future__ import annotations

from opentmcl.motion import CLOCK_HZ

from .test_switches import STAGE


def test_a_motion_started_into_an_active_switch_is_stopped_one_tick_later(rig):
    """docs/world.md "Time: events, never steps": "A command that starts a motion into an active switch (or into an
    overload) is caught one tick (62.5 ns) later"; TMCM-6212 manual 4.1 AP26 = 0: the right limit
    switch stops the motor at once (AP2 target speed 0). ROR on the actuated right switch still has
    its target speed at the command's tick and none one 16 MHz tick later."""
    r = rig("TMCM-6212", STAGE)
    r.cmd(1, 0, 0, 20000)
    r.vm.advance(3)
    assert (r.gap(1), r.gap(10), r.gap(3)) == (30000, 1, 0)
    r.cmd(1, 0, 0, 20000)              # ROR again, into the switch it stands on
    assert r.gap(2) == 20000
    r.vm.advance_to(r.vm.now + 1)
    assert r.gap(2) == 0
    assert r.phys() == 30000


def _expected_load_value(load: float, pps: float, falloff: float) -> int:
    """docs/world.md "Load, current, stallGuard2": C = (CS + 1) / 32 * (1 - |v| / v_falloff),
    SG = clamp(round(1023 * (1 - L / C)) + 16 * SGT, 0, 1023), here CS = 31 and SGT = 0."""
    capacity = max(0.0, 1 - pps / falloff)
    return max(0, min(1023, round(1023 * (1 - load / capacity))))


def test_1180_torque_falloff_reads_the_speed_in_its_velocity_unit(rig):
    """PD86-1180 manual 5 AP2/AP3/AP4: speeds are in units of "16MHz / 65536" microsteps per second
    scaled by the pulse divisor (AP154 "The exponent of the scaling factor for the pulse (step)
    generator"); docs/world.md: the torque falls with speed to 0 at 30 rev/s of a 200-step motor
    (30 * 200 * 2^AP140 pps, AP140 = 4 here). AP3 = 1000 is 30518 pps with pulse divisor 3 and half
    of that with 4, so the same load 0.3 reads lower with the smaller divisor."""
    got = {}
    for divisor in (3, 4):
        r = rig("TMCM-1180", {"axis": {"0": {"load": 0.3}}})
        r.sap(154, divisor)
        r.sap(6, 255)                  # CS 31: C = 1 at standstill
        r.cmd(1, 0, 0, 1000)
        r.vm.advance(1)
        assert (r.gap(3), r.gap(140)) == (1000, 4)
        pps = 1000 * CLOCK_HZ / 65536 / 2 ** divisor
        got[divisor] = (r.gap(206), _expected_load_value(0.3, pps, 30 * 200 * 2 ** 4))
    assert got[3][0] == got[3][1] and got[4][0] == got[4][1]
    assert got[3][0] < got[4][0] < 1023 * (1 - 0.3) + 1


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
