"""Cookbook: how to write the test (docs/faults.md "Testing host code"). Each test runs once per
fault and seed of its `tmcl_faults` marker, on a fresh virtual module whose link or firmware fails
as described; a failure report names the faults, what fired and the seed to repeat it with.

    pytest examples/faults/test_cookbook_host.py -p opentmcl.pytest_plugin
"""
import pytest
from careful import retry, set_parameter

from opentmcl.host import TmclStatusError

SGP, GGP, USER, MARK = 9, 10, 2, 200
CONFIG = {4: 1500, 5: 800}   # PD86-1180: maximum speed and acceleration (RAM only)

NOISY_LINE = [
    {"kind": "corrupt_request", "probability": 0.2},      # status 1 "wrong checksum"
    {"kind": "drop_reply", "probability": 0.1},
    [{"kind": "corrupt_reply", "probability": 0.1}, {"kind": "delay", "probability": 0.1, "delay": 0.5}],
]


def configure(m) -> None:
    """The host's set-up: a speed per axis, each read back."""
    for axis in range(len(m.axes)):
        set_parameter(m, 4, axis, 20000 + axis)


@pytest.mark.tmcl_module("TMCM-6212", timeout=0.3)
@pytest.mark.tmcl_faults(NOISY_LINE, seeds=3)
def test_configure_on_a_noisy_line(tmcl_module):
    configure(tmcl_module)
    assert [tmcl_module.vm.axes[a].get(4) for a in range(6)] == [20000 + a for a in range(6)]


class Application:
    """A host that notices a reset (a user variable above the stored range powers up as 0) and sets
    the module up again before it moves."""

    def __init__(self, m) -> None:
        self.m = m

    def set_up(self) -> None:
        for number, value in CONFIG.items():
            set_parameter(self.m, number, 0, value)
        retry(lambda: self.m.request(SGP, MARK, USER, 1))

    def move_to(self, target: int) -> None:
        if retry(lambda: self.m.request(GGP, MARK, USER).value) == 0:
            self.set_up()
        retry(lambda: self.m.request(4, 0, 0, target))


@pytest.mark.tmcl_module("PD86-1180", timeout=0.3)
@pytest.mark.tmcl_faults([{"name": "cut", "kind": "power_loss", "duration": 0.2}])
def test_set_up_again_after_a_power_loss(tmcl_module):
    app = Application(tmcl_module)
    app.set_up()
    tmcl_module.faults.trigger("cut")
    tmcl_module.advance(0.3)
    app.move_to(1000)
    assert {n: tmcl_module.vm.axes[0].get(n) for n in CONFIG} == CONFIG


def test_a_status_error_other_than_1_is_not_retried(tmcl_module):
    """retry() repeats status 1 only: an invalid value (status 4) is the host's own error."""
    with pytest.raises(TmclStatusError):
        retry(lambda: tmcl_module.request(5, 4, 0, -1))
