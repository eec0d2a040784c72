"""Example: testing your own motion code against a virtual module with the `tmcl_module` fixture.

Run with ``pytest examples/test_with_tmcl_module.py`` (opentmcl installed: the plugin loads by itself;
otherwise add ``-p opentmcl.pytest_plugin``). See docs/pytest-plugin.md.
"""
import pytest


def go_home_and_measure(module, distance: int) -> int:
    """"Your" application code: move out by `distance` and back, return the position reached."""
    axis = module[0]
    axis.move_by(distance, wait=True)
    axis.move_to(0, wait=True)
    return axis.position


def test_default_module_is_a_tmcm_6212(tmcl_module):
    """Without a marker (or --tmcl-module) the fixture is a TMCM-6212 at address 1 with 6 axes."""
    assert tmcl_module.name == "TMCM-6212"
    assert len(tmcl_module.axes) == 6
    assert tmcl_module.get_global(66) == 1          # serial address (GP66)


@pytest.mark.tmcl_module("PD86-1180", address=3)
def test_round_trip_on_a_pd86_1180(tmcl_module):
    """Waiting for "position reached" lets virtual time pass: the test takes milliseconds."""
    assert go_home_and_measure(tmcl_module, 20000) == 0
    assert tmcl_module.time > 0.1                    # virtual seconds went by
    assert tmcl_module.vm.address == 3


def test_rotation_under_virtual_time(tmcl_module):
    """ROR, then let exactly two virtual seconds pass and look at the module's state."""
    axis = tmcl_module[0]
    axis.rotate(10000)                               # ROR 0, 10000 (pps on the TMCM-6212)
    start = tmcl_module.time
    tmcl_module.advance(2.0)
    assert tmcl_module.time == pytest.approx(start + 2.0)
    assert axis.actual_speed == 10000
    assert axis.position > 10000
    axis.stop()                                      # MST
    tmcl_module.advance(1.0)
    assert axis.actual_speed == 0


@pytest.mark.tmcl_module("PD28-1021")
def test_the_virtual_module_itself_is_at_hand(tmcl_module):
    """`.vm` is the VirtualModule: look inside it where a real bench would need a probe."""
    assert tmcl_module.vm.profile.axes == 1
    assert tmcl_module.get_global(76) == 2           # host address (GP76)
