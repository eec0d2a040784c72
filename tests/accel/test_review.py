"""Findings of the round-23 review of the compiled accelerator (src/opentmcl/_accel.c), each pinned
against the pure-Python reference: what the pure module does, the compiled one does too.

- copy.deepcopy and pickle of a module: the pure module has no instance attribute `handle`; the
  compiled one holds an `_accel.Handle`, which must be rebuilt on the copy (`Handle.__reduce__`).
- a `handle` patched onto the class (or `vm.__class__` reassigned) after the module was built:
  the pure module calls the class's method; the compiled handle checks it on every call.
- an object the cyclic GC has cleared (tp_clear: NULL fields) raises ReferenceError when called
  instead of dereferencing NULL.
- the C source compiles without warnings under `-Wall -Wextra`.
"""
from __future__ import annotations

import copy
import os
import pickle
import shlex
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

import pytest

from opentmcl import VirtualModule, accel
from opentmcl.protocol.frame import Request

from .conftest import pair

# built and selected: under OPENTMCL_PURE=1 both modules are pure and there is nothing to compare
needs_compiled = pytest.mark.skipif(not accel.active(), reason="the compiled path is not active")

SOURCE = Path(accel.__file__).with_name("_accel.c")
GAP1 = Request(1, 6, 1, 0, 0).encode()  # GAP 1, motor 0 (TMCM-6212 manual 3.6.6)
SAP1 = Request(1, 5, 1, 0, 1234).encode()  # SAP 1, motor 0: the actual position


def _fresh_copies(vm: VirtualModule):
    return [("deepcopy", copy.deepcopy(vm)), ("pickle", pickle.loads(pickle.dumps(vm)))]


@needs_compiled
def test_a_compiled_module_is_copied_and_pickled_as_the_pure_one():
    ref, fast = pair("TMCM-6212", address=1)
    for vm in (ref, fast):
        vm.advance(0.01)
    for (how, a), (_, b) in zip(_fresh_copies(ref), _fresh_copies(fast), strict=True):
        assert accel.enabled(b) and not accel.enabled(a), how
        handle = b.__dict__["handle"]
        assert type(handle) is accel.compiled.Handle and handle.__self__ is b, how  # type: ignore[union-attr]
        for frame in (SAP1, GAP1, GAP1):  # the read is bound on the copy, to the copy's axis
            assert a.handle(frame) == b.handle(frame), (how, frame)
        assert b.axes[0].engine.position == 1234
    assert fast.axes[0].engine.position == 0 and fast.handle(GAP1) == ref.handle(GAP1)


@needs_compiled
def test_a_handle_patched_onto_the_class_after_the_module_was_built_is_called(monkeypatch):
    ref, fast = pair("TMCM-6212", address=1)
    calls = []
    original = VirtualModule.handle

    def spy(self, frame, *, interface="serial"):
        calls.append((self, bytes(frame), interface))
        return original(self, frame, interface=interface)

    for vm in (ref, fast):
        vm.handle(GAP1)  # bound: the compiled fast path would answer it
    monkeypatch.setattr(VirtualModule, "handle", spy)
    assert fast.handle(GAP1, interface="can") == ref.handle(GAP1, interface="can")
    assert [c[0] for c in calls] == [fast, ref] and calls[0][1:] == (GAP1, "can")
    monkeypatch.undo()
    calls.clear()
    assert fast.handle(GAP1) == ref.handle(GAP1) and calls == []  # the compiled path again


@needs_compiled
def test_a_module_whose_class_is_reassigned_takes_the_new_class_handle():
    class Logged(VirtualModule):
        seen: list[bytes] = []

        def handle(self, frame, *, interface="serial"):
            self.seen.append(bytes(frame))
            return super().handle(frame, interface=interface)

    class Plain(VirtualModule):  # no override: stays on the compiled path
        pass

    ref, fast = pair("TMCM-6212", address=1)
    fast.handle(GAP1)
    fast.__class__ = Logged
    with accel.pure():
        want = ref.handle(GAP1)
    assert fast.handle(GAP1) == want and Logged.seen == [GAP1]
    fast.__class__ = Plain
    assert fast.handle(GAP1) == want and Logged.seen == [GAP1]


def _compiler() -> str | None:
    cc = sysconfig.get_config_var("CC")
    return shutil.which(shlex.split(cc)[0]) if cc else None


@pytest.mark.skipif(_compiler() is None, reason="no C compiler")
def test_the_extension_compiles_without_warnings_under_wall_wextra(tmp_path):
    include = sysconfig.get_paths()["include"]
    if not (Path(include) / "Python.h").exists():
        pytest.skip("no Python headers")
    cc = shlex.split(sysconfig.get_config_var("CC"))
    out = subprocess.run([*cc, "-fsyntax-only", "-Wall", "-Wextra", "-Werror", f"-I{include}", str(SOURCE)],
                         capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert out.returncode == 0, out.stderr


_CLEARED = """
import ctypes
from opentmcl import VirtualModule, accel
C = accel.compiled
get_slot = ctypes.pythonapi.PyType_GetSlot
get_slot.restype, get_slot.argtypes = ctypes.c_void_p, [ctypes.py_object, ctypes.c_int]
def clear(obj):  # what the cyclic GC does to an object of a garbage cycle: tp_clear (slot 51)
    assert ctypes.PYFUNCTYPE(ctypes.c_int, ctypes.py_object)(get_slot(type(obj), 51))(obj) == 0
vm = VirtualModule("TMCM-6212", address=1)
inner = C.sixpoint_read(vm.axes[0].engine, 1, lambda: 0)
objs = [C.Handle(vm), C.packed(b"abcd", lambda: 1, lambda v: b""),
        C.sixpoint_read(vm.axes[0].engine, 0, lambda: 0), inner]
outer = C.packed(b"abcd", inner, lambda v: b"")
for o in objs:
    clear(o)
out = []
for o in objs + [outer]:
    try:
        o(bytes(9)) if type(o) is C.Handle else o()
    except ReferenceError:
        out.append("ReferenceError")
print(*out, repr(objs[0]).startswith("<compiled handle of"))
"""


@needs_compiled
def test_an_object_the_gc_has_cleared_raises_instead_of_crashing():
    """tp_clear leaves NULL fields; a call reaching such an object (a finalizer of its cycle)
    raised nothing before: it dereferenced NULL (segmentation fault)."""
    out = subprocess.run([sys.executable, "-c", _CLEARED], capture_output=True, text=True, timeout=60,
                         env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)})
    assert out.returncode == 0, (out.returncode, out.stderr[-2000:])
    assert out.stdout.split() == ["ReferenceError"] * 5 + ["True"]
