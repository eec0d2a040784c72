"""The optional compiled accelerator of the request path (issue 16 item 5; docs/performance.md
"Compiled accelerator").

`opentmcl._accel` (src/opentmcl/_accel.c, built by setup.py when a C compiler is there) holds
compiled twins of four pieces of the pure-Python request path, which stays the reference:

- `VirtualModule.handle` (firmware/vm.py): `install(vm)` makes `vm.handle` an `_accel.Handle`;
- `dispatch._packed` (firmware/dispatch.py): `packed(head, read, reply)`, the reply of a pre-bound read;
- `SixPointRampEngine.position` / `.position_reached` (motion/sixpoint.py), the reads of GAP 1
  and GAP 8: `sixpoint_read(engine, attribute, fallback)`;
- the loop of `VirtualModule._sync_engines` (firmware/vm.py): `engine_sync(SixPointRampEngine)`.

`active()` is False without the compiled module or with the environment variable
`OPENTMCL_PURE=1`, and inside `with pure():` (tests, benchmarks). The firmware asks it once per
module, when it builds one (`install`); the module keeps that path (`enabled(vm)`), also for the
reads it binds later.

This module is in the lowest layer: it imports nothing of the package.
"""
from __future__ import annotations

import importlib
import os
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from types import ModuleType
from typing import Any

ENV = "OPENTMCL_PURE"


def _load() -> ModuleType | None:
    try:
        return importlib.import_module("opentmcl._accel")
    except ImportError:
        return None


compiled: ModuleType | None = _load()
"""`opentmcl._accel`, or None when it was not built."""

_forced_pure = 0  # depth of `pure()` blocks


def active() -> bool:
    """Whether new modules and newly bound reads use the compiled path."""
    return compiled is not None and not _forced_pure and os.environ.get(ENV, "") in ("", "0")


@contextmanager
def pure() -> Iterator[None]:
    """Modules built and reads bound inside the block take the pure-Python path (tests, benchmarks)."""
    global _forced_pure
    _forced_pure += 1
    try:
        yield
    finally:
        _forced_pure -= 1


def install(vm: Any, base: Any) -> None:
    """Choose the path of a new module: when `active()`, its pre-bound reads will be compiled
    (`enabled(vm)`) and `vm.handle` becomes the compiled handle (an instance attribute) unless
    `vm`'s class overrides `base.handle` (a subclass keeps its own). The compiled handle looks up
    `type(vm).handle` on every call, so a method patched onto the class later, or a new
    `vm.__class__`, is called as on the pure path; `copy.deepcopy` and pickle rebuild it on the copy."""
    on = active()
    vm._accel = on
    if on and _own_handle(type(vm), base):
        assert compiled is not None
        vm.handle = compiled.Handle(vm)


def _own_handle(cls: type, base: Any) -> bool:
    """`cls.handle` is `base`'s own method: not overridden, nor patched onto the class (a test's
    wrapper), which the compiled handle would bypass."""
    method = getattr(cls, "handle", None)
    return (method is base.handle and getattr(method, "__qualname__", "") == f"{base.__qualname__}.handle"
            and not hasattr(method, "__wrapped__"))


def enabled(vm: Any) -> bool:
    """Whether `vm` was built on the compiled path (`install`): a module keeps its path."""
    return getattr(vm, "_accel", False) is True


def packed(head: bytes, read: Callable[[], Any], reply: Callable[[Any], bytes]) -> Callable[[], bytes]:
    """The compiled `dispatch._packed(head, read)` (call only when `active()`); `reply(value)` is
    the Python reply it hands a value that is not an int (dispatch.reply_bytes behind `head`)."""
    assert compiled is not None
    return compiled.packed(head, read, reply)


def engine_sync(cls: type) -> Callable[[list[Any], int], None] | None:
    """The compiled loop of `VirtualModule._sync_engines` (`for e in engines: if e.now < now:
    e.advance(now)`), which advances engines of exactly `cls` (the six-point engine) without calling
    `advance` where that would only set `now`; None without the compiled module. Use it only for a
    module that is `enabled`."""
    return None if compiled is None else compiled.EngineSync(cls)


_SIXPOINT_READS = {"position": 0, "position_reached": 1}


def sixpoint_read(engine: object, attribute: str, fallback: Callable[[], Any]) -> Callable[[], Any]:
    """The compiled read of a `SixPointRampEngine`'s `position` or `position_reached` (the engine's
    class must be exactly that one); `fallback` (the property's read) answers every other
    attribute and the states the C code leaves to Python."""
    which = _SIXPOINT_READS.get(attribute)
    if compiled is None or which is None or not compiled.HAVE_INT128:
        return fallback
    return compiled.sixpoint_read(engine, which, fallback)


__all__ = ["ENV", "active", "compiled", "enabled", "engine_sync", "install", "packed", "pure", "sixpoint_read"]
