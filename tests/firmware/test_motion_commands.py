"""Motion commands in direct mode: ROR, ROL, MST, MVP ABS/REL/COORD (TMCM-6212 manual 3.6.1-3.6.4)."""
from __future__ import annotations

import pytest

from opentmcl import VirtualModule

from .conftest import Host


def test_ror_rol_mst(m6212):
    """3.6.1 ROR "rotate with a specified velocity in right direction (increasing the position counter)",
    3.6.2 ROL decreasing it, 3.6.3 MST "stop with a soft stop"."""
    m6212.ok(1, 0, 0, 51200)
    m6212.vm.advance(1.0)
    assert m6212.ok(6, 3, 0) == 51200 and m6212.ok(6, 2, 0) == 51200
    p1 = m6212.ok(6, 1, 0)
    assert p1 > 0
    m6212.ok(2, 0, 1, 51200)
    m6212.vm.advance(1.0)
    assert m6212.ok(6, 3, 1) == -51200 and m6212.ok(6, 1, 1) < 0
    m6212.ok(3, 0, 0)
    assert m6212.ok(6, 2, 0) == 0
    m6212.vm.advance(0.01)
    assert 0 < m6212.ok(6, 3, 0) < 51200       # soft stop: still decelerating
    m6212.vm.advance(2.0)
    assert m6212.ok(6, 3, 0) == 0


def test_mvp_abs_arrives_exactly(anymod):
    """3.6.4 MVP ABS: the motor moves to the absolute position and AP8 "Position reached flag ... set when
    target position and actual position are equal"."""
    anymod.ok(4, 0, 0, 12345)
    assert anymod.ok(6, 0, 0) == 12345
    assert anymod.ok(6, 8, 0) == 0
    anymod.vm.advance(120.0)
    assert anymod.ok(6, 1, 0) == 12345
    assert anymod.ok(6, 8, 0) == 1
    assert anymod.ok(6, 3, 0) == 0


def test_mvp_rel_from_last_target_default_6212(m6212):
    """TMCM-6212 4.1 AP127 "Start position for MVP REL command: 0 last target position, 1 actual position";
    3.6.4 example "MVP REL, 0, -10000"."""
    m6212.ok(4, 0, 0, 100000)
    m6212.vm.advance(0.05)                       # still on the way
    m6212.ok(4, 1, 0, -10000)
    assert m6212.ok(6, 0, 0) == 90000            # last target + offset
    m6212.ok(5, 127, 0, 1)
    actual = m6212.ok(6, 1, 0)
    m6212.ok(4, 1, 0, 10)
    assert m6212.ok(6, 0, 0) == actual + 10


def test_mvp_rel_from_encoder_position_6212(m6212):
    """TMCM-6212 4.1 AP127 "Start position for MVP REL command: ... 2 encoder position": the offset is
    added to the encoder position AP209 as the module reads it now (after a move the encoder has
    counted along), not to a stale value."""
    m6212.ok(4, 0, 0, 5000)
    m6212.vm.advance(3.0)
    encoder = m6212.ok(6, 209, 0)
    assert encoder != 0
    m6212.ok(5, 127, 0, 2)
    m6212.ok(4, 1, 0, 100)
    assert m6212.ok(6, 0, 0) == encoder + 100


def test_mvp_rel_from_actual_position_1180(m1180):
    """PD86-1180 4.6.4 MVP REL: "a relative movement by means of an offset to the actual position"."""
    m1180.ok(5, 1, 0, 300)
    m1180.ok(4, 1, 0, 200)
    assert m1180.ok(6, 0, 0) == 500


def test_mvp_wrap_takes_the_short_way(m6212):
    """3.6.4 Note: "The distance between the actual position and the new position must not be more than
    2147483647 microsteps. Otherwise the motor will run in the opposite direction in order to take the
    shorter distance (caused by 32 bit overflow)." """
    m6212.ok(5, 1, 0, 2**31 - 1000)
    m6212.ok(4, 0, 0, -(2**31) + 1000)           # 2000 steps forward through the wrap
    m6212.vm.advance(0.01)
    assert m6212.ok(6, 3, 0) > 0
    m6212.vm.advance(2.0)
    assert m6212.ok(6, 1, 0) == -(2**31) + 1000


def test_mvp_rel_wraps_32_bit(m6212):
    """3.6.4: the range of MVP is 32 bit signed; a REL target beyond it wraps."""
    m6212.ok(5, 127, 0, 1)
    m6212.ok(5, 1, 0, 2**31 - 10)
    m6212.ok(4, 1, 0, 20)
    assert m6212.ok(6, 0, 0) == -(2**31) + 10


def test_target_change_on_the_fly(m6212):
    """TMCM-6212 1 "On the fly alteration of motion parameters (e.g. position, velocity, acceleration)"."""
    m6212.ok(4, 0, 0, 200000)
    m6212.vm.advance(0.3)
    m6212.ok(4, 0, 0, -5000)
    m6212.vm.advance(10.0)
    assert m6212.ok(6, 1, 0) == -5000


def test_mvp_invalid_motor(m6212):
    """3.6.4 Binary representation: motor 0...5."""
    assert m6212(4, 0, 6, 10).status == 4


def test_heartbeat_stops_motors(m6212):
    """TMCM-6212 5.1 GP68 "If this time limit is up and no further command is received by the module the
    motor will be stopped."""
    m6212.ok(9, 68, 0, 500)
    m6212.ok(1, 0, 0, 1000)
    m6212.vm.advance(0.4)
    assert m6212.ok(6, 3, 0) == 1000             # the GAP itself is a command: heartbeat restarts
    m6212.vm.advance(0.6)
    assert m6212.vm.axes[0].engine.velocity == 0


def test_advance_splits_do_not_matter():
    """docs/architecture.md "Time": advance jumps between events — one long advance equals many short ones."""
    a, b = Host(VirtualModule("TMCM-6212")), Host(VirtualModule("TMCM-6212"))
    for h in (a, b):
        h.ok(4, 0, 0, 51200)
        h.ok(1, 0, 1, 30000)
    a.vm.advance(1.0)
    for _ in range(100):
        b.vm.advance(0.01)
    for axis in (0, 1):
        assert a.ok(6, 1, axis) == b.ok(6, 1, axis)


@pytest.mark.parametrize("name", ["TMCM-1021", "TMCM-1180", "tmcm-6212", "PD28-1021"])
def test_module_aliases(name):
    """Issue: VirtualModule accepts "TMCM-1021" and "TMCM-1180" as well."""
    VirtualModule(name)


def test_unknown_module_is_a_clear_error():
    with pytest.raises(KeyError, match="unknown module"):
        VirtualModule("TMCM-9999")


def test_1180_actual_speed_write_holds_velocity(m1180):
    """PD86-1180 5: AP3 "Actual speed" is RW (±2047); a write sets the TMC429 velocity at once (hold mode)."""
    m1180.ok(5, 3, 0, 300)
    assert m1180.ok(6, 3, 0) == 300
    m1180.vm.advance(0.1)
    assert m1180.ok(6, 3, 0) == 300 and m1180.ok(6, 1, 0) > 0
    assert m1180(5, 3, 0, 3000).status == 4


def test_1180_actual_acceleration_ap135(m1180):
    """PD86-1180 5: AP135 "Actual acceleration" reads the ramp generator's current acceleration."""
    m1180.ok(4, 0, 0, 100000)
    m1180.vm.advance(0.01)
    assert m1180.ok(6, 135, 0) == m1180.ok(6, 5, 0)
    m1180.ok(3, 0, 0)
    m1180.vm.advance(60)
    assert m1180.ok(6, 135, 0) == 0


def test_1180_ramp_mode_follows_the_motion_commands(m1180):
    """PD86-1180 ch. 5 AP138 "Ramp mode: Automatically set when using ROR, ROL, MST and MVP. 0: position
    mode ... 2: velocity mode ... the soft mode (value 1) ... can be selected": GAP 138 reads the mode
    the last motion command chose, and a selected soft mode stays selected for MVP."""
    assert m1180.ok(6, 138, 0) == 0
    m1180.ok(1, 0, 0, 500)                      # ROR
    assert m1180.ok(6, 138, 0) == 2
    m1180.ok(4, 0, 0, 1000)                     # MVP ABS
    assert m1180.ok(6, 138, 0) == 0
    m1180.ok(2, 0, 0, 300)                      # ROL
    assert m1180.ok(6, 138, 0) == 2
    m1180.ok(4, 0, 0, 0)
    m1180.ok(3, 0, 0)                           # MST: velocity mode, target speed 0
    assert m1180.ok(6, 138, 0) == 2
    m1180.ok(5, 138, 0, 1)                      # soft mode selected
    m1180.ok(4, 0, 0, 2000)
    assert m1180.ok(6, 138, 0) == 1


def test_1180_ror_rol_velocity_edges(m1180):
    """PD86-1180 4.6.1/4.6.2: ROR/ROL <velocity> "0… 2047" ("This makes possible choosing a velocity
    between 0 and 2047"): both ends accepted, 2048 and -1 are status 4 (issue 29 item 7; ROL turns
    left, so no negative velocity is needed)."""
    got = {(op, v): m1180(op, 0, 0, v).status for op in (1, 2) for v in (0, 2047, 2048, -1, -2047)}
    assert got == {(1, 0): 100, (1, 2047): 100, (1, 2048): 4, (1, -1): 4, (1, -2047): 4,
                   (2, 0): 100, (2, 2047): 100, (2, 2048): 4, (2, -1): 4, (2, -2047): 4}
    m1180.ok(2, 0, 0, 100)
    assert m1180.ok(6, 2, 0) == -100


def test_sap_2_during_a_positioning_move_changes_no_motion(anymod):
    """AP2 "Target speed": "The desired speed in velocity mode. Not valid in position mode"
    (TMCM-6212 4.1, PD28-1021 5; PD86-1180 5: "set by hardware"). SAP 2 while MVP runs is
    accepted, and the move goes on to its target: no rotation the host did not ask for."""
    anymod.ok(4, 0, 0, 12345)
    anymod.vm.advance(0.05)
    assert anymod.ok(6, 3, 0) != 0
    anymod.ok(5, 2, 0, 100)
    anymod.vm.advance(120.0)
    assert anymod.ok(6, 1, 0) == 12345
    assert anymod.ok(6, 8, 0) == 1 and anymod.ok(6, 3, 0) == 0
    anymod.ok(5, 2, 0, -100)                # at rest in position mode: still no motion
    anymod.vm.advance(1.0)
    assert anymod.ok(6, 1, 0) == 12345 and anymod.ok(6, 3, 0) == 0


def test_sap_2_in_velocity_mode_sets_the_speed(anymod):
    """AP2: "The desired speed in velocity mode" - after ROR, SAP 2 changes the speed (the last
    valid value of the PD86-1180's 2047 range, and its negative: the other direction)."""
    anymod.ok(1, 0, 0, 100)
    anymod.ok(5, 2, 0, 2047)
    anymod.vm.advance(30.0)
    assert anymod.ok(6, 3, 0) == 2047
    anymod.ok(5, 2, 0, -2047)
    anymod.vm.advance(30.0)
    assert anymod.ok(6, 3, 0) == -2047


def test_ror_and_rol_take_the_range_of_the_target_speed_ap2(tmp_path):
    """TMCM-6212 3.6.1 ROR / 3.6.2 ROL "Internal function: ... the velocity value is transferred
    to axis parameter #2 (target velocity)": the range checked is AP2's. A profile that narrows
    AP2 to -1000 ... 1000 (docs/profiles.md, an existing number merged) and leaves AP3 (actual
    speed) at +-7999774 takes ROR / ROL 1000 and refuses 1001 with status 4 (invalid value)."""
    path = tmp_path / "slow.toml"
    path.write_text('extends = "TMCM-6212"\n[module]\nname = "SLOW-6212"\n'
                    "[[axis_parameter]]\nnumber = 2\nmin = -1000\nmax = 1000\n")
    h = Host(VirtualModule(str(path), address=1))
    assert h(1, 0, 0, 1000).status == 100
    assert h.ok(6, 2, 0) == 1000
    assert h(1, 0, 0, 1001).status == 4
    assert h(2, 0, 1, 1000).status == 100
    assert h.ok(6, 2, 1) == -1000
    assert h(2, 0, 1, 1001).status == 4
    assert h.ok(6, 2, 1) == -1000  # the refused ROL changed nothing
