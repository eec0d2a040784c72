"""Edges of the axis world and its Python API (docs/scenarios.md "Python API"), found unpinned by
mutation testing (docs/mutation.md)."""
from __future__ import annotations

from opentmcl.firmware import flags

from .test_switches import STAGE


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


def test_set_shutdown_drives_the_shutdown_pin(rig):
    """docs/scenarios.md: `vm.world.set_shutdown(1)  # SHUTDOWN pin high`; PD86-1180 manual 6 GP80
    "Shutdown pin functionality: ... 1 - high active": a pin set high from Python stops the moving
    motor and sets ESD (TMCM-6212 3.6.16 "12 ESD - shutdown error"); set low it does not."""
    low = rig("TMCM-1180", {})
    low.cmd(9, 80, 0, 1)
    low.vm.world.set_shutdown(0)
    low.cmd(1, 0, 0, 300)
    low.vm.advance(0.5)
    assert low.gap(3) != 0 and not low.vm.flags & flags.ESD
    high = rig("TMCM-1180", {})
    high.cmd(9, 80, 0, 1)
    high.cmd(1, 0, 0, 300)
    high.vm.advance(0.2)
    high.vm.world.set_shutdown(1)
    high.vm.advance(0.2)
    assert high.gap(3) == 0 and high.vm.flags & flags.ESD


def test_1180_null_channel_clear_keeps_an_odd_prescaler(rig):
    """PD86-1180 manual 7.2: "Other values between those given in the table can be used" for the
    prescaler <p>, and "just add the following value to <p>: ... 4 Clear encoder with next null
    channel event": once the encoder is cleared, AP210 is the prescaler 6401 without the adder."""
    r = rig("TMCM-1180", {"axis": {"0": {"start": 100}}})
    r.sap(210, 6401 + 4)
    r.cmd(4, 0, 0, 5000)
    r.vm.advance(30)
    assert r.gap(1) == 5000
    assert r.gap(210) == 6401


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
