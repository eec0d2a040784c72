"""When the world acts on a command: docs/world.md "Time: events, never steps" - a motion started
into an active switch is caught one tick (62.5 ns) later, each new command again, and a check at the
next tick that cannot resolve its condition does not stall time."""
from __future__ import annotations

import pytest

from .test_reference import STAGE as REFERENCE_STAGE
from .test_switches import STAGE

V = 51200       # pps; the TMCM-6212's default AP5 accelerates to it in one second
TICK = 1 / 16e6  # one tick of the 16 MHz clock, the VM's time step


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
    (Each new command starts the count of the checks at the next tick again: a count that gave up
    after 4 due ticks in a row, new commands or not, let the fifth ROR run into the switch.)"""
    assert _commands_into_an_active_right_switch(rig, 5) == (0, 0)


@pytest.mark.parametrize("command_each_tick", [False, True])
def test_an_unresolved_next_tick_check_gives_up_after_four_ticks(rig, monkeypatch, command_each_tick):
    """world_events.py `EventLookup._due_again`: "A check is due at the next tick; not more than 4
    ticks in a row, since a check that cannot resolve it must not stall time" (docs/architecture.md
    "Time": events are looked up, not polled). A condition that stays due (here forced) is checked
    at the next tick 4 times, then only at the axis's own events: a millisecond of virtual time
    (16000 ticks) of a moving axis takes a handful of checks, not one per tick. A command at each
    tick starts the count again (docs/assumptions.md, "A check at the next tick")."""
    from opentmcl.firmware.world_checks import Checks
    r = rig("TMCM-6212", REFERENCE_STAGE)
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
