"""Module faults on ``sim://NAME?faults=FILE`` (issue 34, "Module faults"), each checked through the
wire (GAP/GGP after the fault) or the world's state, in virtual time.

Manual references: PD86-1180 manual 4.6.x STAP/RSAP ("Most parameters are automatically restored
after power up"), 5 (AP208 "TMC262 driver error flags": bit 1 "driver is shut down due to
overtemperature", bit 2 "pre-warning overtemperature"; AP209 encoder position, AP212 maximum
encoder deviation), 6 GP77 ("Start TMCL application automatically after power up"); TMCM-6212
manual 4.1 (AP9-AP11 switch states, AP207 "extended error flags": 2 deviation error)."""
from __future__ import annotations

import pytest

from opentmcl.host import TmclTimeout

from .helpers import GAP, GGP, MVP, SAP, SGP, STAP, STGP, now, sim, vm_of

USER = 2  # bank of the user variables


def test_power_loss_restores_ram_from_the_eeprom_and_starts_the_program(tmp_path):
    """A power loss by name: RAM parameters back to their stored values (AP4 to its default, AP5 to
    the value STAP stored), the EEPROM kept, and with GP77 = 1 the stored program runs (it sets
    user variable 1 to 42); the module is silent while the power is off."""
    m = sim(tmp_path, [{"name": "cut", "kind": "power_loss", "duration": 0.3}], module="PD86-1180")
    default_ap4 = m.request(GAP, 4, 0).value
    m.request(SAP, 4, 0, default_ap4 - 7)
    m.request(SAP, 5, 0, 999)
    m.request(STAP, 5, 0)
    m.download_program([(SGP, 1, USER, 42), (28, 0, 0, 0)])   # SGP 1, 2, 42; STOP
    m.request(SGP, 77, 0, 1)
    m.request(STGP, 77, 0)
    m.request(SGP, 1, USER, 0)
    m.client.transport.faults.trigger("cut")
    with pytest.raises(TmclTimeout):
        m.request(GAP, 4, 0, timeout=0.2)
    m.client.sleep(0.2)
    assert m.request(GAP, 4, 0).value == default_ap4
    assert m.request(GAP, 5, 0).value == 999
    assert m.request(GGP, 1, USER).value == 42


@pytest.mark.parametrize(("store", "stored"), [("complete", 222), ("absent", 111)])
def test_power_loss_during_a_store(tmp_path, store, stored):
    """Power lost during the second STAP: the store is complete or absent, never torn; no reply."""
    m = sim(tmp_path, [{"kind": "power_loss", "command": "STAP", "count": 2, "store": store, "duration": 0.1}],
            module="PD86-1180")
    m.request(SAP, 5, 0, 111)
    m.request(STAP, 5, 0)
    m.request(SAP, 5, 0, 222)
    with pytest.raises(TmclTimeout):
        m.request(STAP, 5, 0)
    assert m.request(GAP, 5, 0).value == stored


def test_power_loss_at_a_time_stops_the_motor(tmp_path):
    """A power loss at 0.5 s during a move: the motor stops where it is (the stage stands), the
    position counter starts again at 0 after power-up."""
    m = sim(tmp_path, [{"kind": "power_loss", "at": 0.5, "duration": 0.2}])
    m.request(MVP, 0, 0, 500000)
    m.client.sleep(0.5)
    stage = vm_of(m).world.axis(0).physical_position
    m.client.sleep(0.5)
    assert vm_of(m).world.axis(0).physical_position == stage
    assert m.request(GAP, 1, 0).value == 0


def test_a_hung_firmware_answers_nothing_for_a_time(tmp_path):
    """hang for 1 s on the first GIO: that request and every one for 1 s go unanswered; the motion
    already running goes on (the motion controller runs the ramp on its own)."""
    m = sim(tmp_path, [{"kind": "hang", "command": "GIO", "count": 1, "duration": 1.0}])
    m.request(MVP, 0, 0, 10_000_000)
    with pytest.raises(TmclTimeout):
        m.request(15, 0, 0)
    with pytest.raises(TmclTimeout):
        m.request(GAP, 1, 0)
    m.client.sleep(0.1)
    assert now(m) > 1.0
    assert m.request(GAP, 1, 0).value > 0


def test_overtemperature_prewarning_sets_bit_2_only(tmp_path):
    """Pre-warning: AP208 bit 2, not bit 1; the driver runs on (the stage follows the counter)."""
    m = sim(tmp_path, [{"name": "warm", "kind": "overtemperature", "level": "prewarning"}])
    m.client.transport.faults.trigger("warm")
    assert m.request(GAP, 208, 0).value & 0x06 == 0x04
    m.request(MVP, 0, 0, 20000)
    m.client.sleep(2.0)
    assert vm_of(m).world.axis(0).physical_position == m.request(GAP, 1, 0).value == 20000


def test_overtemperature_shutdown_turns_the_driver_off_until_it_cools(tmp_path):
    """Shutdown: AP208 bits 1 and 2; the driver makes no torque, so the stage stands while the
    counter runs on, and the deviation check (AP212) stops the motor with AP207's deviation bit;
    after 1 s it has cooled down: the flags clear."""
    m = sim(tmp_path, [{"name": "hot", "kind": "overtemperature", "level": "shutdown", "duration": 1.0}])
    m.request(SAP, 212, 0, 1000)
    m.request(MVP, 0, 0, 200000)
    m.client.sleep(0.2)
    stage = vm_of(m).world.axis(0).physical_position
    m.client.transport.faults.trigger("hot")
    assert m.request(GAP, 208, 0).value & 0x06 == 0x06
    m.client.sleep(0.5)
    assert vm_of(m).world.axis(0).physical_position == stage
    assert m.request(GAP, 3, 0).value == 0                  # stopped by the deviation check
    assert m.request(GAP, 207, 0).value & 2
    assert abs(m.request(GAP, 1, 0).value - m.request(GAP, 209, 0).value) > 1000
    m.client.sleep(0.6)
    assert m.request(GAP, 208, 0).value & 0x06 == 0


def test_a_stuck_switch(tmp_path):
    """The left limit switch stuck at 1 for 0.5 s: AP11 reads 1 although no switch is near, then 0."""
    m = sim(tmp_path, [{"kind": "stuck_switch", "switch": "left", "level": 1, "duration": 0.5, "at": 0.1}])
    assert m.request(GAP, 11, 0).value == 0
    m.client.sleep(0.2)
    assert m.request(GAP, 11, 0).value == 1
    m.client.sleep(0.5)
    assert m.request(GAP, 11, 0).value == 0


def test_a_bouncing_switch(tmp_path):
    """The home switch bounces 4 times 10 ms apart: AP9 reads 1, 0, 1, 0, then the stage's level."""
    m = sim(tmp_path, [{"name": "b", "kind": "bouncing_switch", "switch": "home", "bounces": 4, "period": 0.01}])
    m.client.transport.faults.trigger("b")
    seen = []
    for _ in range(5):
        seen.append(m.request(GAP, 9, 0).value)
        m.client.sleep(0.01)
    assert seen == [1, 0, 1, 0, 0]


def test_lost_steps_under_load_seen_by_encoder_and_deviation_check(tmp_path):
    """step_loss (a load of 3x the torque at full current) while moving: the encoder (AP209) falls
    behind the counter (AP1) and the deviation check (AP212) stops the motor (AP207 bit 2)."""
    m = sim(tmp_path, [{"kind": "step_loss", "command": "MVP", "count": 1, "load": 3.0, "duration": 2.0}])
    m.request(SAP, 212, 0, 5000)
    m.request(MVP, 0, 0, 400000)
    m.client.sleep(1.0)
    assert m.request(GAP, 3, 0).value == 0
    assert m.request(GAP, 207, 0).value & 2
    assert m.request(GAP, 1, 0).value - m.request(GAP, 209, 0).value > 5000


def _answers(m) -> bool:
    try:
        m.request(GGP, 66, 0, timeout=0.05)
        return True
    except TmclTimeout:
        return False


def test_overlapping_power_losses_end_with_the_last(tmp_path):
    """A power loss of 1 s, and another of 1 s half a second later (a plan that fires power losses
    by chance or by name may do so): the module is off until the second ends, and powers up once
    (a SAP done after the power-up is kept)."""
    m = sim(tmp_path, [{"name": "cut", "kind": "power_loss", "duration": 1.0}], module="PD86-1180")
    m.client.transport.faults.trigger("cut")
    m.client.sleep(0.5)
    m.client.transport.faults.trigger("cut")
    m.client.sleep(0.6)                      # 1.1 s after the first: the second still holds
    assert not _answers(m)
    m.client.sleep(0.4)
    assert _answers(m)
    m.request(SAP, 4, 0, 777)
    m.client.sleep(1.0)
    assert m.request(GAP, 4, 0).value == 777
    backs = [f for f in m.client.transport.faults.log.fired if f.detail.startswith("power back")]
    assert [f.name for f in backs] == ["cut"]


def test_overlapping_overtemperatures_keep_the_flags_of_the_one_still_hot(tmp_path):
    """AP208 bit 2 "pre-warning overtemperature" for 2 s and, within it, bit 1 "driver is shut down
    due to overtemperature" for 0.5 s (PD86-1180 manual 5): when the shutdown is over the
    pre-warning stays (and the driver runs again); a second shutdown that overlaps the first keeps
    the driver off until it ends."""
    m = sim(tmp_path, [{"name": "warm", "kind": "overtemperature", "level": "prewarning", "duration": 2.0},
                       {"name": "hot", "kind": "overtemperature", "level": "shutdown", "duration": 0.5}])
    board = m.client.transport.faults
    board.trigger("warm")
    board.trigger("hot")
    m.client.sleep(0.3)
    board.trigger("hot")                     # again: hot until 0.8 s
    m.client.sleep(0.3)
    assert m.request(GAP, 208, 0).value & 0x06 == 0x06
    m.client.sleep(0.3)
    assert m.request(GAP, 208, 0).value & 0x06 == 0x04
    m.request(MVP, 0, 0, 2000)
    m.client.sleep(0.5)
    assert vm_of(m).world.axis(0).physical_position == 2000     # the driver runs again
    m.client.sleep(0.7)
    assert m.request(GAP, 208, 0).value & 0x06 == 0


def test_overlapping_stuck_switches_release_once_to_the_stage(tmp_path):
    """The left switch stuck for 1 s, and again half a second later: it reads 1 until the second
    ends, then follows the stage (0) again, not the level the first fault forced."""
    m = sim(tmp_path, [{"name": "stuck", "kind": "stuck_switch", "switch": "left", "duration": 1.0}])
    m.client.transport.faults.trigger("stuck")
    m.client.sleep(0.5)
    m.client.transport.faults.trigger("stuck")
    m.client.sleep(0.7)
    assert m.request(GAP, 11, 0).value == 1
    m.client.sleep(0.4)
    assert m.request(GAP, 11, 0).value == 0
