"""pytest support (issue 34, "a marker or fixture that runs one host test under a list of faults,
with every seed printed on failure so the run can be repeated"; "Done when": "A host test written
with the new fixture catches a host that ignores status 1. It also catches a host that assumes RAM
parameters survive a power loss.")"""
from __future__ import annotations

import re

import pytest

pytest_plugins = ["pytester"]

TEST = '''
import pytest
from opentmcl.host import TmclStatusError

SAP, GAP, SGP, GGP = 5, 6, 9, 10

{host}

@pytest.mark.tmcl_faults([{{"kind": "corrupt_request", "probability": 0.3, "byte": 7}}], seeds=4)
def test_speed_is_set(tmcl_module):
    set_speed(tmcl_module, 12345)
    assert tmcl_module.vm.axes[0].get(4) == 12345

@pytest.mark.tmcl_faults([{{"name": "cut", "kind": "power_loss", "duration": 0.1}}])
def test_speed_survives_a_power_loss(tmcl_module):
    set_speed(tmcl_module, 12345)
    tmcl_module.faults.trigger("cut")
    tmcl_module.advance(0.2)
    before_a_move(tmcl_module)
    assert tmcl_module.vm.axes[0].get(4) == 12345
'''

CAREFUL = '''
def set_speed(m, value):
    m.speed = value
    for _ in range(10):
        try:
            m.request(SAP, 4, 0, value)
            return
        except TmclStatusError as exc:
            if exc.status != 1:
                raise

def before_a_move(m):
    if m.request(GAP, 4, 0).value != m.speed:   # RAM lost: set it up again
        set_speed(m, m.speed)
'''

CARELESS = '''
def set_speed(m, value):
    try:
        m.request(SAP, 4, 0, value)
    except TmclStatusError:
        pass                                    # ignores status 1 "wrong checksum"

def before_a_move(m):
    pass                                        # assumes RAM parameters survive a power loss
'''


@pytest.fixture
def run(pytester, monkeypatch):
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")

    def run_inner(host: str, *args: str):
        pytester.makepyfile(test_inner=TEST.format(host=host))
        return pytester.runpytest("-p", "opentmcl.pytest_plugin", "-p", "no:cacheprovider", *args)

    return run_inner


def test_a_careful_host_passes_under_every_fault_and_seed(run):
    result = run(CAREFUL)
    result.assert_outcomes(passed=5)
    assert "test_speed_is_set[corrupt_request-s3]" in "\n".join(run(CAREFUL, "--collect-only", "-q").outlines)


def _section(text: str, test_id: str) -> str:
    """The "opentmcl faults" section of the failure report of `test_id`."""
    report = text.split(f" {test_id} _", 1)[1]
    report = re.split(r"\n_{3,} |\n=+ short test summary", report, maxsplit=1)[0]
    return report.split("opentmcl faults", 1)[1]


def test_a_careless_host_is_caught_and_the_seed_printed(run):
    """The host that ignores status 1 fails for some seed; the one that assumes RAM survives fails;
    each failure says the faults, what fired and the seed, and the printed command repeats it
    exactly (the same faults fire at the same requests)."""
    result = run(CARELESS, "--tmcl-fault-seed", "100")
    assert result.parseoutcomes()["failed"] >= 2
    text = result.stdout.str()
    assert "FAILED test_inner.py::test_speed_survives_a_power_loss[cut]" in text
    assert "faults: cut; seed 100" in text and "power lost for 0.1 s (triggered by name)" in text
    assert "repeat: pytest 'test_inner.py::test_speed_survives_a_power_loss[cut]' --tmcl-fault-seed 100" in text
    first = re.search(r"FAILED test_inner.py::(test_speed_is_set\[corrupt_request-s\d\])", text).group(1)
    section = _section(text, first)
    assert "corrupt_request: request SAP 4, 0, 12345: byte 7" in section
    assert re.search(rf"repeat: pytest 'test_inner.py::{re.escape(first)}' --tmcl-fault-seed 100", section)
    again = run(CARELESS, f"test_inner.py::{first}", "--tmcl-fault-seed", "100")
    again.assert_outcomes(failed=1)
    assert _section(again.stdout.str(), first) == section


def test_bad_fault_in_the_marker_is_one_line(run):
    result = run(CAREFUL + "\n@pytest.mark.tmcl_faults([{'kind': 'melt'}])\ndef test_bad(tmcl_module):\n    pass\n")
    assert "unknown fault kind 'melt'" in result.stdout.str()
    assert result.ret != 0
