"""stallGuard2, coolStep, drive currents, step loss and the deviation stop (items 3 and 4), on the
behavioural model of docs/world.md: capacity C = (CS + 1) / 32 * (1 - |v| / v_falloff) with
CS = current >> 3, load value SG = clamp(round(1023 (1 - L / C)) + 16 SGT, 0, 1023)."""
import pytest

from opentmcl.firmware import flags
from opentmcl.motion import CLOCK_HZ
from opentmcl.motion.stage import Profile
from opentmcl.motion.stallguard import load_value
from tests.firmware.test_program_support import Wire

FALLOFF_6212 = 30 * 200 * 256   # default torque fall-off: 30 rev/s at 256 microsteps (docs/world.md)
V = 51200                       # pps; the TMCM-6212's default AP5 accelerates to it in one second


def speed_share(pps: float, falloff: float = FALLOFF_6212) -> float:
    return 1 - pps / falloff


def test_load_value_falls_linearly_with_load(rig):
    """TMCM-6212 manual 6.3: "The measured value changes linear with the load on the motor ...
    At maximum motor load the stallGuard value goes to zero"; AP206 reads it while moving."""
    values = []
    for load in (0.0, 0.1, 0.2, 0.3):
        r = rig("TMCM-6212", {"axis": {"0": {"load": load}}})
        r.sap(6, 255)                  # CS 31: C = 1
        r.cmd(1, 0, 0, 20000)
        r.vm.advance(1)
        values.append(r.gap(206))
    assert values == [load_value(load, speed_share(20000), 0) for load in (0.0, 0.1, 0.2, 0.3)]
    assert values[0] == 1023 and values[1] < 922
    steps = [a - b for a, b in zip(values, values[1:], strict=False)]
    assert max(steps) - min(steps) <= 1


@pytest.mark.parametrize("falloff", [None, 800_000])
def test_load_value_depends_on_velocity(rig, falloff):
    """TMCM-6212 manual 1.1: "The stallGuard2 measurement value changes linearly over a wide range
    of load, velocity, and current settings": the same load reads lower at a higher speed (the
    motor's torque falls with speed; the scenario's `torque_falloff_speed` sets where it reaches 0,
    default 30 rev/s)."""
    axis = {"load": 0.3} | ({"torque_falloff_speed": falloff} if falloff else {})
    got = {}
    for pps in (20000, 400000):
        r = rig("TMCM-6212", {"axis": {"0": axis}})
        r.sap(6, 255)
        r.sap(5, 2_000_000)
        r.cmd(1, 0, 0, pps)
        r.vm.advance(1)
        assert r.gap(3) == pps
        got[pps] = r.gap(206)
    share = (lambda v: speed_share(v, falloff)) if falloff else speed_share
    assert got == {pps: load_value(0.3, share(pps), 0) for pps in got}
    assert got[400000] < got[20000]


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


def test_load_value_depends_on_current_and_threshold():
    """TMCM-6212 manual 4.1 AP174: "A lower value gives a higher sensitivity ... A higher value
    makes stallGuard2 less sensitive and requires more torque to indicate a stall"."""
    assert load_value(0.25, 0.5, 0) == 512 and load_value(0.25, 1.0, 0) == 767
    assert load_value(0.45, 0.5, -10) == 0
    assert load_value(0.5, 0.5, 10) == 160
    assert load_value(0.1, 0.0, 0) == 0


def _stall_rig(rig, sgt=0, limit=1000):
    r = rig("TMCM-6212", {"axis": {"0": {"load": {"steps": [[10000, 0.6]], "before": 0.1}}}})
    r.sap(181, limit)
    r.sap(174, sgt)
    return r


def test_stop_on_stall(rig):
    """TMCM-6212 manual 4.1 AP181 "Above this speed motor will stop in case stallGuard2 load
    value reaches zero", AP207 bit 0 "stallGuard error" (cleared when read), the stall
    interrupt (5.4) and the JC EPO condition (our choice, docs/assumptions.md)."""
    r = _stall_rig(rig)
    r.cmd(1, 0, 0, 20000)
    r.vm.advance(2)
    assert r.gap(3) == 0
    assert r.gap(1) == 10000          # the load steps up at 10000: C = 17/32 < 0.6
    assert r.phys() == 10000          # stopped before losing a step
    assert r.gap(207) == 1
    assert r.gap(207) == 0            # cleared by the read
    assert r.vm.flags & flags.EPO


def test_no_stall_stop_below_the_stall_speed(rig):
    """TMCM-6212 manual 4.1 AP181: "Below this speed motor will not be stopped" - the motor
    then loses steps instead (the counter runs on, the stage does not)."""
    r = _stall_rig(rig, limit=30000)
    r.cmd(1, 0, 0, 20000)
    r.vm.advance(2)
    assert r.gap(3) == 20000
    assert r.gap(1) > 20000
    assert r.phys() == 10000


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


def test_stall_interrupt_is_raised(rig):
    """TMCM-6212 manual 5.4 interrupt 15 "stallGuard axis 0": the handler runs on a stall."""
    r = _stall_rig(rig)
    w = Wire(r.vm)
    w.load("VECT 15, Stall\nEI 15\nEI 255\nROR 0, 20000\nLoop: JA Loop\n"
           "Stall: CALC LOAD, 77\nAGP 0, 2\nRETI")
    w.run()
    r.vm.advance(2)
    assert r.cmd(10, 0, 2) == 77      # user variable 0, written by the handler


def test_step_loss_and_deviation_stop(rig):
    """TMCM-6212 manual 4.1 AP212 "When the actual position (parameter 1) and the encoder
    position (parameter 209) differ more than set here the motor will be stopped"; AP207 bit 1
    deviation error, JC EDV, deviation interrupt. The load exceeds what the current holds: the
    position counter runs on, the encoder does not."""
    r = rig("TMCM-6212", {"axis": {"0": {"load": {"steps": [[5000, 0.9]]}}}})
    r.sap(212, 2000)
    r.cmd(1, 0, 0, 20000)
    r.vm.advance(2)
    assert r.gap(3) == 0
    assert r.gap(209) == 5000
    assert r.gap(1) == 5000 + 2001
    assert r.gap(207) == 2
    assert r.vm.flags & flags.EDV


@pytest.mark.parametrize("command", [(1, 0, 20000), (4, 0, 100_000)])  # ROR, MVP ABS
@pytest.mark.parametrize("offset", [2000, 2001])
def test_deviation_present_when_the_motion_starts(rig, command, offset):
    """TMCM-6212 manual 4.1 AP212: "When the actual position (parameter 1) and the encoder
    position (parameter 209) differ more than set here the motor will be stopped". A deviation
    that exists before the command (AP209 rewritten, manual 6.2 "writable, e.g. for setting a new
    origin") stops the motion at once; a deviation equal to the limit (the last one allowed) does
    not. Before round 23 the twin looked at the deviation only while the motor moved, so a motion
    starting from rest ran on until an unrelated event."""
    r = rig("TMCM-6212", {})
    r.sap(212, 2000)
    r.sap(209, offset)
    number, type_, value = command
    r.cmd(number, type_, 0, value)
    r.vm.advance(0.5)
    if offset > 2000:
        assert (r.gap(1), r.gap(3), r.gap(209)) == (0, 0, offset)
        assert r.gap(207) == 2 and r.vm.flags & flags.EDV
    else:
        assert r.gap(3) != 0 and r.gap(1) > 0
        assert r.gap(207) == 0


@pytest.mark.parametrize(("command", "stop_at"), [(1, 1001), (2, -1001)])
def test_deviation_limit_stops_a_free_wheeling_motor_in_both_directions(rig, command, stop_at):
    """TMCM-6212 manual 4.1 AP212 "When the actual position (parameter 1) and the encoder position
    (parameter 209) differ more than set here the motor will be stopped", and AP167 = 0 "completely
    disables all driver transistors and the motor can free-wheel": the rotor and the encoder stay at
    0 while the counter runs, so with AP212 = 1000 a deviation of 1000 (the last allowed one) goes
    on and the motor stops at the first counter beyond it, 1001 steps right (ROR) or left (ROL) of
    the encoder, with AP207 bit 1 (deviation) set."""
    r = rig("TMCM-6212", {})
    r.sap(212, 1000)
    r.sap(167, 0)
    r.cmd(command, 0, 0, V)
    r.vm.advance(2.0)
    assert (r.gap(1), r.gap(209), r.gap(3), r.phys()) == (stop_at, 0, 0, 0)
    assert r.gap(207) & 2


def test_coolstep_lowers_the_current_at_light_load(rig):
    """TMCM-6212 manual 4.1 AP168 minimum 1/2 CS, AP169 32 readings per decrement, AP172
    lower threshold, AP180 actual current: at light load the current falls to the minimum."""
    r = rig("TMCM-6212", {"axis": {"0": {"load": 0.05}}})
    r.sap(172, 1)
    r.cmd(1, 0, 0, 51200)
    r.vm.advance(0.1)
    assert r.gap(180) == 16           # AP6 = 128: CS = 128 >> 3
    r.vm.advance(3)
    assert r.gap(180) == 7            # (16 + 1) // 2 - 1


def test_coolstep_settles_in_the_hysteresis_band(rig):
    """TMCM-6212 manual 4.1 AP170/AP172: above the upper threshold (AP172 + AP170 + 1) * 32 the
    current is decreased, below AP172 * 32 increased; a heavy load keeps it near CS."""
    r = rig("TMCM-6212", {"axis": {"0": {"load": 0.43}}})
    r.sap(6, 127)                      # CS 15: C = 0.5 at standstill, 0.483 at 51200 pps
    r.sap(172, 1)
    r.cmd(1, 0, 0, 51200)
    r.vm.advance(3)
    cs = r.gap(180)
    sg = r.gap(206)
    assert cs == 14 and 32 <= sg < 64


def test_coolstep_raises_the_current_up_to_the_run_current_scale_and_no_further(rig):
    """TMCM-6212 manual 4.1 AP180: "The value goes up to the CS value and down to the portion of CS
    as specified by SEIMIN"; AP171: "The current becomes incremented for each measured stallGuard2
    value below the lower threshold". From the minimum (AP6 = 128: CS 16, SEIMIN 0: 7) a load no
    current can hold (SG stays 0) drives AP180 back up to exactly 16 - the upper limit - and not
    to 17 (steps of 2, AP171 = 1: 7, 9, ... 15, then capped at 16)."""
    r = rig("TMCM-6212", {"axis": {"0": {"load": {"by": "position", "steps": [[160000, 0.9]], "before": 0.05}}}})
    r.sap(172, 1)
    r.sap(171, 1)
    r.cmd(1, 0, 0, 51200)
    r.vm.advance(3)
    assert r.gap(180) == 7 and r.gap(1) < 160000
    seen = set()
    for _ in range(100):
        r.vm.advance(0.01)
        seen.add(r.gap(180))
    assert r.gap(1) > 160000 and r.gap(206) == 0
    assert r.gap(180) == 128 >> 3 and max(seen) == 16


def test_coolstep_off_below_the_threshold_speed(rig):
    """TMCM-6212 manual 4.1 AP182 "Above this speed coolStep becomes enabled"."""
    r = rig("TMCM-6212", {"axis": {"0": {"load": 0.05}}})
    r.sap(172, 1)
    r.sap(182, 60000)
    r.cmd(1, 0, 0, 51200)
    r.vm.advance(3)
    assert r.gap(180) == 16


def test_standby_current_after_the_power_down_delay(rig):
    """TMCM-6212 manual 4.1 AP7 standby current, AP214 "Standstill period before the current
    will be ramped down to standby current" (10 ms units)."""
    r = rig("TMCM-6212", {})
    r.sap(7, 40)
    r.sap(214, 50)
    r.cmd(4, 0, 0, 1000)
    r.vm.advance(0.3)
    assert r.gap(180) == 128 >> 3
    r.vm.advance(0.5)
    assert r.gap(180) == 40 >> 3


def test_boost_current_while_accelerating(rig):
    """PD86-1180 manual 5 AP200 "Current used for acceleration and deceleration phases"."""
    r = rig("TMCM-1021", {})
    r.sap(200, 200)
    r.sap(5, 10000)
    r.cmd(1, 0, 0, 20000)
    r.vm.advance(0.5)
    assert r.gap(180) == 200 >> 3
    r.vm.advance(2)
    assert r.gap(180) == 128 >> 3


def test_1180_freewheeling_cuts_the_current(rig):
    """PD86-1180 manual 5 AP204 "Time after which the power to the motor will be cut when its
    velocity has reached zero" (ms)."""
    r = rig("TMCM-1180", {})
    r.sap(204, 100)
    r.vm.advance(0.2)
    assert r.gap(180) == 0


def test_time_dependent_load(rig):
    """Issue 5 item 3: a time-dependent load from the scenario; the stall happens when the load
    steps up at t = 1 s."""
    r = rig("TMCM-6212", {"axis": {"0": {"load": {"by": "time", "steps": [[1.0, 0.9]]}}}})
    r.sap(181, 1000)
    r.cmd(1, 0, 0, 10000)
    r.vm.advance(0.99)
    assert r.gap(3) == 10000
    r.vm.advance(0.02)
    assert r.gap(3) == 0
    assert r.gap(207) == 1


def test_load_api(rig):
    """Issue 5 item 3: the load can also be set through the Python API."""
    r = rig("TMCM-6212", {})
    aw = r.vm.world.axis(0)
    aw.set_load(Profile([(2000, 0.95)]), by="position")
    r.sap(181, 1000)
    r.cmd(1, 0, 0, 10000)
    r.vm.advance(1)
    assert r.gap(1) == 2000
    with pytest.raises(ValueError):
        Profile([(0, 1)], kind="spline")


@pytest.mark.parametrize(("load", "sg"), [(0.0, 1023), (0.25, 767), (1.0, 0)])
def test_set_load_takes_a_plain_number(rig, load, sg):
    """docs/scenarios.md Python API `aw.set_load(0.4)  # constant load` and docs/world.md: load L
    as a fraction of the torque at 100 % current, capacity C = (CS + 1) / 32 (CS = AP6 >> 3, 31 at
    AP6 = 255; no fall-off at rest), AP206 = round(1023 * (1 - L / C)) with SGT = AP174 = 0, read at
    standstill too: 1023 without load, round(767.25) = 767 at a quarter, 0 at L = C."""
    r = rig("TMCM-6212", {})
    r.sap(6, 255)
    r.sap(174, 0)
    r.vm.world.axis(0).set_load(load)
    assert r.gap(206) == sg == round(1023 * (1 - load / ((31 + 1) / 32)))


def test_load_now_reads_the_load_and_a_mechanical_end(rig):
    """docs/scenarios.md: `aw.load_now()  # load torque now (fraction of the torque at 100 %
    current)`; docs/world.md "Load, current, stallGuard2, coolStep": the load from the scenario or
    `set_load`, "pushing into a mechanical end adds 100" - only while pushing into it (ROR at the
    right end), not while standing there nor moving away (ROL)."""
    r = rig("TMCM-6212", {"axis": {"0": {"load": 0.25, "ends": [None, 1000]}}})
    aw = r.vm.world.axis(0)
    assert aw.load_now() == 0.25
    aw.set_load(0.4)
    assert aw.load_now() == 0.4
    r.cmd(1, 0, 0, 2000)                          # ROR into the end at 1000
    r.vm.advance(2.0)
    assert r.phys() == 1000 and aw.load_now() == 100.4
    r.cmd(3)                                      # MST: standing at the end
    r.vm.advance(0.5)
    assert aw.load_now() == 0.4
    r.cmd(2, 0, 0, 2000)                          # ROL away from it
    r.vm.advance(0.1)
    assert r.phys() < 1000 and aw.load_now() == 0.4


def test_stallguard_homing_program(rig):
    """TMCM-6212 manual 6.3: "Stall detection can for example be used for finding the reference
    point without the need for reference switches. A short routine written in TMCL is needed"
    - examples/scenarios/stallguard_homing.tmc drives into the hard stop and zeroes."""
    from pathlib import Path
    root = Path(__file__).resolve().parents[2]
    r = rig("TMCM-6212", str(root / "examples/scenarios/tmcm6212_stage.toml"))
    w = Wire(r.vm)
    w.load((root / "examples/scenarios/stallguard_homing.tmc").read_text())
    w.run()
    r.vm.advance(10)
    assert r.gap(1) == 0
    assert r.phys() == -60000         # the left hard stop of the example stage


def test_stall_detected_when_the_speed_reaches_the_stall_limit(rig):
    """TMCM-6212 manual 4.1 AP181: a motor already overloaded at low speed stops the moment its
    speed reaches the stop-on-stall speed during the acceleration (not at the end of the ramp).
    AMAX 10000 pps^2: 2000 pps are reached after 0.2 s, 200 microsteps from the start."""
    r = rig("TMCM-6212", {"axis": {"0": {"load": 0.9}}})
    r.sap(5, 10000)
    r.sap(181, 2000)
    r.cmd(1, 0, 0, 20000)
    r.vm.advance(1)
    assert r.gap(3) == 0
    assert r.gap(207) == 1
    assert r.gap(1) == 200             # the counter ran on (the rotor slipped from the start)
    assert r.phys() == 0


def test_load_ramp_over_time_is_followed(rig):
    """Issue 5 item 3 (time-dependent load): a load ramping from 0 to 1 within 2 s; AP206 falls
    with it while the motor runs (full current, C = 1)."""
    r = rig("TMCM-6212", {"axis": {"0": {"load": {"by": "time", "ramp": [[0, 0.0], [2, 1.0]]}}}})
    r.sap(6, 255)
    r.cmd(1, 0, 0, 5000)
    r.vm.advance(0.5)
    assert r.gap(206) == load_value(0.25, speed_share(5000), 0)
    r.vm.advance(1.0)
    assert r.gap(206) == load_value(0.75, speed_share(5000), 0)


def test_a_stall_under_a_load_ramp_over_time_is_seen_within_a_millisecond(rig):
    """docs/world.md "Time-dependent ramps of the load are re-evaluated every millisecond" and
    TMCM-6212 manual 4.1 AP181 "Above this speed motor will stop in case stallGuard2 load value
    reaches zero". ROR 51200 pps (reached after 1 s, so x(t) = 25600 + 51200 (t - 1)) under a load
    rising over time as L(t) = 0.2 t: with AP6 = 255 the capacity is (31 + 1) / 32 times the
    fall-off 1 - 51200 / 1536000 (docs/world.md, 256 microsteps), and AP206 = round(1023 (1 - L/C))
    first reads 0 where L > C (1 - 0.5 / 1023). One advance over the whole ramp: the motor stops
    within 1 ms after that instant (AP207 bit 0), not only at the ramp's end (10 s)."""
    r = rig("TMCM-6212", {"axis": {"0": {"load": {"by": "time", "ramp": [[0, 0.0], [10, 2.0]]}}}})
    r.sap(6, 255)
    r.sap(181, 1000)
    r.sap(174, 0)
    r.cmd(1, 0, 0, V)
    r.vm.advance(12)
    capacity = (1 - V / (30 * 200 * 256)) * (1 - 0.5 / 1023)
    t0 = capacity / 0.2
    def x(t):
        return 25600 + V * (t - 1)
    assert r.gap(3) == 0 and r.gap(207) & 1
    assert x(t0) <= r.gap(1) <= x(t0 + 0.001)


def test_stall_limit_after_the_driver_was_off(rig):
    """TMCM-6212 manual 4.1 AP181, as above, after AP167 (TOFF) = 0 let the counter run while the
    stage stood: the counter and the stage now disagree, and the stop still comes the moment the
    speed reaches the stop-on-stall speed, 200 microsteps after the start."""
    r = rig("TMCM-6212", {"axis": {"0": {"load": 0.9}}})
    toff = r.gap(167)
    r.sap(167, 0)
    r.cmd(4, 0, 0, 5000)               # MVP ABS: the counter runs, the free-wheeling stage stays
    r.vm.advance(5)
    assert r.gap(1) == 5000 and r.phys() == 0
    r.sap(167, toff)
    r.sap(5, 10000)
    r.sap(181, 2000)
    r.cmd(1, 0, 0, 20000)
    r.vm.advance(1)
    assert r.gap(3) == 0
    assert r.gap(207) == 1
    assert r.gap(1) == 5200
