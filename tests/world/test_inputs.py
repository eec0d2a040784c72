"""Inputs, outputs and error flags driven by the world (item 5); the scenario's inputs are checked
against the module's ports at power-up."""
import pytest

from opentmcl import VirtualModule
from opentmcl.firmware import flags
from opentmcl.motion.scenario import ScenarioError
from opentmcl.motion.stage import Profile
from tests.firmware.test_program_support import Wire


def test_digital_input_steps_over_time(rig):
    """TMCM-6212 manual 3.6.13 GIO bank 0: the digital inputs follow the scenario's steps."""
    r = rig("TMCM-6212", {"input": [{"bank": 0, "port": 1, "steps": [[0.5, 1], [1.0, 0]]}]})
    assert r.cmd(15, 1, 0) == 0
    r.vm.advance(0.6)
    assert r.cmd(15, 1, 0) == 1
    r.vm.advance(0.5)
    assert r.cmd(15, 1, 0) == 0


def test_analog_input_ramp(rig):
    """TMCM-6212 manual 3.6.13 GIO bank 1 (analog inputs): a ramp from 0 to 4000 in 2 s."""
    r = rig("TMCM-6212", {"input": [{"bank": 1, "port": 0, "ramp": [[0, 0], [2, 4000]]}]})
    r.vm.advance(0.5)
    assert r.cmd(15, 0, 1) == 1000
    r.vm.advance(1.0)
    assert r.cmd(15, 0, 1) == 3000
    r.vm.advance(5)
    assert r.cmd(15, 0, 1) == 4000


def test_input_api(rig):
    """The world's Python API drives an input with a constant or a profile over time."""
    r = rig("TMCM-6212", {})
    r.vm.world.set_input(0, 2, 1)
    assert r.cmd(15, 2, 0) == 1
    r.vm.world.set_input(0, 2, Profile([(1.0, 0)], before=1))
    r.vm.advance(1.1)
    assert r.cmd(15, 2, 0) == 0


def test_input_signals_saturate_at_the_port_range(rig):
    """TMCM-6212 manual 3.6.13: "Digital lines will read as 0 or 1, while the ADC channels
    deliver their 16 bit result in the range of 0...65535"; PD86-1180 4.6.15: "10 bit result in
    the range of 0… 1023" - a scenario signal beyond the range reads as the range's end."""
    r = rig("TMCM-6212", {"input": [{"bank": 1, "port": 0, "ramp": [[0, 0], [1, 10**6]]},
                                    {"bank": 0, "port": 1, "value": -3}]})
    r.vm.advance(0.5)
    assert r.cmd(15, 0, 1) == 65535
    assert r.cmd(15, 1, 0) == 0
    r = rig("TMCM-1180", {"input": [{"bank": 1, "port": 0, "value": 5000}]})
    assert r.cmd(15, 0, 1) == 1023
    with pytest.raises(ValueError):
        r.vm.world.set_input(9, 9, 1)


def test_an_adin_line_reads_as_digital_and_analog_at_once(rig):
    """TMCM-6212 manual 3.6.13: "The ADIN lines can be read as digital or analogue inputs at the same
    time. The digital states can be accessed in bank 0" (analog 0...65535 in bank 1). One level per
    line: a rising analog ramp sets the digital reading from mid-scale on (docs/assumptions.md) and
    raises the input-change interrupt 39 (manual 5 bank 3 parameter 39 = 1, low-high) there;
    driving the digital side reads as full scale. PD86-1180 4.6.15 likewise with 0...1023."""
    r = rig("TMCM-6212", {"input": [{"bank": 1, "port": 0, "ramp": [[0, 0], [2, 65535]]}]})
    w = Wire(r.vm)
    w.load("SGP 39, 3, 1\nVECT 39, Changed\nEI 39\nEI 255\nLoop: JA Loop\n"
           "Changed: GGP 1, 2\nCALC ADD, 1\nAGP 1, 2\nGIO 0, 1\nAGP 2, 2\nRETI")
    w.run()
    r.vm.advance(0.9)
    assert (r.cmd(15, 0, 0), r.cmd(10, 1, 2)) == (0, 0)
    r.vm.advance(0.2)                                   # 32768 is crossed at 1.0 s
    assert (r.cmd(15, 0, 0), r.cmd(10, 1, 2)) == (1, 1)
    assert 32768 <= r.cmd(10, 2, 2) <= 32768 + 33       # the handler saw the level just past mid-scale
    r.vm.world.set_input(0, 0, 0)                       # now the digital side drives the line
    assert (r.cmd(15, 0, 0), r.cmd(15, 0, 1)) == (0, 0)
    r.vm.world.set_input(0, 0, 1)
    assert r.cmd(15, 0, 1) == 65535
    r = rig("TMCM-1180", {"input": [{"bank": 1, "port": 1, "value": 511}]})
    assert r.cmd(15, 1, 0) == 0
    r.vm.world.set_input(1, 1, 512)
    assert r.cmd(15, 1, 0) == 1
    with pytest.raises(ValueError, match="one line"):
        rig("TMCM-6212", {"input": [{"bank": 0, "port": 3, "value": 1}, {"bank": 1, "port": 3, "value": 0}]})


def test_input_change_interrupt_on_the_selected_transition(rig):
    """TMCM-6212 manual 5 bank 3 parameters 39-42 select the input-change transition (1 low-high,
    2 high-low, 3 both); interrupt 39 + port runs its handler when the scenario's input changes."""
    sc = {"input": [{"bank": 0, "port": 0, "steps": [[0.2, 1], [0.4, 0], [0.6, 1]]}]}
    for mode, count in ((1, 2), (2, 1), (3, 3)):
        r = rig("TMCM-6212", sc)
        w = Wire(r.vm)
        w.load(f"SGP 39, 3, {mode}\nVECT 39, Changed\nEI 39\nEI 255\nLoop: JA Loop\n"
               "Changed: GGP 0, 2\nCALC ADD, 1\nAGP 0, 2\nRETI")
        w.run()
        r.vm.advance(1)
        assert r.cmd(10, 0, 2) == count, mode


def test_stop_switch_interrupt_from_the_stage(rig):
    """TMCM-6212 manual 5.4 interrupt 28 "Right stop switch 0" on the transition selected by
    bank-3 parameter 28: the slider reaches the right limit switch."""
    r = rig("TMCM-6212", {"axis": {"0": {"right": {"position": 8000}}}})
    w = Wire(r.vm)
    w.load("SGP 28, 3, 1\nVECT 28, Right\nEI 28\nEI 255\nROR 0, 20000\nLoop: JA Loop\n"
           "Right: GAP 1, 0\nAGP 0, 2\nRETI")
    w.run()
    r.vm.advance(1)
    assert r.cmd(10, 0, 2) == 8000


def test_driver_flags_ap208(rig):
    """PD86-1180 manual 5 AP208 TMC262 flags: bit 7 stand still, bit 0 stallGuard2 threshold
    reached, bits 1-6 (overtemperature, shorts, open load) from the scenario's driver_flags."""
    r = rig("TMCM-1180", {"axis": {"0": {"driver_flags": {"steps": [[1.0, 4]]}}}})
    assert r.gap(208) == 0x80
    r.vm.advance(1.5)
    assert r.gap(208) == 0x84
    r.cmd(1, 0, 0, 300)
    r.vm.advance(1)
    assert r.gap(208) == 0x04


def test_extended_error_flags_cleared_by_a_motion_command(rig):
    """TMCM-6212 manual 4.1 AP207: "These error flags are cleared automatically when this
    parameter has been read out or when a motion command has been executed"."""
    r = rig("TMCM-6212", {"axis": {"0": {"load": {"steps": [[1000, 0.9]]}}}})
    r.sap(181, 100)
    r.cmd(1, 0, 0, 5000)
    r.vm.advance(1)
    assert r.gap(1) == 1000
    r.cmd(2, 0, 0, 5000)             # ROL: a motion command
    assert r.gap(207) == 0


def test_jc_error_conditions_follow_the_world(rig):
    """TMCM-6212 manual 3.6.16 JC conditions EDV (deviation) and EPO (position error, set by a
    stall here - docs/assumptions.md); CLE clears them (3.6.29)."""
    r = rig("TMCM-6212", {"axis": {"0": {"load": {"steps": [[1000, 0.9]]}}}})
    w = Wire(r.vm)
    w.load("SAP 212, 0, 500\nROR 0, 5000\nWAIT TICKS, 0, 100\nJC EDV, Dev\nSTOP\n"
           "Dev: CALC LOAD, 5\nAGP 0, 2\nCLE EDV\nJC EDV, Bad\nSTOP\nBad: CALC LOAD, 9\nAGP 0, 2\nSTOP")
    w.run()
    r.vm.advance(2)
    assert r.cmd(10, 0, 2) == 5
    assert not r.vm.flags & flags.EDV


def test_1180_shutdown_pin(rig):
    """PD86-1180 manual 6 GP80 "Shutdown pin functionality: 0 no function, 1 high active, 2 low
    active": the active pin stops the motor and sets ESD (JC condition 12)."""
    sc = {"shutdown": {"steps": [[0.5, 1]]}}
    r = rig("TMCM-1180", sc)
    r.cmd(1, 0, 0, 300)
    r.vm.advance(1)
    assert r.gap(3) != 0              # GP80 = 0: no function
    r = rig("TMCM-1180", sc)
    r.cmd(9, 80, 0, 1)
    r.cmd(1, 0, 0, 300)
    r.vm.advance(1)
    assert r.gap(3) == 0
    assert r.vm.flags & flags.ESD


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


def test_power_up_names_bank_and_port_of_a_missing_input():
    """TMCM-6212 manual 3.6.13 GIO: bank 1 holds the analog inputs AIN0..AIN3 (ports 0..3);
    docs/scenarios.md `[[input]]` `bank`, `port` "the GIO address". Port 3 (the last) is driven,
    port 4 (the first beyond) is refused with a ScenarioError naming bank and port."""
    vm = VirtualModule("TMCM-6212", scenario={"input": [{"bank": 1, "port": 3, "value": 1000}]})
    assert vm.request(15, 3, 1).value == 1000
    with pytest.raises(ScenarioError, match=r"^input bank 1 port 4: TMCM-6212 has no such port$"):
        VirtualModule("TMCM-6212", scenario={"input": [{"bank": 1, "port": 4, "value": 1000}]})
