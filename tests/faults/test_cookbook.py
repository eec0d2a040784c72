"""The cookbook runs (issue 34, "A cookbook in docs/, one runnable example per fault ... The
examples run in CI"): every script of examples/faults/ ends with status 0, every fault kind has its
script, and the cookbook's own pytest file passes under the plugin."""
from __future__ import annotations

import runpy
import sys
from pathlib import Path

import pytest

from opentmcl.faults import KINDS

EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "faults"
SCRIPTS = sorted(p for p in EXAMPLES.glob("*.py") if p.stem in KINDS)

pytest_plugins = ["pytester"]


def test_every_fault_kind_has_an_example():
    assert sorted(p.stem for p in SCRIPTS) == sorted(KINDS)
    documented = (EXAMPLES.parents[1] / "docs" / "faults.md").read_text(encoding="utf-8")
    assert all(f"examples/faults/{p.name}" in documented for p in SCRIPTS)


@pytest.mark.parametrize("script", SCRIPTS, ids=lambda p: p.stem)
def test_the_example_runs(script, monkeypatch, capsys):
    monkeypatch.syspath_prepend(str(EXAMPLES))
    monkeypatch.delitem(sys.modules, "careful", raising=False)
    with pytest.raises(SystemExit) as end:
        runpy.run_path(str(script), run_name="__main__")
    assert end.value.code == 0
    assert capsys.readouterr().out.strip()


def test_the_cookbook_tests_pass_under_the_plugin(pytester, monkeypatch):
    """examples/faults/test_cookbook_host.py, with a fixed first seed (CI repeats the same runs)."""
    monkeypatch.setenv("PYTEST_DISABLE_PLUGIN_AUTOLOAD", "1")
    for name in ("test_cookbook_host.py", "careful.py"):
        pytester.makepyfile(**{name[:-3]: (EXAMPLES / name).read_text(encoding="utf-8")})
    pytester.syspathinsert()
    result = pytester.runpytest("-p", "opentmcl.pytest_plugin", "-p", "no:cacheprovider", "--tmcl-fault-seed", "34")
    result.assert_outcomes(passed=11)
