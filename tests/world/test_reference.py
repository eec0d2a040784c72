"""Reference search state machines (item 2): every mode of TMCM-6212 manual 6.1 (table 21,
figures 3-10), PD86-1180 manual 7.1 and the PD28-1021 (TMCM-6212 modes, sibling).

The stage: left limit switch active on [-23000, -20000], right on [30000, 33000], home switch
on [4500, 5500]; the slider starts at 0. A switch is met at its first active position; the
switching points of an edge are the last inactive and the first active position, and the
reference point is their centre (rounded half to even): -19999.5 -> -20000 for the left
switch's inner edge, 29999.5 -> 30000 for the right one, 4499.5 -> 4500 for the home switch.
"""
import pytest

from opentmcl import VirtualModule
from tests.firmware.test_program_support import Wire

STAGE = {"axis": {"0": {"left": {"position": -20000, "width": 3000},
                        "right": {"position": 30000, "width": 3000},
                        "home": {"position": 5000, "width": 1000}}}}

L_IN = [("leave", "left", -19999), ("enter", "left", -20000)]      # inner edge of the left switch
R_IN = [("leave", "right", 29999), ("enter", "right", 30000)]
L_OUT = [("leave", "left", -23001), ("enter", "left", -23000)]     # outer edge (from both sides)
R_OUT = [("leave", "right", 33001), ("enter", "right", 33000)]
H_LO = [("leave", "home", 4499), ("enter", "home", 4500)]

MODES_6212 = {
    # 6.1.1 "only searches the left end switch"; +64 the right one
    1: ([("seek", "left", -1), ("found", "left", -20000), *L_IN], -20000, 0),
    65: ([("seek", "right", 1), ("found", "right", 30000), *R_IN], 30000, 0),
    # 6.1.2 "first searches the right end switch and then the left end switch"; AP196 distance
    2: ([("seek", "right", 1), ("found", "right", 30000), *R_IN,
         ("seek", "left", -1), ("found", "left", -20000), *L_IN], -20000, 49999),
    66: ([("seek", "left", -1), ("found", "left", -20000), *L_IN,
          ("seek", "right", 1), ("found", "right", 30000), *R_IN], 30000, 49999),
    # 6.1.3 "The left end switch is then searched from both sides, to find the middle"
    3: ([("seek", "right", 1), ("found", "right", 30000), *R_IN,
         ("seek", "left", -1), ("found", "left", -20000), *L_IN, *L_OUT], -21500, 51500),
    67: ([("seek", "left", -1), ("found", "left", -20000), *L_IN,
          ("seek", "right", 1), ("found", "right", 30000), *R_IN, *R_OUT], 31500, 51500),
    # 6.1.4 "searches the left end switch only, but from both sides"
    4: ([("seek", "left", -1), ("found", "left", -20000), *L_IN, *L_OUT], -21500, 0),
    68: ([("seek", "right", 1), ("found", "right", 30000), *R_IN, *R_OUT], 31500, 0),
    # 6.1.5 home in negative direction, "reversed if the left limit switch is reached"
    5: ([("seek", "home", -1), ("turn", "left", -20000), ("found", "home", 4500), *H_LO], 4500, 0),
    # 6.1.6 home in positive direction (found before the right switch)
    6: ([("seek", "home", 1), ("found", "home", 4500), *H_LO], 4500, 0),
    # 6.1.7 home in positive direction, ignoring end switches, "exact middle of the switch"
    7: ([("seek", "home", 1), ("found", "home", 4500), *H_LO,
         ("leave", "home", 5501), ("enter", "home", 5500)], 5000, 0),
}


def _run(rig, module, mode, scenario=STAGE):
    r = rig(module, scenario)
    r.sap(193, mode)
    r.search()
    return r


@pytest.mark.parametrize(("module", "mode"), [("TMCM-6212", m) for m in sorted(MODES_6212)]
                         + [("TMCM-1021", m) for m in sorted(MODES_6212) if not m & 64])
def test_reference_search_modes(rig, module, mode):
    """TMCM-6212 manual 6.1, table 21 and figures 3-9: the sequence of switch events of each
    mode, the reference point at the centre of the switching points, position counter and
    encoder (6.2: "After a reference search this parameter is also automatically set to 0")
    zero there, AP196 the distance between the end switches (modes 2 and 3), AP197 the last
    position before zeroing. The PD28-1021 follows its sibling (no +64 variants)."""
    log, ref, distance = MODES_6212[mode]
    r = _run(rig, module, mode)
    search = r.vm.reference_search(r.vm.axes[0])
    assert search.log == [*log, ("zero", None, ref)]
    assert r.phys() == ref
    assert r.gap(1) == 0 and r.gap(209) == 0
    assert r.gap(196) == distance
    assert r.gap(197) == ref
    assert r.gap(3) == 0


def test_mode_8_searches_the_home_switch_in_negative_direction(rig):
    """TMCM-6212 manual table 21: mode 8 "Search home switch in negative direction, ignore end
    switches" - on a circular axis it meets the home switch from above and finds its middle."""
    sc = {"axis": {"0": {"type": "circular", "steps_per_turn": 51200, "start": 20000,
                         "home": {"position": 100, "width": 800}}}}
    r = _run(rig, "TMCM-6212", 8, sc)
    log = r.vm.reference_search(r.vm.axes[0]).log
    assert log[:2] == [("seek", "home", -1), ("found", "home", 500 - 20000)]  # counter started at 0
    assert r.phys() % 51200 == 100
    assert r.gap(1) == 0


def test_mode_7_on_a_circular_axis_finds_the_middle(rig):
    """TMCM-6212 manual 6.1.7: mode 7 "is recommended mainly for use with a circular axis. The
    exact middle of the switch will be found and used as the zero point"."""
    sc = {"axis": {"0": {"type": "circular", "steps_per_turn": 51200, "start": 20000,
                         "home": {"position": 100, "width": 800}}}}
    r = _run(rig, "TMCM-6212", 7, sc)
    assert r.phys() == 51300          # one turn on, at the middle of the switch
    assert r.gap(1) == 0


def test_plus_128_inverts_the_home_switch(rig):
    """TMCM-6212 manual 6.1.5: "Add 128 to the mode number (i.e. set axis parameter #193 to
    129) to reverse the polarity of the home switch input" - a normally closed home switch."""
    sc = {"axis": {"0": {"left": {"position": -20000}, "home": {"position": 5000, "width": 1000, "inverted": True}}}}
    for mode, result in ((5 + 128, 4500), (6 + 128, 4500), (7 + 128, 5000)):
        r = _run(rig, "TMCM-6212", mode, sc)
        assert r.phys() == result, mode


def test_search_and_calibration_speeds(rig):
    """TMCM-6212 manual 6.1 notes: "Until the reference switch is found for the first time, the
    searching speed set by axis parameter 194 is used"; the calibration moves use AP195."""
    sc = {"axis": {"0": {"left": {"position": -20000, "hysteresis": 400}}}}
    r = rig("TMCM-6212", sc)
    r.sap(5, 200000)                   # AMAX: 40000 pps reached after 0.2 s
    r.sap(194, 40000)
    r.sap(195, 1000)
    r.cmd(13, 0)
    r.vm.advance(0.25)
    assert r.gap(3) == -40000
    r.vm.advance(0.5)                  # the switch was hit at t = 0.6 s; leaving it takes 0.4 s
    assert r.gap(3) == 1000
    r.search()
    log = r.vm.reference_search(r.vm.axes[0]).log
    assert log[2:4] == [("leave", "left", -19599), ("enter", "left", -20000)]
    assert r.phys() == -19800          # centre of -19599 and -20000, rounded half to even


def test_rfs_stop_and_status(rig):
    """TMCM-6212 manual 3.6.11: RFS STOP stops the search; RFS STATUS is 0 when no search runs."""
    r = rig("TMCM-6212", STAGE)
    assert r.cmd(13, 2) == 0
    r.cmd(13, 0)
    r.vm.advance(0.1)
    assert r.cmd(13, 2) != 0
    r.cmd(13, 1)
    r.vm.advance(1)
    assert r.cmd(13, 2) == 0
    assert r.gap(3) == 0
    assert -20000 < r.gap(1) < 0


def test_a_search_without_a_search_speed_parameter_stands_until_rfs_stop(tmp_path):
    """TMCM-6212 3.6.11 RFS (START 0, STOP 1, STATUS 2) and 4.1 AP194 "Reference search speed";
    docs/profiles.md `[remove]`. On a profile without AP194 the speed of the switch search reads
    as 0 (as a parameter the module lacks reads through `get_raw`): the motor does not leave 0,
    the search stays active (STATUS 1), and RFS STOP ends it (STATUS 0)."""
    path = tmp_path / "nospeed.toml"
    path.write_text('extends = "TMCM-6212"\n[module]\nname = "NOSPEED-6212"\n'
                    "[remove]\naxis_parameter = [194]\n")
    vm = VirtualModule(str(path), scenario=STAGE)
    assert vm.request(6, 194, 0).status == 3
    assert vm.request(13, 0, 0).status == 100
    vm.advance(1.0)
    assert (vm.request(13, 2, 0).value, vm.request(6, 1, 0).value) == (1, 0)
    assert vm.request(13, 1, 0).status == 100
    assert vm.request(13, 2, 0).value == 0


@pytest.mark.parametrize(("start", "found"), [(-20000, 0), (-19999, -1)])
def test_search_log_records_a_switch_found_where_the_search_starts(rig, start, found):
    """reference.py `ReferenceSearch.log` "Phases of the last search: (what, switch, direction or
    position)" (docs/world.md, docs/scenarios.md `vm.reference_search(vm.axes[0]).log`); TMCM-6212
    manual 6.1.1 mode 1 "only searches the left end switch". The left switch is active on
    [-23000, -20000] and the counter starts at 0: starting on its last active position the switch
    is found at once, at counter 0; starting one step outside it, it is found one step left (-1).
    Either way the switching point calibration of its inner edge follows (6.1 notes)."""
    sc = {"axis": {"0": {**STAGE["axis"]["0"], "start": start}}}
    r = rig("TMCM-6212", sc)
    r.sap(193, 1)
    r.search()
    log = r.vm.reference_search(r.vm.axes[0]).log
    assert log[:2] == [("seek", "left", -1), ("found", "left", found)]
    assert log[2:4] == [("leave", "left", found + 1), ("enter", "left", found)]   # inner edge
    assert log[-1][0] == "zero" and r.gap(1) == 0


def test_soft_stop_overshoot_is_calibrated_away(rig):
    """TMCM-6212 manual 4.1 AP26 soft stop: the motor brakes past the switching point; the
    calibration at AP195 still finds the switching points."""
    r = rig("TMCM-6212", STAGE)
    r.sap(26, 1)
    r.sap(193, 7)
    r.search()
    assert r.phys() == 5000


def test_wait_rfs_in_a_program(rig):
    """TMCM-6212 manual 3.6.20 WAIT RFS: "Wait until the reference search of the motor ... has
    been reached" - the program continues after the search, position 0."""
    r = rig("TMCM-6212", STAGE)
    w = Wire(r.vm)
    w.load("SAP 193, 0, 1\nRFS START, 0\nWAIT RFS, 0, 0\nGAP 197, 0\nSTOP")
    w.run()
    r.vm.advance(5)
    assert w.a == -20000
    assert r.gap(1) == 0


MODES_1180 = {
    # PD86-1180 7.1: "in modes 1 and 2, the motor will start by moving left"
    1: ([("seek", "left", -1), ("found", "left", -20000), *L_IN], -20000, 0),
    2: ([("seek", "right", 1), ("found", "right", 30000), *R_IN,
         ("seek", "left", -1), ("found", "left", -20000), *L_IN], -20000, 49999),
}


@pytest.mark.parametrize("mode", sorted(MODES_1180))
def test_1180_modes(rig, mode):
    """PD86-1180 manual 5 AP193 modes 1 and 2, 7.1: "After hitting the reference switch, the
    motor slowly moves right until the switch is released. Finally the switch is re-entered in
    left direction, setting the reference point to the center of the two switching points".
    Revision history 10.1, firmware 4.41: "the last position before setting the counter to zero
    can be read out with axis parameter 197"."""
    sc = {"axis": {"0": {"left": {"position": -20000}, "right": {"position": 30000}}}}
    log, ref, distance = MODES_1180[mode]
    r = _run(rig, "TMCM-1180", mode, sc)
    assert r.vm.reference_search(r.vm.axes[0]).log == [*log, ("zero", None, ref)]
    assert r.phys() == ref and r.gap(1) == 0 and r.gap(196) == distance
    assert r.gap(197) == ref
    assert r.gap(209) == 0


def test_1180_three_switch_mode(rig):
    """PD86-1180 manual 7.1: "In mode 3 (three-switch mode), the right stop switch is searched
    first to distinguish the left stop switch from the reference switch by the order of
    activation when moving left (reference switch and left limit switch share the same
    electrical function)" - the first REFL activation moving left is the reference switch;
    manual 5 AP193: "3 search right stop switch, then search left stop switch from both sides",
    so the origin is the middle of the reference switch (4500..5500), not its upper edge."""
    sc = {"axis": {"0": {"left": {"position": -20000}, "right": {"position": 30000},
                         "home": {"position": 5000, "width": 1000}}}}
    r = _run(rig, "TMCM-1180", 3, sc)
    log = r.vm.reference_search(r.vm.axes[0]).log
    assert log[:2] == [("seek", "right", 1), ("found", "right", 30000)]
    assert ("found", "left", 5500) in log           # REFL = the home switch, met from the right
    assert log[-3:-1] == [("leave", "left", 4499), ("enter", "left", 4500)]   # its far side
    assert r.phys() == 5000
    assert r.gap(1) == 0 and r.gap(197) == 5000
    assert r.gap(196) == 25000       # 29999.5 - 5000, rounded half to even


@pytest.mark.parametrize("hysteresis", [0, 1, 100, 101])
def test_1180_three_switch_mode_with_switch_hysteresis(rig, hysteresis):
    """PD86-1180 manual 7.1: "the switch is re-entered in left direction, setting the reference
    point to the center of the two switching points" - with a switch hysteresis h each side's
    two switching points are h + 1 microsteps apart, and the origin is the mean of both centres
    (symmetric: the middle of the switch whatever h)."""
    sc = {"axis": {"0": {"left": {"position": -20000}, "right": {"position": 30000},
                         "home": {"position": 5000, "width": 1000, "hysteresis": hysteresis}}}}
    r = _run(rig, "TMCM-1180", 3, sc)
    log = r.vm.reference_search(r.vm.axes[0]).log
    upper = [x for what, sw, x in log if sw == "left" and what in ("leave", "enter")][:2]
    assert upper == [5500 + hysteresis + 1, 5500]
    assert r.phys() == 5000


def test_1180_plus_128_inverts_the_reference_input(rig):
    """PD86-1180 manual 5 AP193: "Adding 128 to these values reverses the polarity of the home
    switch input" (mode 129 with a normally closed left switch)."""
    sc = {"axis": {"0": {"left": {"position": -20000, "inverted": True}}}}
    r = _run(rig, "TMCM-1180", 129, sc)
    assert r.phys() == -20000 and r.gap(1) == 0


# A stage for the home-switch modes whose home switch lies behind the slider or beyond an end
# switch: left switch on [-23000, -20000], right on [30000, 33000], the slider starts at 10000.
BEHIND = {"axis": {"0": {"start": 10000, "left": {"position": -20000, "width": 3000},
                         "right": {"position": 30000, "width": 3000},
                         "home": {"position": 5000, "width": 1000}}}}
H_HI = [("leave", "home", 5501), ("enter", "home", 5500)]         # upper edge, met moving left
BEYOND = {"axis": {"0": {"left": {"position": -20000, "width": 3000},
                         "right": {"position": 30000, "width": 3000},
                         "home": {"position": -40000, "width": 1000}}},
          "axis_right": {"0": {"left": {"position": -20000, "width": 3000},
                               "right": {"position": 30000, "width": 3000},
                               "home": {"position": 40000, "width": 1000}}}}

FIGURES = {
    # 6.1.5 (figure 7): "searches the home switch in negative direction" - found at once moving left
    (5, "behind"): ([("seek", "home", -1), ("found", "home", 5500), *H_HI], 5500),
    # 6.1.6 (figure 8, table 21): positive direction, "reverse the direction when right stop
    # switch reached", then the home switch is met moving left
    (6, "behind"): ([("seek", "home", 1), ("turn", "right", 30000), ("found", "home", 5500), *H_HI], 5500),
    # table 21 mode 8: negative direction, the middle of the switch (both edges)
    (8, "behind"): ([("seek", "home", -1), ("found", "home", 5500), *H_HI,
                     ("leave", "home", 4499), ("enter", "home", 4500)], 5000),
}


@pytest.mark.parametrize(("mode", "stage"), sorted(FIGURES))
def test_home_switch_modes_from_the_other_side(rig, mode, stage):
    """TMCM-6212 manual 6.1.5, 6.1.6 and table 21 (figures 7, 8 and 10): the home switch modes
    with the slider right of the home switch - the sequence of switch events, the reference point
    at the centre of the switching points (modes 5/6) or the middle of the switch (mode 8)."""
    log, ref = FIGURES[(mode, stage)]
    r = _run(rig, "TMCM-6212", mode, BEHIND)
    counter = [(what, sw, x if what == "seek" else x - 10000) for what, sw, x in log]  # counter 0 at 10000
    assert r.vm.reference_search(r.vm.axes[0]).log == [*counter, ("zero", None, ref - 10000)]
    assert r.phys() == ref
    assert r.gap(1) == 0 and r.gap(209) == 0 and r.gap(197) == ref - 10000


@pytest.mark.parametrize(("mode", "scenario", "middle"), [(7, "axis_right", 40000), (8, "axis", -40000)])
def test_modes_7_and_8_ignore_the_end_switches(rig, mode, scenario, middle):
    """TMCM-6212 manual table 21: mode 7 "Search home switch in positive direction, ignore end
    switches", mode 8 the same in negative direction - the motor drives through the limit
    switch to a home switch beyond it and zeroes at the middle of the home switch."""
    r = rig("TMCM-6212", {"axis": BEYOND[scenario]})
    r.sap(193, mode)
    r.search()
    log = r.vm.reference_search(r.vm.axes[0]).log
    assert log[:2] == [("seek", "home", 1 if mode == 7 else -1), ("found", "home", middle - (1 if mode == 7 else -1) * 500)]
    assert not any(what == "turn" for what, _, _ in log)
    r.search()
    assert r.phys() == middle and r.gap(1) == 0


@pytest.mark.parametrize(("mode", "ref"), [(129, 4500), (130, 4500), (131, 5000), (132, -40000)])
def test_129_to_132_are_modes_5_to_8_with_an_inverted_home_switch(rig, mode, ref):
    """TMCM-6212 manual 6.1.5-6.1.8: "Add 128 to the mode number (i.e. set axis parameter #193
    to 129) to reverse the polarity of the home switch input" (129..132 for modes 5..8, see
    docs/assumptions.md) - a normally closed home switch is found as in modes 5..8."""
    home = {"position": -40000 if mode == 132 else 5000, "width": 1000, "inverted": True}
    sc = {"axis": {"0": {"left": {"position": -20000, "width": 3000},
                         "right": {"position": 30000, "width": 3000}, "home": home}}}
    r = _run(rig, "TMCM-6212", mode, sc)
    assert r.vm.reference_search(r.vm.axes[0]).log[0][:2] == ("seek", "home")
    assert r.phys() == ref and r.gap(1) == 0


@pytest.mark.parametrize(("command", "value"), [(3, 0), (4, 1000), (1, 5000)])
def test_a_motion_command_ends_a_running_search(rig, command, value):
    """TMCM-6212 manual 3.6.11: RFS STATUS tells "if it already has finished"; the manual does
    not say what MST, MVP or ROR do to a running search - here they take the motor over and end
    the search (docs/assumptions.md), so RFS STATUS and WAIT RFS do not wait for ever."""
    r = rig("TMCM-6212", STAGE)
    r.cmd(13, 0)
    r.vm.advance(0.2)
    assert r.cmd(13, 2) != 0
    r.cmd(command, 0, 0, value)
    r.vm.advance(0.01)
    assert r.cmd(13, 2) == 0
    assert r.vm.reference_search(r.vm.axes[0]).log[-1][0] == "interrupted"
    r.vm.advance(3)
    assert r.gap(3) == (value if command == 1 else 0)
    if command == 4:
        assert r.gap(1) == 1000


def test_shutdown_pin_ends_a_running_search(rig):
    """PD86-1180 manual 6 GP80 "Select the functionality of the SHUTDOWN pin": an active pin
    stops the motor, so the search it was driving ends (RFS STATUS 0)."""
    r = rig("TMCM-1180", {"axis": {"0": {"left": {"position": -20000}}}})
    r.cmd(9, 80, 0, 1)
    r.cmd(13, 0)
    r.vm.advance(0.5)
    r.vm.world.set_shutdown(1)
    r.vm.advance(0.5)
    assert r.gap(3) == 0
    assert r.cmd(13, 2) == 0


# --- after the search: the origin is set on the target too (issue 10, section 4) ---------------
SWITCHES = {"axis": {"0": {"left": {"position": -20000}, "right": {"position": 30000}}}}
MODULES = ["TMCM-6212", "TMCM-1021", "TMCM-1180"]


@pytest.mark.parametrize("module", MODULES)
def test_target_and_actual_agree_after_a_search(rig, module):
    """TMCM-6212 manual 4.1 AP8 "Position reached flag": "This flag is always set when target
    position and actual position are equal" - after a search both are 0, so AP8 reads 1."""
    r = rig(module, SWITCHES)
    r.sap(193, 1)
    r.search()
    assert r.gap(1) == 0
    assert r.gap(0) == 0
    assert r.gap(8) == 1


@pytest.mark.parametrize("module", MODULES)
def test_mvp_rel_after_a_cancelled_move_and_a_search(rig, module):
    """TMCM-6212 manual 3.6.4 MVP: "Starting a relative movement by means of an offset to the
    actual position"; AP127 = 0 "last target position". A move cancelled by MST, then a
    search, then MVP REL 1000: the motor goes to 1000 in the new coordinates (1000 microsteps
    right of the origin), not to the old target + 1000."""
    r = rig(module, SWITCHES)
    r.sap(193, 1)
    r.cmd(4, 0, 0, 25000)          # MVP ABS 25000 ...
    r.vm.advance(0.3)
    r.cmd(3)                       # ... cancelled by MST
    r.vm.advance(2)
    assert r.gap(0) == 25000 and 0 < r.gap(1) < 25000
    r.search()
    r.cmd(4, 1, 0, 1000)           # MVP REL 1000
    r.vm.advance(5)
    assert r.gap(1) == 1000 and r.gap(0) == 1000 and r.gap(8) == 1
    assert r.phys() == -20000 + 1000


@pytest.mark.parametrize("module", MODULES)
def test_wait_pos_after_wait_rfs_returns(rig, module):
    """TMCM-6212 manual 3.6.20 WAIT POS: "Wait until the target position of the motor ... has
    been reached"; after WAIT RFS target and actual position are both the origin, so a WAIT POS
    with no timeout continues at once (here: the program reaches its last instruction)."""
    r = rig(module, SWITCHES)
    r.cmd(4, 0, 0, 25000)
    r.vm.advance(0.3)
    r.cmd(3)
    r.vm.advance(2)
    w = Wire(r.vm)
    w.load("SAP 193, 0, 1\nRFS START, 0\nWAIT RFS, 0, 0\nWAIT POS, 0, 0\nSAP 1, 0, 777\nSTOP")
    w.run()
    r.vm.advance(60)
    assert r.gap(1) == 777


def _every_mode():
    """(module, AP193 value) for every value each profile's row accepts."""
    from opentmcl.modules.profile import load_profile

    return [(m, v) for m in MODULES for v in load_profile(m).axis_parameter(193).values]


def _stage_for(module: str, mode: int) -> dict:
    """Left switch on [-23000, -20000], right on [30000, 33000], home on [4500, 5500] (none on
    the TMCM-1180, whose reference input is the left one); the switch that +128 inverts is
    normally closed; the slider starts left of the home switch, right of it for the modes that
    search it in negative direction only (8: from 10000)."""
    base = mode & 0x3F
    if module == "TMCM-6212" and mode & 128 and base <= 4:
        base += 4                       # 129..132 are modes 5..8 (TMCM-6212 6.1.5-6.1.8)
    inverted = bool(mode & 128)
    axis = {"start": 10000 if base == 8 else 0,
            "left": {"position": -20000, "width": 3000, "inverted": inverted and module == "TMCM-1180"},
            "right": {"position": 30000, "width": 3000}}
    if module != "TMCM-1180":
        axis["home"] = {"position": 5000, "width": 1000, "inverted": inverted}
    return {"axis": {"0": axis}}


@pytest.mark.parametrize(("module", "mode"), _every_mode())
def test_every_mode_ends_with_target_equal_to_actual(rig, module, mode):
    """TMCM-6212 manual 4.1 AP8: "This flag is always set when target position and actual position
    are equal"; 3.6.4 MVP REL: "an offset to the actual position". Every reference search mode on
    every module, after a move cancelled far from the switches (its target left in the old
    coordinates): target and actual both read 0, AP8 reads 1, the motor stands, and MVP REL 100
    (-100 for the +64 modes, whose reference is the right switch) ends 100 microsteps from the
    reference point."""
    sc = _stage_for(module, mode)
    r = rig(module, sc)
    r.sap(193, mode)
    start = sc["axis"]["0"]["start"]
    r.cmd(4, 0, 0, start + 40000)    # MVP ABS far right ...
    r.vm.advance(0.2)
    r.cmd(3)                         # ... cancelled by MST
    r.vm.advance(2)
    assert r.gap(0) == start + 40000 and r.gap(1) != r.gap(0)
    r.search()
    assert (r.gap(0), r.gap(1), r.gap(8), r.gap(3)) == (0, 0, 1, 0)
    origin, step = r.phys(), -100 if mode & 64 else 100    # away from the reference switch
    r.cmd(4, 1, 0, step)             # MVP REL
    r.vm.advance(5)
    assert (r.gap(0), r.gap(1), r.gap(8)) == (step, step, 1)
    assert r.phys() == origin + step
