"""Packaging (issue 15 item 8; docs/host.md "Installing", docs/pytest-plugin.md "Enabling it").

The issue: "a host-only user must install matplotlib, starlette, uvicorn and websockets; the pytest
plugin loads into every pytest run of the environment; `connect` reachable only through a module
`__getattr__` (IDEs and type checkers miss it); the version is written twice".
"""
from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import tomllib
import venv
from importlib import metadata
from pathlib import Path

import pytest

from opentmcl import extras

ROOT = Path(__file__).resolve().parents[1]
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
PROJECT = PYPROJECT["project"]
HEAVY = ("starlette", "uvicorn", "websockets", "matplotlib")
"""The web and plot stacks: a host-only install has none of them."""


def _requirement_name(spec: str) -> str:
    return re.split(r"[\s\[<>=!~;]", spec, maxsplit=1)[0].lower()


def _child(code: str, *args: str, cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True, timeout=120,
                          cwd=cwd)


# --- extras ------------------------------------------------------------------------------------

def test_the_base_install_has_neither_web_nor_plot_stack():
    """`dependencies` is what send/connect/sim:// and the servers import; the web and plot stacks are
    the `web` and `plot` extras (the names opentmcl/extras.py checks), `all` is both and `test` has all."""
    base = {_requirement_name(d) for d in PROJECT["dependencies"]}
    optional = {name: {_requirement_name(d) for d in deps} for name, deps in PROJECT["optional-dependencies"].items()}
    assert base.isdisjoint(HEAVY)
    assert {"pyserial", "python-can", "pyyaml"} <= base     # serial://, can:// and serve --can, YAML scenarios
    for extra, modules in extras.EXTRAS.items():
        assert optional[extra] == set(modules), extra
    assert PROJECT["optional-dependencies"]["all"] == ["opentmcl[web,plot]"]
    assert "opentmcl[all]" in PROJECT["optional-dependencies"]["test"]


def test_the_readme_installs_the_whole_tool_first_and_ci_runs_its_test_command():
    """The README's first command gives the whole tool (`[all]`); its second, the test command, is
    `.ci/run`'s, character for character."""
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    quick = readme.split("## Quick start", 1)[1].split("```sh", 1)[1].split("```", 1)[0]
    commands = [line for line in quick.splitlines() if line.strip() and not line.lstrip().startswith("#")]
    assert "pip install -q -e '.[all]'" in commands[0] and commands[0].endswith("opentmcl demo")
    ci = [line for line in (ROOT / ".ci/run").read_text(encoding="utf-8").splitlines()
          if line.startswith("python3 -m venv")]
    assert ci == [commands[1]]
    assert "'.[test]'" in commands[1]


@pytest.mark.parametrize(("argv", "extra"), [
    (["dashboard", "--to", "sim://TMCM-6212", "--web", "127.0.0.1:0"], "web"),
    (["serve", "--module", "TMCM-6212", "--web", "127.0.0.1:0"], "web"),
    (["plot", "missing.tmc", "-o", "out.png"], "plot"),
])
def test_a_command_whose_extra_is_missing_says_which_to_install(tmp_path, argv, extra):
    """With the extra's packages absent (made unimportable in a real CLI process), the command exits 2
    with one line naming the extra and the pip command, before it starts anything."""
    blocked = ", ".join(repr(m) for m in extras.EXTRAS[extra])
    code = (f"import sys; sys.modules.update(dict.fromkeys([{blocked}]))\n"
            "from opentmcl.cli import main; sys.exit(main(sys.argv[1:]))\n")
    out = _child(code, *argv, cwd=tmp_path)
    assert out.returncode == 2, out.stderr
    lines = out.stderr.splitlines()
    assert len(lines) == 1, out.stderr
    assert f"needs the '{extra}' extra" in lines[0] and f"pip install 'opentmcl[{extra}]'" in lines[0]
    assert list(tmp_path.iterdir()) == []     # no output file, no recording


def test_extras_missing_finds_an_absent_package_and_passes_a_present_one():
    assert extras.missing("web") is None                # the test environment has every extra
    code = ("import sys; sys.modules['uvicorn'] = None\n"
            "from opentmcl import extras; print(extras.missing('web'))\n"
            "try:\n    extras.require('web', 'the dashboard')\n"
            "except ImportError as exc:\n    print(type(exc).__name__, exc.name, exc.extra)\n")
    assert _child(code).stdout.split() == ["uvicorn", "MissingExtra", "uvicorn", "web"]


def test_the_host_and_send_paths_import_no_web_or_plot_stack():
    """What a host-only user runs -- `opentmcl.connect("sim://...")` with names, and `opentmcl send` --
    imports none of starlette, uvicorn, websockets, matplotlib (so the base install suffices)."""
    code = ("import sys, opentmcl\n"
            "m = opentmcl.connect('sim://TMCM-6212'); m.axes[0].set('MaxVelocity', 1000)\n"
            "print(m.axes[0].get(4))\n"
            "from opentmcl.cli import main\n"
            "assert main(['send', 'GAP 1, 0', '--plain', '--to', 'sim://PD86-1180']) == 0\n"
            f"print(sorted(n for n in sys.modules if n.split('.')[0] in {HEAVY!r}))\n")
    out = _child(code)
    assert out.stdout.split() == ["1000", "0", "[]"], out.stderr


# --- version, public names ---------------------------------------------------------------------------

def test_the_version_has_one_source():
    """pyproject.toml's version is the only one: `opentmcl.__version__` and `--version` read it back."""
    import opentmcl

    assert opentmcl.__version__ == metadata.version("opentmcl") == PROJECT["version"]
    literal = re.compile(rf"[\"']{re.escape(PROJECT['version'])}[\"']")
    assert [p for p in (ROOT / "src").rglob("*.py") if literal.search(p.read_text(encoding="utf-8"))] == []
    out = subprocess.run([sys.executable, "-m", "opentmcl", "--version"], capture_output=True, text=True, timeout=60)
    assert out.stdout.strip() == f"opentmcl {PROJECT['version']}"


def test_connect_is_imported_with_the_package_and_the_rest_on_first_use():
    """`connect` and the host types are bound by ``import opentmcl`` itself (not a module __getattr__);
    `VirtualModule` and `replay` stay lazy so that the package loads no firmware."""
    code = ("import sys, opentmcl\n"
            "print(sorted(set(opentmcl.__all__) - set(vars(opentmcl))))\n"
            "print(any(n.startswith(('opentmcl.firmware', 'opentmcl.capture')) for n in sys.modules))\n"
            "print(opentmcl.VirtualModule.__name__, opentmcl.replay.__name__, sorted(set(opentmcl.__all__) - set(dir(opentmcl))))\n")
    assert _child(code).stdout.split() == ["['VirtualModule',", "'__version__',", "'replay']", "False",
                                           "VirtualModule", "replay", "[]"]


def test_type_checkers_see_every_public_name(tmp_path):
    """mypy, on a user's code outside the repository, knows the type of every name of ``__all__``:
    a wrong argument to `opentmcl.connect` is an arg-type error, the rest type-checks."""
    (tmp_path / "user.py").write_text(
        "import opentmcl\n"
        "m: opentmcl.Module = opentmcl.connect('sim://TMCM-6212')\n"
        "a: opentmcl.Axis = m.axes[0]\n"
        "vm: opentmcl.VirtualModule = opentmcl.VirtualModule('TMCM-6212', address=1)\n"
        "ok: bool = opentmcl.replay('run.jsonl').ok\n"
        "v: str = opentmcl.__version__\n"
        "errors: tuple[type[Exception], ...] = (opentmcl.TmclError, opentmcl.TmclStatusError, opentmcl.TmclTimeout,\n"
        "    opentmcl.TmclConnectionError, opentmcl.UnknownParameterError)\n"
        "opentmcl.connect(5)\n")
    out = subprocess.run([sys.executable, "-m", "mypy", "--no-incremental", "--strict", "user.py"],
                         cwd=tmp_path, capture_output=True, text=True, timeout=300)
    errors = [line for line in out.stdout.splitlines() if ": error:" in line]
    assert len(errors) == 1 and 'Argument 1 to "connect" has incompatible type "int"' in errors[0], out.stdout


def test_pyproject_declares_licence_and_classifiers_and_no_project_urls():
    """An SPDX licence expression (PEP 639, setuptools >= 77 builds it), trove classifiers incl.
    `Typing :: Typed` (the package ships py.typed); no project URLs while the project has no public
    address (issue 32 item 2: "give none rather than fake ones"; tests/test_sdist.py checks the
    built metadata)."""
    assert PROJECT["license"] == "MIT"
    assert PYPROJECT["build-system"]["requires"] == ["setuptools>=77"]
    assert {"Typing :: Typed", "Framework :: Pytest", "Programming Language :: Python :: 3 :: Only"} <= set(PROJECT["classifiers"])
    assert not [c for c in PROJECT["classifiers"] if c.startswith("License ::")]  # PEP 639: the expression only
    assert "urls" not in PROJECT
    assert (ROOT / "src/opentmcl/py.typed").is_file()


# --- the pytest plugin ---------------------------------------------------------------------------------

def test_the_pytest_plugin_is_inert_in_a_suite_that_does_not_use_it(tmp_path):
    """docs/pytest-plugin.md: loaded into every pytest run of the environment, the plugin imports
    only the host library -- no firmware, endpoints, tools or third-party packages -- starts no
    thread and writes no file until a test asks for `tmcl_module`."""
    (tmp_path / "test_other.py").write_text(
        "import sys, threading\n"
        "def test_unrelated(request):\n"
        "    assert request.config.pluginmanager.has_plugin('opentmcl.pytest_plugin')\n"
        "    ours = sorted({n.split('.')[1] for n in sys.modules if n.startswith('opentmcl.')})\n"
        "    theirs = sorted(n for n in ('serial', 'can', 'yaml', 'matplotlib', 'starlette', 'uvicorn',\n"
        "                                'websockets', 'numpy') if n in sys.modules)\n"
        "    print('LOADED', ours, theirs, threading.active_count())\n")
    env = {**os.environ, "PYTHONDONTWRITEBYTECODE": "1"}
    out = subprocess.run([sys.executable, "-m", "pytest", "-p", "opentmcl.pytest_plugin", "-p", "no:cacheprovider",
                          "-q", "-s", "test_other.py"], cwd=tmp_path, capture_output=True, text=True, timeout=120,
                         env=env)
    assert out.returncode == 0, out.stdout + out.stderr
    (line,) = [x for x in out.stdout.splitlines() if x.startswith("LOADED")]
    assert line == "LOADED ['host', 'limits', 'modules', 'motion', 'protocol', 'pytest_plugin', 'registry'] [] 1"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["test_other.py"]


# --- a fresh install without extras ----------------------------------------------------------------------

@pytest.mark.slow
def test_a_fresh_install_without_extras_sends_and_connects(tmp_path):
    """`pip install -e .` in a new virtual environment (packages from pip's configured indexes and
    cache): `opentmcl send` and `connect` work, the web and plot stacks are absent, and the
    dashboard names the extra to install."""
    src = tmp_path / "src-tree"
    shutil.copytree(ROOT / "src", src / "src", ignore=shutil.ignore_patterns("__pycache__", "*.egg-info"))
    for name in ("pyproject.toml", "README.md"):
        shutil.copy(ROOT / name, src / name)
    env_dir = tmp_path / "venv"
    venv.create(env_dir, with_pip=True)
    bin_dir = env_dir / "bin"
    clean = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    install = subprocess.run([str(bin_dir / "pip"), "install", "-q", "-e", str(src)], capture_output=True,
                             text=True, timeout=900, env=clean)
    assert install.returncode == 0, install.stderr
    send = subprocess.run([str(bin_dir / "opentmcl"), "send", "--plain", "SAP 4, 0, 777", "GAP 4, 0", "--to",
                           "sim://TMCM-6212"],
                          capture_output=True, text=True, timeout=120, env=clean, cwd=tmp_path)
    assert send.returncode == 0 and send.stdout.split()[-1] == "777", send.stderr   # GAP 4 reads back SAP 4
    code = ("import importlib.util, opentmcl\n"
            "m = opentmcl.connect('sim://PD86-1180'); m.axes[0].set('MaxVelocity', 99); print(m.axes[0].get(4))\n"
            f"print([n for n in {HEAVY!r} if importlib.util.find_spec(n)])\n")
    host = subprocess.run([str(bin_dir / "python"), "-c", code], capture_output=True, text=True, timeout=120,
                          env=clean, cwd=tmp_path)
    assert host.stdout.split() == ["99", "[]"], host.stderr
    dash = subprocess.run([str(bin_dir / "opentmcl"), "dashboard", "--to", "sim://TMCM-6212"], capture_output=True,
                          text=True, timeout=120, env=clean, cwd=tmp_path)
    assert dash.returncode == 2 and "pip install 'opentmcl[web]'" in dash.stderr, dash.stderr
