"""The pytest plugin (opentmcl.pytest_plugin): `tmcl_module` fixture, marker, option, virtual time.

Inner runs load the plugin with ``-p opentmcl.pytest_plugin`` and plugin autoloading off, so the
tests do not depend on the ``pytest11`` entry point being installed (nor clash with it when it is).
"""
import os
from pathlib import Path

import pytest

pytest_plugins = ["pytester"]

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "test_with_tmcl_module.py"


@pytest.fixture
def run(pytester, monkeypatch):
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")

    def run_inner(source: str, *args: str):
        pytester.makepyfile(test_inner=source)
        return pytester.runpytest("-p", "opentmcl.pytest_plugin", "-p", "no:cacheprovider", *args)

    return run_inner


def test_default_module_and_host_api(run):
    """Without marker or option: a TMCM-6212 (6 axes) at address 1; the fixture is a host Module,
    GGP 66 (TMCM-6212 manual 3.6.8 example) answers the serial address 1."""
    result = run('''
from opentmcl.host.module import Module

def test_it(tmcl_module):
    assert isinstance(tmcl_module, Module)
    assert tmcl_module.name == "TMCM-6212" and len(tmcl_module.axes) == 6
    assert tmcl_module.request(10, 66, 0).value == 1
    assert tmcl_module.vm.address == 1
''')
    result.assert_outcomes(passed=1)


def test_marker_chooses_module_and_address(run):
    """@pytest.mark.tmcl_module("PD86-1180", address=3): PD86-1180 manual GP66 = 3."""
    result = run('''
import pytest

@pytest.mark.tmcl_module("PD86-1180", address=3)
def test_it(tmcl_module):
    assert tmcl_module.name == "PD86-1180"
    assert tmcl_module.address == 3 and tmcl_module.get_global(66) == 3
''')
    result.assert_outcomes(passed=1)


def test_option_sets_the_default_and_the_marker_wins(run):
    """--tmcl-module NAME applies to unmarked tests; a marker on the test overrides it."""
    result = run('''
import pytest

def test_unmarked(tmcl_module):
    assert tmcl_module.name == "PD28-1021"

@pytest.mark.tmcl_module("TMCM-6212")
def test_marked(tmcl_module):
    assert tmcl_module.name == "TMCM-6212"
''', "--tmcl-module", "PD28-1021")
    result.assert_outcomes(passed=2)


def test_advance_controls_virtual_time(run):
    """TMCM-6212 manual 3.6.1 ROR: the motor turns at the given velocity (pps); after advance(2.0)
    the virtual clock moved by exactly 2 s and the axis turns at 10000 pps; 3.6.3 MST stops it.
    A move with wait=True lets virtual time pass until position reached (3.6.4 MVP)."""
    result = run('''
import pytest

def test_it(tmcl_module):
    axis = tmcl_module[0]
    axis.rotate(10000)
    start = tmcl_module.time
    tmcl_module.advance(2.0)
    assert tmcl_module.time == pytest.approx(start + 2.0)
    assert axis.actual_speed == 10000
    assert tmcl_module.vm.axes[0].engine.position == axis.position > 0
    axis.stop()
    tmcl_module.advance(1.0)
    assert axis.actual_speed == 0
    axis.move_to(-3000, wait=True)
    assert axis.position == -3000
    with pytest.raises(ValueError):
        tmcl_module.advance(-1)
''')
    result.assert_outcomes(passed=1)


def test_each_test_gets_a_fresh_module(run):
    """State set in one test (SAP 1: actual position) does not leak into the next."""
    result = run('''
def test_a(tmcl_module):
    tmcl_module[0].position = 1234
    assert tmcl_module[0].position == 1234

def test_b(tmcl_module):
    assert tmcl_module[0].position == 0
''', "-p", "no:randomly")
    result.assert_outcomes(passed=2)


def test_eeprom_option_keeps_stored_values(run, tmp_path):
    """The marker's eeprom= file keeps stored parameters between tests (manual 3.6.9 STGP)."""
    path = tmp_path / "ee.json"
    result = run(f'''
import pytest

@pytest.mark.tmcl_module("TMCM-6212", eeprom={str(path)!r})
def test_store(tmcl_module):
    tmcl_module.set_global(77, 1)     # GP77 auto start mode
    tmcl_module.store_global(77)

@pytest.mark.tmcl_module("TMCM-6212", eeprom={str(path)!r})
def test_restored(tmcl_module):
    assert tmcl_module.get_global(77) == 1
''', "-p", "no:randomly")
    result.assert_outcomes(passed=2)


def test_bad_marker_or_name_fails_clearly(run):
    """An unknown module, option, address or time-out is a test failure with a message, not a traceback."""
    result = run('''
import pytest

@pytest.mark.tmcl_module("TMCM-9999")
def test_unknown(tmcl_module):
    pass

@pytest.mark.tmcl_module("TMCM-6212", speed=3)
def test_bad_option(tmcl_module):
    pass

@pytest.mark.tmcl_module("TMCM-6212", address=0)
def test_bad_address(tmcl_module):
    pass

@pytest.mark.tmcl_module("TMCM-6212", timeout=-1)
def test_bad_timeout(tmcl_module):
    pass
''')
    result.assert_outcomes(errors=4)
    result.stdout.fnmatch_lines(["*unknown module 'TMCM-9999'*", "*unknown option(s) speed*",
                                 "*module address must be 1..255*", "*timeout must be a positive, finite number*"])
    assert "Traceback" not in result.stdout.str()


def test_marker_and_option_are_documented(run):
    """`pytest --markers` and `pytest --help` list them."""
    markers = run("def test_nothing():\n    pass\n", "--markers")
    markers.stdout.fnmatch_lines(["*tmcl_module(name*"])
    helptext = run("def test_nothing():\n    pass\n", "--help")
    helptext.stdout.fnmatch_lines(["*--tmcl-module*"])


def test_documented_example_passes(pytester, monkeypatch):
    """examples/test_with_tmcl_module.py (docs/pytest-plugin.md) runs green."""
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    pytester.makepyfile(test_example=EXAMPLE.read_text())
    result = pytester.runpytest("-p", "opentmcl.pytest_plugin", "-p", "no:cacheprovider")
    result.assert_outcomes(passed=4)


ENTRY_POINT_NAME = "opentmcl.pytest_plugin"
"""The name proposed for `[project.entry-points.pytest11]`: the module's own name, so that pytest
finds the plugin already registered when a project also names it in `-p` or `pytest_plugins`."""


@pytest.mark.parametrize("extra", [[], ["-p", "opentmcl.pytest_plugin"], ["conftest"]])
def test_entry_point_loads_the_plugin_without_clashes(pytester, monkeypatch, extra):
    """With the pytest11 entry point installed (simulated by a dist-info directory on the path),
    the fixture is there without -p; naming the plugin again (-p, pytest_plugins) is harmless."""
    site = pytester.mkdir("site")
    info = site / "opentmcl_entry_point_probe-0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: opentmcl-entry-point-probe\nVersion: 0\n")
    (info / "entry_points.txt").write_text(f"[pytest11]\n{ENTRY_POINT_NAME} = opentmcl.pytest_plugin\n")
    pytester.makepyfile(test_inner="def test_it(tmcl_module):\n    assert tmcl_module.name == 'TMCM-6212'\n")
    args = [a for a in extra if a != "conftest"]
    if "conftest" in extra:
        pytester.makeconftest('pytest_plugins = ["opentmcl.pytest_plugin"]\n')
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join([str(site), os.environ.get("PYTHONPATH", "")]))
    monkeypatch.delenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", raising=False)
    result = pytester.runpytest_subprocess("-p", "no:cacheprovider", *args)
    result.assert_outcomes(passed=1)
