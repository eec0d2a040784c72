"""Limit and home switches of a virtual stage (item 1 of the axis world).

Stage for most tests: left limit switch active for p <= -20000, right limit switch for
p >= 30000, home switch on [4500, 5500].
"""
import pytest

from opentmcl.motion.scenario import ScenarioError

STAGE = {"axis": {"0": {"left": {"position": -20000}, "right": {"position": 30000},
                        "home": {"position": 5000, "width": 1000}}}}


def test_switch_states_read_back_along_the_stage(rig):
    """TMCM-6212 manual 4.1: AP9 home switch state, AP10 right and AP11 left limit switch
    state ("the logical state of the ... input")."""
    r = rig("TMCM-6212", STAGE)
    assert (r.gap(9), r.gap(10), r.gap(11)) == (0, 0, 0)
    r.cmd(4, 0, 0, 5000)            # MVP ABS onto the home switch
    r.vm.advance(2)
    assert (r.gap(9), r.gap(10), r.gap(11)) == (1, 0, 0)
    r.cmd(4, 0, 0, -25000)
    r.vm.advance(3)
    assert r.gap(1) == -20000       # stopped by the left switch at its switching point
    assert (r.gap(9), r.gap(10), r.gap(11)) == (0, 0, 1)


def test_hard_stop_at_the_right_switch(rig):
    """TMCM-6212 manual 4.1 AP26 = 0 (no soft stop): ROR stops at once where the right limit
    switch becomes active; AP10 reads 1."""
    r = rig("TMCM-6212", STAGE)
    r.cmd(1, 0, 0, 20000)
    r.vm.advance(3)
    assert r.gap(3) == 0
    assert r.gap(1) == 30000
    assert r.gap(10) == 1


def test_soft_stop_decelerates_past_the_switch(rig):
    """TMCM-6212 manual 4.1 AP26 "Use soft stop when motor is stopped by a limit switch": the
    motor brakes with the velocity-mode deceleration (AP5) from the switching point on,
    v^2 / (2 a) = 20000^2 / (2 * 51200) = 3906 microsteps."""
    r = rig("TMCM-6212", STAGE)
    r.sap(26, 1)
    r.cmd(1, 0, 0, 20000)
    r.vm.advance(3)
    assert r.gap(3) == 0
    assert 30000 + 3900 <= r.gap(1) <= 30000 + 3910
    assert r.gap(10) == 1


def test_disabled_right_switch_does_not_stop(rig):
    """TMCM-6212 manual 4.1 AP12 "Deactivates the stop function of the right limit switch"."""
    r = rig("TMCM-6212", STAGE)
    r.sap(12, 1)
    r.cmd(1, 0, 0, 20000)
    r.vm.advance(3)
    assert r.gap(3) == 20000
    assert r.gap(1) > 40000
    assert r.gap(10) == 1           # the state is still read back


def test_only_the_switch_in_the_direction_of_motion_stops(rig):
    """TMCM-6212 manual 4.1 AP10/AP12: the right switch stops motion to the right only;
    standing on it, the motor can still leave to the left."""
    r = rig("TMCM-6212", STAGE)
    r.cmd(1, 0, 0, 20000)
    r.vm.advance(3)
    assert r.gap(1) == 30000
    r.cmd(1, 0, 0, 20000)           # into the switch again: stopped at once
    r.vm.advance(0.5)
    assert r.gap(1) == 30000
    r.cmd(2, 0, 0, 20000)           # ROL: away from it
    r.vm.advance(0.5)
    assert r.gap(1) < 30000 - 5000
    assert r.gap(10) == 0


def test_polarity_inverts_the_logical_state(rig):
    """TMCM-6212 manual 4.1 AP24 "Setting this parameter to 1 inverts the logic state of the
    right limit switch input": the untouched switch now reads 1 and blocks motion to the right."""
    r = rig("TMCM-6212", STAGE)
    r.sap(24, 1)
    assert r.gap(10) == 1 and r.gap(11) == 0
    r.cmd(1, 0, 0, 20000)
    r.vm.advance(1)
    assert r.gap(1) == 0
    r.sap(25, 1)
    assert r.gap(11) == 1


def test_swap_exchanges_left_and_right(rig):
    """TMCM-6212 manual 4.1 AP14 "Swap the left and right limit switches when set to 1"."""
    r = rig("TMCM-6212", {"axis": {"0": {"left": {"position": -5000}}}})
    r.sap(14, 1)
    r.cmd(2, 0, 0, 20000)           # ROL passes the physical left switch (now the right one)
    r.vm.advance(1)
    assert r.gap(1) < -10000
    assert r.gap(10) == 1 and r.gap(11) == 0
    r.cmd(3)                        # MST
    r.vm.advance(1)
    here = r.gap(1)
    r.cmd(1, 0, 0, 20000)           # to the right with the (swapped) right switch active: no motion
    r.vm.advance(0.5)
    assert r.gap(1) == here


def test_forced_inputs(rig):
    """Issue 5: switch inputs the user can force (Python API); AP9 follows the forced input."""
    r = rig("TMCM-6212", STAGE)
    aw = r.vm.world.axis(0)
    aw.force_switch("home", 1)
    assert r.gap(9) == 1
    aw.force_switch("left", 1)
    r.cmd(2, 0, 0, 10000)
    r.vm.advance(0.5)
    assert r.gap(1) == 0            # the forced left switch stops the motion to the left
    aw.force_switch("left", None)
    r.cmd(2, 0, 0, 10000)
    r.vm.advance(0.5)
    assert r.gap(1) < 0
    with pytest.raises(ValueError):
        aw.force_switch("middle", 1)


def test_force_switch_names_the_switches_it_knows(rig):
    """docs/world.md (Python API): `force_switch` takes left, right or home; another name is a
    ValueError that names it and the three valid ones."""
    r = rig("TMCM-6212", {})
    with pytest.raises(ValueError, match=r"no switch 'middle' \(left, right, home\)"):
        r.vm.world.axis(0).force_switch("middle", 1)


def test_returning_a_switch_that_was_never_forced_is_a_no_op(rig):
    """docs/scenarios.md: `aw.force_switch("left", 1)  # force an input; None returns it to the
    stage` - None on a switch that is not forced leaves it with the stage (AP11 left switch state
    still follows the slider) and raises nothing."""
    r = rig("TMCM-6212", STAGE)
    aw = r.vm.world.axis(0)
    aw.force_switch("left", None)
    assert aw.switches.forced == {}
    assert r.gap(11) == 0
    aw.force_switch("home", 1)
    aw.force_switch("left", None)    # another switch is forced: it stays forced
    assert aw.switches.forced == {"home": 1} and r.gap(9) == 1


def test_scenario_force_and_normally_closed_switch(rig):
    """docs/scenarios.md: `force` fixes an input; `inverted` models a normally closed switch."""
    r = rig("TMCM-6212", {"axis": {"0": {"force": {"right": 1}},
                                   "1": {"left": {"position": -100, "inverted": True}}}})
    assert r.gap(10, 0) == 1
    assert r.gap(11, 1) == 1        # not actuated: a normally closed switch reads 1
    r.sap(25, 1, motor=1)
    assert r.gap(11, 1) == 0


def test_1180_end_switch_polarity_gp79_and_soft_stop_ap149(rig):
    """PD86-1180 manual 6 GP79 "End switch polarity" (both switches) and 5 AP149 "soft stop
    flag: If cleared, the motor will stop immediately"."""
    r = rig("TMCM-1180", {"axis": {"0": {"right": {"position": 3000}}}})
    r.cmd(9, 79, 0, 1)
    assert r.gap(10) == 1 and r.gap(11) == 1
    r.cmd(9, 79, 0, 0)
    r.sap(149, 1)
    r.cmd(1, 0, 0, 500)
    r.vm.advance(5)
    assert r.gap(3) == 0
    assert r.gap(1) > 3000
    r2 = rig("TMCM-1180", {"axis": {"0": {"right": {"position": 3000}}}})
    r2.cmd(1, 0, 0, 500)
    r2.vm.advance(5)
    assert r2.gap(1) == 3000


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


def test_1180_reference_switch_tolerance(rig):
    """PD86-1180 manual 5 AP141 "For three-switch mode: a position range, where an additional
    switch (connected to the REFL input) won't cause motor stop"."""
    sc = {"axis": {"0": {"left": {"position": -20000}, "home": {"position": 0, "width": 400}}}}
    r = rig("TMCM-1180", sc)
    r.cmd(4, 0, 0, -1000)
    r.vm.advance(3)
    assert r.gap(1) == 0        # REFL (home wired in series) already active: no motion to the left
    r = rig("TMCM-1180", sc)
    r.sap(141, 500)
    r.cmd(4, 0, 0, -1000)
    r.vm.advance(3)
    assert r.gap(1) == -1000


def test_hysteresis_releases_later(rig):
    """docs/scenarios.md `hysteresis`: an actuated switch releases h microsteps outside its
    active range."""
    r = rig("TMCM-6212", {"axis": {"0": {"home": {"position": 5000, "width": 1000, "hysteresis": 50}}}})
    r.cmd(4, 0, 0, 4500)
    r.vm.advance(2)
    assert r.gap(9) == 1
    r.cmd(4, 0, 0, 4451)
    r.vm.advance(1)
    assert r.gap(9) == 1
    r.cmd(4, 0, 0, 4449)
    r.vm.advance(1)
    assert r.gap(9) == 0


def test_switch_state_persists_across_a_restart(rig):
    """Issue 5: the world persists across power cycles; after a reset (command 137) the
    position counter restarts at 0 but the slider stays on the switch."""
    r = rig("TMCM-6212", STAGE)
    r.cmd(1, 0, 0, 20000)
    r.vm.advance(3)
    r.vm.request(137, 0, 0, 1234)
    assert r.gap(1) == 0
    assert r.gap(10) == 1
    assert r.phys() == 30000


@pytest.mark.parametrize("bad", [
    {"axis": {"0": {"left": {"width": 10}}}},
    {"axis": {"0": {"home": {"position": 1}}}},
    {"axis": {"0": {"type": "circular", "left": {"position": 1}}}},
    {"axis": {"0": {"type": "helix"}}},
    {"axis": {"x": {}}},
    {"axis": {"0": {"load": {"steps": "no"}}}},
    {"unknown": 1},
    {"axis": {"0": {"ends": [5000, -5000]}}},
    {"axis": {"0": {"left": {"position": 100}, "right": {"position": -100}}}},
    {"axis": {"0": {"load": float("nan")}}},
    {"axis": {"0": {"force": {"left": 2}}}},
    {"axis": {"0": {"start": 2**40}}},
    {"axis": {"0": {"right": {"position": -2**31 - 1}}}},
    {"axis": [{"index": 0}, {"index": 0}]},
])
def test_bad_scenarios_raise_scenario_error(rig, bad):
    """House rules: bad input gives a clear typed exception."""
    with pytest.raises(ScenarioError):
        rig("TMCM-6212", bad)


@pytest.mark.parametrize(("name", "text", "broken"), [
    ("s.toml", "[axis.0]\nright = { position = 100 }\n", "[axis.0\n"),
    ("s.yaml", "axis:\n  0:\n    right: {position: 100}\n", "axis: [unclosed\n"),   # issue 5: TOML or YAML
])
def test_scenario_files_and_their_errors(rig, tmp_path, name, text, broken):
    """docs/scenarios.md: TOML and YAML files load (a right limit switch at 100 stops a move to
    1000 there, TMCM-6212 manual 4 AP10); syntax errors, unknown ports and axes are ScenarioErrors
    naming the problem."""
    good = tmp_path / name
    good.write_text(text)
    r = rig("TMCM-6212", str(good))
    r.cmd(1, 0, 0, 1000)
    r.vm.advance(1)
    assert r.gap(1) == 100
    bad = tmp_path / f"bad{good.suffix}"
    bad.write_text(broken)
    with pytest.raises(ScenarioError, match=bad.name):
        rig("TMCM-6212", str(bad))
    with pytest.raises(ScenarioError, match="port 7"):
        rig("TMCM-6212", {"input": [{"bank": 0, "port": 7, "value": 1}]})
    with pytest.raises(ScenarioError):
        rig("TMCM-6212", 42)
    with pytest.raises(ScenarioError, match="axis.1"):
        rig("TMCM-1180", {"axis": {"1": {}}})


def test_wait_refsw_and_limsw_wake_at_the_switch_edge(rig):
    """TMCM-6212 manual 3.6.20 WAIT REFSW "Wait until the reference switch ... has been
    triggered", LIMSW likewise for a limit switch: the program continues at the edge; the GAP
    after it runs one instruction (100 us, 2 microsteps at 20000 pps) later. The limit switch
    has stopped the motor at its switching point."""
    from tests.firmware.test_program_support import Wire

    for cond, expected in (("REFSW", 4502), ("LIMSW", 30000)):
        r = rig("TMCM-6212", STAGE)
        w = Wire(r.vm)
        w.load(f"ROR 0, 20000\nWAIT {cond}, 0, 0\nGAP 1, 0\nSTOP")
        w.run()
        r.vm.advance(3)
        assert w.a == expected, cond
