"""The `tmcl_replay` fixture of the pytest plugin: a user's capture as a regression test (issue 13 item 3)."""
from pathlib import Path

import pytest

pytest_plugins = ["pytester"]

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "captures" / "bus_ascii_two_modules.jsonl"


@pytest.fixture
def run(pytester, monkeypatch):
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")

    def run_inner(source: str):
        pytester.makepyfile(test_inner=source.replace("CAPTURE", repr(str(EXAMPLE))))
        return pytester.runpytest("-p", "opentmcl.pytest_plugin", "-p", "no:cacheprovider")

    return run_inner


def test_agreeing_capture_passes_and_a_changed_module_fails_with_the_parameter(run, tmp_path):
    changed = tmp_path / "changed.toml"
    changed.write_text('extends = "PD28-1021"\n[module]\nname = "C"\n[[axis_parameter]]\nnumber = 4\ndefault = 1\n')
    result = run(f'''
def test_same(tmcl_replay):
    assert tmcl_replay(CAPTURE, "PD28-1021", address=2).compared == 5

def test_changed(tmcl_replay):
    tmcl_replay(CAPTURE, {str(changed)!r}, address=2)

def test_bad_file(tmcl_replay, tmp_path):
    (tmp_path / "x.jsonl").write_text("{{}}\\n")
    tmcl_replay(tmp_path / "x.jsonl", "PD28-1021")
''')
    result.assert_outcomes(passed=1, failed=2)
    text = result.stdout.str()
    assert "GAP 4, 0 [max_positioning_speed]: value: captured 51200, virtual 1" in text
    assert "tmcl_replay:" in text and "not an opentmcl-capture file" in text


PROFILE = 'extends = "PD86-1180"\n[module]\nname = "MY-1180"\nfirmware_version = "1180V999"\n'
"""A derived profile (docs/profiles.md); PD86-1180 manual 4.6.39: 136 type 0 answers the string."""


def test_marker_and_ini_take_a_profile_file_relative_to_the_ini(pytester, monkeypatch):
    """Issue 13 "Done when": `extends` works in every place a module name is accepted - the
    `tmcl_module` marker and the ini option too (docs/pytest-plugin.md). A relative file in the ini
    is taken from the ini file's folder, as pytest's own paths are, so the suite runs from any
    directory; a missing file fails in one line. (Old code: relative to the current directory, and
    the message printed twice.)"""
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    suite = pytester.mkdir("suite")
    (suite / "my.toml").write_text(PROFILE)
    (suite / "pytest.ini").write_text("[pytest]\ntmcl_module = my.toml\n")
    (suite / "test_inner.py").write_text(f'''
import pytest

def test_ini(tmcl_module):
    assert tmcl_module.firmware_version() == "1180V999"

@pytest.mark.tmcl_module({str(suite / "my.toml")!r}, address=3)
def test_marker(tmcl_module):
    assert tmcl_module.firmware_version() == "1180V999"
''')
    args = ["-p", "opentmcl.pytest_plugin", "-p", "no:cacheprovider", "-c", str(suite / "pytest.ini"), str(suite)]
    pytester.runpytest(*args).assert_outcomes(passed=2)  # run from pytester's folder, not suite/
    (suite / "pytest.ini").write_text("[pytest]\ntmcl_module = nope.toml\n")
    result = pytester.runpytest(*args)
    result.assert_outcomes(passed=1, errors=1)
    lines = [line for line in result.stdout.lines if "nope.toml" in line and "cannot read" in line]
    assert lines[0].startswith(f"tmcl_module: {suite / 'nope.toml'}: cannot read")
    assert not any("During handling" in line for line in result.stdout.lines)
