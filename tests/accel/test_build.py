"""The accelerator is built wherever it can be, and the pure-Python path stays tested.

setup.py declares `opentmcl._accel` as an optional extension: without a C compiler the install
is the pure package (README's two commands keep working). With one, `pip install -e '.[test]'`
builds it in place, and a suite that then runs without it would test the pure path only: that
fails here. `OPENTMCL_PURE=1` selects the pure path at run time; the firmware tests run once more
that way in a subprocess (the mutation runs use it too, tests/mutation_plugin.py).
"""
from __future__ import annotations

import os
import shlex
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

import pytest

from opentmcl import accel

ROOT = Path(__file__).resolve().parents[2]


def c_compiler() -> str | None:
    """The C compiler this Python builds extensions with, if it is installed."""
    cc = sysconfig.get_config_var("CC")
    if not cc:
        return None
    return shutil.which(shlex.split(cc)[0])


def env(**extra: str) -> dict[str, str]:
    out = dict(os.environ, **extra)
    out["PYTHONPATH"] = os.pathsep.join(p for p in (str(ROOT / "src"), os.environ.get("PYTHONPATH")) if p)
    return out


def test_a_machine_with_a_c_compiler_has_the_compiled_module():
    compiler = c_compiler()
    if compiler is None:
        pytest.skip("no C compiler: the pure-Python package is the whole install")
    assert accel.compiled is not None, (
        f"a C compiler is there ({compiler}) but opentmcl._accel is not built: "
        "run `pip install -e '.[test]'` again (it builds src/opentmcl/_accel.c in place) and read its "
        "output for the build error")


def test_opentmcl_pure_selects_the_python_path():
    code = ("from opentmcl import VirtualModule, accel\n"
            "import inspect\n"
            "vm = VirtualModule('TMCM-6212')\n"
            "vm.handle(bytes.fromhex('010601000000000008'))  # GAP 1, 0 (manual 3.6.6), bound\n"
            "print(accel.active(), inspect.ismethod(vm.handle), accel.enabled(vm),\n"
            "      vm.request(6, 1, 0).value)\n")
    out = subprocess.run([sys.executable, "-c", code], env=env(OPENTMCL_PURE="1"), capture_output=True,
                         text=True, timeout=60, check=True).stdout.split()
    assert out == ["False", "True", "False", "0"]


def test_the_firmware_tests_pass_on_the_pure_path():
    """tests/firmware (about 10 s) with OPENTMCL_PURE=1: every module there is the reference."""
    done = subprocess.run([sys.executable, "-m", "pytest", "-q", "-x", "-p", "no:cacheprovider", "tests/firmware"],
                          cwd=ROOT, env=env(OPENTMCL_PURE="1"), capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-2000:]
    assert " passed" in done.stdout
