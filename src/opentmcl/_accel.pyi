"""Stub of the compiled accelerator (src/opentmcl/_accel.c; opentmcl/accel.py uses it)."""
from collections.abc import Callable
from typing import Any

HAVE_INT128: int
PSCALE: int
HEARTBEAT_OF: dict[str, str]

class Handle:
    """`VirtualModule.handle` in C, bound to one module."""

    __self__: Any
    __wrapped__: Callable[..., bytes]
    def __init__(self, vm: Any) -> None: ...
    def __call__(self, frame: bytes | bytearray | memoryview, *, interface: str = "serial") -> bytes: ...

class Packed:
    head: bytes
    read: Callable[[], Any]
    def __call__(self) -> bytes: ...

class SixPointRead:
    engine: Any
    fallback: Callable[[], Any]
    which: int
    def __call__(self) -> Any: ...

def packed(head: bytes, read: Callable[[], Any], slow: Callable[[Any], bytes], /) -> Packed: ...
def sixpoint_read(engine: Any, which: int, fallback: Callable[[], Any], /) -> SixPointRead: ...

class EngineSync:
    """`VirtualModule._sync_engines`' loop in C; engines of exactly `cls` are advanced inline."""

    cls: type
    def __init__(self, cls: type) -> None: ...
    def __call__(self, engines: list[Any], now: int, /) -> None: ...
