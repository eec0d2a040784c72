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
