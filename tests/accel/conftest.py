"""Shared helpers of the accelerator tests: a pure and an accelerated module side by side."""
from __future__ import annotations

import pytest

from opentmcl import VirtualModule, accel

# Not built: test_build.py fails when a C compiler is there. OPENTMCL_PURE=1: the run asked for
# the pure-Python path only (README "For developers"), so there is no compiled path to compare.
needs_compiled = pytest.mark.skipif(not accel.active(), reason="no compiled request path in this run "
                                    "(opentmcl._accel not built, or OPENTMCL_PURE=1)")


def pair(name: str, **kwargs) -> tuple[VirtualModule, VirtualModule]:
    """(pure module, accelerated module) of the same profile and arguments."""
    with accel.pure():
        ref = VirtualModule(name, **kwargs)
    fast = VirtualModule(name, **kwargs)
    assert "handle" not in ref.__dict__ and not accel.enabled(ref)
    if accel.active():
        assert type(fast.handle) is accel.compiled.Handle  # type: ignore[union-attr]
    return ref, fast


def answer(vm: VirtualModule, frame, **kwargs):
    """The reply of `vm.handle`, or the exception's type and message."""
    try:
        return vm.handle(frame, **kwargs)
    except Exception as exc:  # noqa: BLE001 - compared between the two paths
        return type(exc), str(exc)
