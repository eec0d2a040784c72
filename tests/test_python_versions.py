"""Every Python version the package claims resolves and installs (issue 32 item 1).

Issue 32: "`requires-python = ">=3.10"` and a 3.10 classifier, but the `test` extra needs
`httpx2>=2.16`, which requires Python 3.11 or later ... Decide: support 3.10 for real, tested in
CI, or claim 3.11+. The test extra also needs a starlette whose TestClient knows httpx2 (1.2 or
later)". Deliver: "install the package in fresh virtual environments, and run a `pip install
--dry-run` resolution for each claimed Python version that is installable here".

The claimed versions are the `Programming Language :: Python :: 3.N` classifiers. For each, this
machine's interpreter (pyenv's) resolves `opentmcl[test]` from the built sdist with pip's own
configuration (PyPI and the local indexes of pip.conf; no index is given here): a resolution that
cannot reach a package fails, it is not skipped. A claimed version without an interpreter here
fails too. The resolutions and the installs run side by side in threads, each a process of its
own, so the module costs about as long as the slowest of them. The long check, the README's first
command with all dependencies on every claimed version, is marked `slow`.
"""
from __future__ import annotations

import json
import site
import subprocess
import sys
from collections.abc import Iterator
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass
from importlib import metadata
from pathlib import Path

import pytest
from packaging.requirements import Requirement
from packaging.specifiers import SpecifierSet

from tests.distribution import PROJECT, ROOT, claimed_versions, clean_env, interpreter, snapshot

CLAIMED = claimed_versions()
BELOW = (CLAIMED[0][0], CLAIMED[0][1] - 1)
"""The newest version below the claimed ones (3.10): pip must refuse the package there."""
HERE = sys.version_info[:2]
TIMEOUT = 900  # seconds for one pip run: a bound against a hang, not a speed limit
OTHERS = [v for v in CLAIMED if v != HERE]


def label(version: tuple[int, int]) -> str:
    return f"{version[0]}.{version[1]}"


def run(*argv: str | Path, cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run([str(a) for a in argv], capture_output=True, text=True, timeout=TIMEOUT, cwd=cwd,
                          env=clean_env())


def resolve(python: str, sdist: Path, report: Path, extra: str = "[test]") -> subprocess.CompletedProcess[str]:
    """`pip install --dry-run` of `opentmcl[test]` from the sdist, as if nothing were installed."""
    return run(python, "-m", "pip", "install", "--dry-run", "--quiet", "--ignore-installed", "--report", report,
               f"opentmcl{extra} @ {sdist.as_uri()}")


def install_no_deps(python: str, sdist: Path, where: Path) -> subprocess.CompletedProcess[str]:
    """A fresh virtual environment made by `python`, the package built from the sdist and installed
    by that Python's pip without dependencies; then its entry point sends two instructions to a
    virtual module (the core needs none of the dependencies)."""
    for step in ([python, "-m", "venv", "--without-pip", where],
                 [python, "-m", "pip", "--python", where / "bin" / "python", "install", "--quiet", "--no-deps", sdist]):
        done = run(*step)
        if done.returncode != 0:
            return done
    return run(where / "bin" / "opentmcl", "send", "--plain", "SAP 4, 0, 777", "GAP 4, 0", "--to", "sim://TMCM-6212",
               cwd=where)


@dataclass
class Jobs:
    base: Path
    started: dict[str, Future[subprocess.CompletedProcess[str]]]

    def result(self, key: str) -> subprocess.CompletedProcess[str]:
        assert key in self.started, f"{key}: no such Python here (PATH, pyenv): install it or drop its classifier"
        return self.started[key].result()

    def report(self, version: tuple[int, int]) -> dict[str, str]:
        """name -> version of what the resolution on `version` would install."""
        doc = json.loads((self.base / f"{label(version)}.json").read_text(encoding="utf-8"))
        return {i["metadata"]["name"].lower(): i["metadata"]["version"] for i in doc["install"]}


@pytest.fixture(scope="module")
def jobs(sdist, tmp_path_factory) -> Iterator[Jobs]:
    """Every resolution, and the installs on the claimed versions other than this one, started at
    once; each test waits for its own."""
    base = tmp_path_factory.mktemp("versions")
    pool = ThreadPoolExecutor(max_workers=3)
    started: dict[str, Future[subprocess.CompletedProcess[str]]] = {}
    for version in [*CLAIMED, BELOW]:
        python = interpreter(version)
        if python is None:
            continue
        started[f"resolve {label(version)}"] = pool.submit(resolve, python, sdist.path, base / f"{label(version)}.json",
                                                           "[test]" if version in CLAIMED else "")
        if version in OTHERS:
            started[f"install {label(version)}"] = pool.submit(install_no_deps, python, sdist.path,
                                                               base / f"venv-{label(version)}")
    yield Jobs(base, started)
    pool.shutdown(wait=True)


def test_requires_python_admits_the_claimed_versions_and_not_the_one_below():
    """requires-python's floor is the lowest classifier, the classifiers have no gap, CI's Python
    is among them, and 3.10 -- whose pip finds no httpx2 >= 2.16 -- is outside."""
    spec = SpecifierSet(PROJECT["requires-python"])
    assert CLAIMED[0] == (3, 11) and BELOW == (3, 10)
    assert [m for _, m in CLAIMED] == list(range(CLAIMED[0][1], CLAIMED[-1][1] + 1))
    assert all(f"{label(v)}.0" in spec for v in CLAIMED)
    assert f"{label(BELOW)}.99" not in spec
    assert HERE in CLAIMED


def test_the_readme_states_the_claimed_versions_and_the_one_ci_runs_on():
    """Issue 32: "The README states the Python versions that CI tests". CI runs `.ci/run`, whose
    `python3 -m venv` takes the `python3` of PATH; the README names its version and the claimed ones."""
    readme = " ".join((ROOT / "README.md").read_text(encoding="utf-8").split())
    python3 = run("python3", "-c", "import sys; print(*sys.version_info[:2], sep='.')").stdout.strip()
    assert "python3 -m venv .venv" in (ROOT / ".ci" / "run").read_text(encoding="utf-8")
    assert f"CI runs the second command on Python {python3}." in readme
    claimed = [label(v) for v in CLAIMED]
    listed = ", ".join(claimed[:-1]) + f" and {claimed[-1]}"
    assert f"On {listed}, the versions the package claims," in readme
    assert f"with Python {', '.join(claimed[:-1])} or {claimed[-1]}, from the repository root" in readme


def test_this_environment_meets_the_test_extra_with_an_httpx2_testclient():
    """Every requirement of the test extra is met where the suite runs, and starlette's TestClient
    (1.2 or later, as the extra says) is built on httpx2."""
    import starlette.testclient

    extra = [Requirement(t) for t in PROJECT["optional-dependencies"]["test"]]
    assert Requirement("starlette>=1.2") in extra
    unmet = [f"{r} (installed {metadata.version(r.name)})" for r in extra
             if r.name != "opentmcl" and not r.specifier.contains(metadata.version(r.name), prereleases=True)]
    assert unmet == []
    assert starlette.testclient.httpx.__name__ == "httpx2"


@pytest.mark.parametrize("version", CLAIMED, ids=label)
def test_the_test_extra_resolves_on_every_claimed_python(jobs, version):
    """`pip install --dry-run 'opentmcl[test]'` succeeds on this machine's Python of each claimed
    version, with a starlette of 1.2 or later and httpx2 among what it would install."""
    done = jobs.result(f"resolve {label(version)}")
    assert done.returncode == 0, done.stderr[-4000:]
    picked = jobs.report(version)
    assert picked["opentmcl"] == PROJECT["version"]
    assert SpecifierSet(">=1.2").contains(picked["starlette"]) and "httpx2" in picked


def test_pip_refuses_the_package_below_the_claimed_versions(jobs):
    """The first version that is not claimed (3.10): pip refuses the package itself ("requires a
    different Python"), where it used to fail on the test extra's httpx2 (issue 32)."""
    if f"resolve {label(BELOW)}" not in jobs.started:
        pytest.skip(f"no Python {label(BELOW)} on this machine to try the refusal with")
    done = jobs.result(f"resolve {label(BELOW)}")
    assert done.returncode != 0
    assert "requires a different Python" in done.stderr and ">=3.11" in done.stderr, done.stderr[-2000:]


@pytest.mark.parametrize("version", OTHERS, ids=label)
def test_the_package_installs_in_a_fresh_venv_of_every_other_claimed_python(jobs, version):
    """Built from the sdist by that Python (the accelerator compiled for it where a compiler is),
    installed into a new virtual environment: `opentmcl send` runs (the last reply is GAP 4 = 777)."""
    done = jobs.result(f"install {label(version)}")
    assert done.returncode == 0, done.stderr[-4000:]
    assert done.stdout.splitlines()[-1] == "777", done.stdout


def test_the_wheel_installs_in_a_fresh_venv_of_this_python(wheel, tmp_path):
    """The wheel built from the sdist, installed without dependencies into a new virtual
    environment that borrows the dependencies of the running one (a .pth file): the README's first
    command's `opentmcl demo` and a `send` run from the new environment's own copy."""
    where = tmp_path / "venv"
    assert run(sys.executable, "-m", "venv", "--without-pip", where).returncode == 0
    done = run(sys.executable, "-m", "pip", "--python", where / "bin" / "python", "install", "--quiet", "--no-deps",
               "--no-index", wheel.path)
    assert done.returncode == 0, done.stderr[-4000:]
    (own,) = where.glob("lib/python*/site-packages")
    (own / "borrowed-dependencies.pth").write_text("\n".join(site.getsitepackages()) + "\n")
    where_is = run(where / "bin" / "python", "-c", "import opentmcl, serial, can, yaml; print(opentmcl.__file__)",
                   cwd=tmp_path)
    assert where_is.stdout.strip() == str(own / "opentmcl" / "__init__.py"), where_is.stderr
    demo = run(where / "bin" / "opentmcl", "demo", cwd=tmp_path)
    assert demo.returncode == 0 and "position reached (AP8)" in demo.stdout, demo.stderr
    send = run(where / "bin" / "opentmcl", "send", "GAP 4, 0", "--to", "sim://PD86-1180", cwd=tmp_path)
    assert send.returncode == 0 and send.stdout.startswith("status 100"), send.stdout + send.stderr


@pytest.mark.slow
@pytest.mark.parametrize("version", CLAIMED, ids=label)
def test_the_readmes_first_command_on_every_claimed_python(version, tmp_path):
    """The README's first command, with every dependency from the indexes, in a fresh clone's
    files: `python3 -m venv .venv && .venv/bin/pip install -q -e '.[all]' && .venv/bin/opentmcl demo`
    with python3 being each claimed version (minutes each)."""
    python = interpreter(version)
    assert python is not None, f"no Python {label(version)} here"
    tree = snapshot(tmp_path / "clone")
    for step in ([python, "-m", "venv", ".venv"], [".venv/bin/pip", "install", "-q", "-e", ".[all]"],
                 [".venv/bin/opentmcl", "demo"]):
        done = run(*step, cwd=tree)
        assert done.returncode == 0, f"{step}: {done.stderr[-4000:]}"
    assert "position reached (AP8)" in done.stdout
