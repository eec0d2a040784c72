"""Axis-world and reference-search edges left unpinned by the seeded firmware mutation sample of
round 23, group B (issue 12; `python bench/mutation.py --layer firmware --sample 300 --seed 12`)."""
from __future__ import annotations

import pytest

from opentmcl import VirtualModule
from opentmcl.motion.scenario import ScenarioError

from .test_reference import STAGE

V = 51200       # pps; the TMCM-6212's default AP5 accelerates to it in one second
TICK = 1 / 16e6  # one tick of the 16 MHz clock, the VM's time step


def _removing(tmp_path, number: int):
    path = tmp_path / f"no{number}.toml"
    path.write_text(f'extends = "TMCM-6212"\n[module]\nname = "NO{number}-6212"\n'
                    f"[remove]\naxis_parameter = [{number}]\n")
    return str(path)


# --- AP212 maximum encoder deviation while the stage stands ------------------------------------

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


# --- AP167 (TOFF) on a profile without AP168 ------------------------------------------------------

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


# --- AxisWorld.set_load with a number ------------------------------------------------------------

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


# --- a load ramp over time is seen every millisecond ------------------------------------------

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


# --- a limit switch stops each command into it --------------------------------------------------

def _commands_into_an_active_right_switch(rig, times: int):
    r = rig("TMCM-6212", {"axis": {"0": {"right": {"position": 0, "width": 100000}}}})
    assert r.gap(10) == 1
    for _ in range(times):
        r.cmd(1, 0, 0, V)
        r.vm.advance(TICK)
    r.vm.advance(0.5)
    return r.gap(3), r.gap(1)


@pytest.mark.parametrize("times", [1, 2, 3, 4])
def test_ror_into_an_active_right_switch_stops_each_time(rig, times):
    """TMCM-6212 manual 4.1 AP10 "Right limit switch state" and AP12 "Deactivates the stop function
    of the right limit switch if set to 1" (default 0: the switch stops the motor): the stage starts
    on an actuated right switch; ROR given again at each of up to four consecutive ticks is stopped
    each time, the motor stands at 0."""
    assert _commands_into_an_active_right_switch(rig, times) == (0, 0)


def test_ror_into_an_active_right_switch_five_ticks_in_a_row_is_stopped_too(rig):
    """As above (TMCM-6212 4.1 AP10/AP12): the fifth command at the next tick is stopped as well.
    (Before round 23 the check at the next tick gave up after 4 due ticks in a row even when each
    was a new command, so the fifth ROR ran into the switch.)"""
    assert _commands_into_an_active_right_switch(rig, 5) == (0, 0)


# --- the search log when the switch is already active --------------------------------------------

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


# --- power-up refuses an input port the module lacks ---------------------------------------------

def test_power_up_names_bank_and_port_of_a_missing_input():
    """TMCM-6212 manual 3.6.13 GIO: bank 1 holds the analog inputs AIN0..AIN3 (ports 0..3);
    docs/scenarios.md `[[input]]` `bank`, `port` "the GIO address". Port 3 (the last) is driven,
    port 4 (the first beyond) is refused with a ScenarioError naming bank and port."""
    vm = VirtualModule("TMCM-6212", scenario={"input": [{"bank": 1, "port": 3, "value": 1000}]})
    assert vm.request(15, 3, 1).value == 1000
    with pytest.raises(ScenarioError, match=r"^input bank 1 port 4: TMCM-6212 has no such port$"):
        VirtualModule("TMCM-6212", scenario={"input": [{"bank": 1, "port": 4, "value": 1000}]})


# --- a check at the next tick that cannot resolve its condition does not stall time -------------

@pytest.mark.parametrize("command_each_tick", [False, True])
def test_an_unresolved_next_tick_check_gives_up_after_four_ticks(rig, monkeypatch, command_each_tick):
    """world_events.py `EventLookup._due_again`: "A check is due at the next tick; not more than 4
    ticks in a row, since a check that cannot resolve it must not stall time" (docs/architecture.md
    "Time": events are looked up, not polled). A condition that stays due (here forced) is checked
    at the next tick 4 times, then only at the axis's own events: a millisecond of virtual time
    (16000 ticks) of a moving axis takes a handful of checks, not one per tick. A command at each
    tick starts the count again (docs/assumptions.md, "A check at the next tick")."""
    from opentmcl.firmware.world_checks import Checks
    r = rig("TMCM-6212", STAGE)
    r.cmd(1, 0, 0, V)
    r.vm.advance(0.01)
    checks = []
    original = Checks.run
    monkeypatch.setattr(Checks, "due_now", lambda self: self.aw.index == 0)
    monkeypatch.setattr(Checks, "run", lambda self: (checks.append(r.vm.now), original(self))[1])
    if command_each_tick:
        for _ in range(6):
            r.cmd(1, 0, 0, V + len(checks))  # a new plan at each tick
            r.vm.advance(TICK)
        assert len(set(checks)) >= 6
    else:
        r.cmd(1, 0, 0, V + 1)  # one command, then none for 16000 ticks
        r.vm.advance(0.001)
        assert 4 <= len(set(checks)) <= 12
